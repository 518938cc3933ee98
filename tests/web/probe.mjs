// The browser test's checks, run inside the viewer page (viewer.mjs imports it for ?probe=):
// loads the page's file=... with the viewer, checks every frame while it streams, captures the
// final frame, then loads each bad=... file expecting a clear error on the page, and posts what
// it saw to /report for tests/web/browser_test.mjs to judge.

const frame = () => new Promise((done) => requestAnimationFrame(() => done()));

// Every mesh's drawn index buffer: indices below the drawn resolution, which is decoded.
function checkFrame(object, record) {
  const entry = { bytes: object.bytesReceived, triangles: object.drawnTriangles, vertices: object.drawnVertices, problems: [] };
  object.slots.forEach((slot, m) => {
    const { indices, vertices, decoded } = object.drawnIndices(m);
    let max = -1;
    for (let i = 0; i < indices.length; ++i) if (indices[i] > max) max = indices[i];
    if (vertices > decoded) entry.problems.push(`mesh ${m} draws ${vertices} vertices of ${decoded} decoded`);
    if (max >= vertices) entry.problems.push(`mesh ${m} index ${max} past its ${vertices} vertices`);
    if (indices.length % 3) entry.problems.push(`mesh ${m} has ${indices.length} indices, not whole triangles`);
  });
  record.frames.push(entry);
}

export async function attach(viewer, params) {
  const report = { cases: [], bad: [], console: [] };
  const consoleError = console.error.bind(console);
  console.error = (...args) => {
    report.console.push(args.map(String).join(' '));
    consoleError(...args);
  };
  window.addEventListener('error', (event) => report.console.push(`uncaught: ${event.message}`));
  window.addEventListener('unhandledrejection', (event) => report.console.push(`unhandled rejection: ${event.reason && event.reason.message}`));
  try {
    for (const url of params.getAll('file')) {
      const record = { url, frames: [] };
      const started = performance.now();
      const object = await viewer.load(url);
      record.firstFrameBytes = object.firstFrameBytes;
      record.firstFrameMs = performance.now() - started;
      checkFrame(object, record);
      object.addEventListener('refine', () => checkFrame(object, record));
      await object.loaded;
      record.loadMs = performance.now() - started;
      record.fileBytes = object.fileBytes;
      record.bytes = object.bytesReceived;
      record.triangles = object.drawnTriangles;
      record.fullTriangles = object.slots.reduce((sum, s) => sum + s.totalTriangles, 0);
      report.cases.push(record);
    }
    for (let i = 0; i < 3; ++i) await frame();
    report.image = viewer.canvas.toDataURL('image/png');
    for (const url of params.getAll('bad')) {
      let rejected = null;
      try {
        const object = await viewer.load(url);
        await object.loaded;
      } catch (error) {
        rejected = error.message;
      }
      await frame();
      report.bad.push({ url, rejected, shown: document.getElementById('error').textContent });
    }
  } catch (error) {
    report.failure = `${error.message}\n${error.stack}`;
  }
  report.stillRendering = await Promise.race([frame().then(() => true), new Promise((done) => setTimeout(() => done(false), 2000))]);
  await fetch('/report', { method: 'POST', body: JSON.stringify(report) });
}
