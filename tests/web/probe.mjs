// The browser test's checks, run inside the viewer page (viewer.mjs imports it for ?probe=):
// loads the page's file=... with the viewer, checks every frame while it streams, captures the
// final frame, then loads each bad=... file expecting a clear error on the page, and posts what
// it saw to /report for tests/web/browser_test.mjs to judge.

const frame = () => new Promise((done) => requestAnimationFrame(() => done()));
const sleep = (ms) => new Promise((done) => setTimeout(done, ms));

// ?scenario=automatic: automatic mode under the viewer's link budget, the camera far away, then
// close; what was fetched and drawn at each, and the bytes the first second close took.
async function automatic(viewer, object) {
  const centre = viewer.controls.target.clone();
  const framing = viewer.camera.position.clone();
  const place = (distance) => {
    viewer.camera.position.copy(centre).add(framing.clone().sub(centre).multiplyScalar(distance));
    viewer.camera.far = 4 * distance * framing.distanceTo(centre);
    viewer.camera.updateProjectionMatrix();
    viewer.camera.updateMatrixWorld();
  };
  const state = () => ({ bytes: object.bytesReceived, triangles: object.drawnTriangles, ms: performance.now() });
  place(200); // the bunny a few pixels tall
  await sleep(1500);
  const far = state();
  place(0.35); // the camera inside the bunny's bounding sphere: full detail wanted
  await sleep(1000);
  const second = state();
  // until what the near targets need is in
  for (let waited = 0; waited < 15000 && object.bytesReceived < object.wantEnd; waited += 100) await sleep(100);
  await sleep(300);
  return { far, second, near: { ...state(), want: object.wantEnd, targets: object.targets.slice(), totals: object.totals.map((t) => t.vertices) }, fileBytes: object.fileBytes };
}

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
      const directory = object.source && object.source.directory;
      if (directory) record.deferred = directory.deferred;
      record.firstFrameMs = performance.now() - started;
      checkFrame(object, record);
      object.addEventListener('refine', () => checkFrame(object, record));
      if (params.get('scenario') === 'automatic') record.automatic = await automatic(viewer, object);
      await object.loaded;
      await object.texturesLoaded();
      record.loadMs = performance.now() - started;
      record.fileBytes = object.fileBytes;
      record.bytes = object.bytesReceived;
      record.triangles = object.drawnTriangles;
      record.fullTriangles = object.totals.reduce((sum, t) => sum + t.triangles, 0);
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
