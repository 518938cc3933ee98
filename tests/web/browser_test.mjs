// The browser test (ctest browser_viewer): streams .tom files into the viewer (samples/web/) in
// Debian's chromium, headless with WebGL on SwiftShader, from the project's Range-honouring
// server throttled so that the stream refines over many frames, and judges what the page saw
// (tests/web/probe.mjs posts it):
//   - the first frame is drawn after at most 5% of the bunny's bytes;
//   - every frame is a valid mesh: no index past the vertices drawn, none drawn undecoded;
//   - the final frame matches tomview's image of the full-detail ordinary .tom (SSIM >= 0.98,
//     same camera, tomview's lighting), for the bunny, a multi-material scene and a textured box
//     (whose first frame comes before its image, which the loader attaches when it arrives);
//   - automatic mode fetches a few chunks for a far camera, everything near, within the link budget;
//   - a fixed resolution fetches only a prefix and draws the level extraction gives;
//   - a truncated, a corrupted and a missing file each give an error on the page naming the
//     file and the problem, and the tab keeps rendering; no console error anywhere.
//
//   node browser_test.mjs --tools BUILD/tools --tomview BUILD/.../tomview --site SITE --data DATA --work DIR
import { spawn, spawnSync } from 'node:child_process';
import { copyFileSync, existsSync, mkdirSync, readFileSync, rmSync, writeFileSync } from 'node:fs';
import path from 'node:path';
import { fileURLToPath } from 'node:url';

const here = path.dirname(fileURLToPath(import.meta.url));
const root = path.resolve(here, '../..');
const args = {};
for (let i = 2; i < process.argv.length; i += 2) args[process.argv[i].replace(/^--/, '')] = path.resolve(process.argv[i + 1]);
const work = args.work;
const failures = [];
const check = (ok, what) => {
  console.log(`${ok ? 'ok  ' : 'FAIL'} ${what}`);
  if (!ok) failures.push(what);
};

function run(command, argv) {
  const r = spawnSync(command, argv, { encoding: 'utf8' });
  if (r.status !== 0) throw new Error(`${command} ${argv.join(' ')} failed:\n${r.stdout}${r.stderr}`);
  return r.stdout;
}

// The inputs: bunny00 and a multi-material scene, each as an ordinary and a streamed .tom,
// and the bad files cut or flipped from the streamed bunny.
function prepare() {
  rmSync(work, { recursive: true, force: true });
  for (const d of ['plain', 'stream', 'bad', 'quality']) mkdirSync(path.join(work, d), { recursive: true });
  const inputs = {
    bunny00: path.join(args.data, 'meshes/bunny00.off'),
    '2CylinderEngine': path.join(args.data, 'assimp/glTF2/2CylinderEngine-glTF-Binary/2CylinderEngine.glb'),
    BoxTextured: path.join(args.data, 'assimp/glTF2/BoxTextured-glTF-Binary/BoxTextured.glb'),
  };
  for (const input of Object.values(inputs)) {
    run(path.join(args.tools, 'tombuild'), [input, '-o', path.join(work, 'plain'), '-q']);
    run(path.join(args.tools, 'tombuild'), [input, '--stream', '-o', path.join(work, 'stream'), '-q']);
  }
  const stream = readFileSync(path.join(work, 'stream/bunny00.tom'));
  writeFileSync(path.join(work, 'bad/bunny-truncated.tom'), stream.subarray(0, Math.floor(stream.length * 0.4)));
  const corrupt = Buffer.from(stream);
  corrupt[Math.floor(corrupt.length * 0.6)] ^= 0x5a;
  writeFileSync(path.join(work, 'bad/bunny-corrupt.tom'), corrupt);
  Object.keys(inputs).forEach((name, i) =>
    run(args.tomview, [path.join(work, 'plain', `${name}.tom`), '-o', path.join(work, 'quality', `reference-${i}.png`), '--width', '800', '--height', '600']));
}

async function startServer() {
  const report = path.join(work, 'report.json');
  const server = spawn(process.execPath, [path.join(root, 'samples/web/server.mjs'), '--port', '0', '--throttle', '400000', '--piece', '4096', '--mount', `/data=${work}`,
    '--mount', `/tests=${here}`, '--report', report, args.site], { stdio: ['ignore', 'pipe', 'inherit'] });
  const port = await new Promise((resolve, reject) => {
    let out = '';
    server.stdout.on('data', (d) => {
      out += d;
      const m = /http:\/\/[\d.]+:(\d+)\//.exec(out);
      if (m) resolve(Number(m[1]));
    });
    server.on('exit', (code) => reject(new Error(`the server exited with ${code}`)));
  });
  return { server, port, report };
}

// One page load in headless chromium; resolves with the probe's report.
async function page(server, query, timeoutSeconds = 90) {
  rmSync(server.report, { force: true });
  const profile = path.join(work, `profile-${Date.now()}`);
  const url = `http://127.0.0.1:${server.port}/index.html?shading=reference&size=800x600&probe=/tests/probe.mjs&${query}`;
  const chrome = spawn('chromium', ['--headless=new', '--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--window-size=800,600',
    '--no-first-run', '--disable-extensions', `--user-data-dir=${profile}`, url], { stdio: ['ignore', 'ignore', 'pipe'], detached: true });
  let log = '';
  chrome.stderr.on('data', (d) => (log += d));
  try {
    for (let waited = 0; waited < timeoutSeconds * 10; ++waited) {
      if (existsSync(server.report)) {
        await new Promise((done) => setTimeout(done, 100)); // the whole body written
        return JSON.parse(readFileSync(server.report, 'utf8'));
      }
      if (chrome.exitCode !== null) throw new Error(`chromium exited (${chrome.exitCode}) before the page reported:\n${log}`);
      await new Promise((done) => setTimeout(done, 100));
    }
    throw new Error(`no report from ${url} within ${timeoutSeconds} s; chromium said:\n${log.slice(-3000)}`);
  } finally {
    // chromium and its helper processes: its own process group
    try {
      process.kill(-chrome.pid, 'SIGKILL');
    } catch {
      // already gone
    }
  }
}

function ssim(index, image) {
  writeFileSync(path.join(work, 'quality', `browser-${index}.png`), Buffer.from(image.split(',')[1], 'base64'));
  const lines = run('/usr/bin/python3', [path.join(root, 'scripts/image-quality.py'), path.join(work, 'quality')]).trim().split('\n').map((l) => JSON.parse(l));
  return lines.find((l) => l.frame === index).ssim;
}

function judgeStream(record, name, { firstShare }) {
  const bad = record.frames.filter((f) => f.problems.length);
  check(!bad.length, `${name}: ${record.frames.length} frames while streaming, each a valid mesh${bad.length ? ` (${bad[0].problems[0]} at ${bad[0].bytes} bytes)` : ''}`);
  check(record.frames.length >= 3, `${name}: refined in place over ${record.frames.length} frames`);
  const rising = record.frames.every((f, i) => i === 0 || f.triangles >= record.frames[i - 1].triangles);
  check(rising, `${name}: triangles drawn rise frame after frame`);
  const share = record.firstFrameBytes / record.fileBytes;
  if (firstShare) check(share <= firstShare, `${name}: first frame after ${record.firstFrameBytes} of ${record.fileBytes} bytes (${(100 * share).toFixed(1)}%, at most ${100 * firstShare}%)`);
  else console.log(`     ${name}: first frame after ${record.firstFrameBytes} of ${record.fileBytes} bytes (${(100 * share).toFixed(1)}%)`);
  check(record.bytes === record.fileBytes && record.triangles === record.fullTriangles, `${name}: all ${record.fileBytes} bytes in, ${record.triangles} of ${record.fullTriangles} triangles drawn`);
}

function judgePage(report, name) {
  check(!report.failure, `${name}: the page ran its checks${report.failure ? `: ${report.failure}` : ''}`);
  check(report.console.length === 0, `${name}: no console error${report.console.length ? `: ${report.console.join(' | ')}` : ''}`);
  check(report.stillRendering, `${name}: the tab still renders`);
}

async function main() {
  prepare();
  const server = await startServer();
  try {
    // bunny00 streamed in full, then the bad files
    const bad = ['bunny-truncated.tom', 'bunny-corrupt.tom', 'missing.tom'];
    const bunny = await page(server, `file=/data/stream/bunny00.tom&${bad.map((b) => `bad=/data/bad/${b}`).join('&')}`);
    judgePage(bunny, 'bunny00');
    judgeStream(bunny.cases[0], 'bunny00', { firstShare: 0.05 });
    const s0 = ssim(0, bunny.image);
    check(s0 >= 0.98, `bunny00: final frame against tomview's full detail, SSIM ${s0.toFixed(4)} (at least 0.98)`);
    const expected = [/ends after \d+ of its \d+ bytes/, /checksum mismatch/, /HTTP 404/];
    bunny.bad.forEach((b, i) =>
      check(b.rejected && b.rejected.includes(b.url.split('/').pop()) && expected[i].test(b.rejected) && b.shown.includes(b.rejected),
        `${b.url.split('/').pop()}: error on the page: ${b.rejected}`));

    // a multi-material scene
    const engine = await page(server, 'file=/data/stream/2CylinderEngine.tom');
    judgePage(engine, '2CylinderEngine');
    judgeStream(engine.cases[0], '2CylinderEngine', {});
    const s1 = ssim(1, engine.image);
    check(s1 >= 0.98, `2CylinderEngine: final frame against tomview's full detail, SSIM ${s1.toFixed(4)} (at least 0.98)`);

    // an ordinary .tom: drawn once its last byte is in, the same image as the stream's
    const plain = await page(server, 'file=/data/plain/bunny00.tom&auto=1');
    judgePage(plain, 'bunny00, ordinary file');
    check(plain.cases[0].triangles === 75408 && plain.cases[0].frames.every((f) => !f.problems.length),
      `bunny00, ordinary file: ${plain.cases[0].triangles} triangles drawn, every frame valid`);
    copyFileSync(path.join(work, 'quality', 'reference-0.png'), path.join(work, 'quality', 'reference-3.png'));
    const s3 = ssim(3, plain.image);
    check(s3 >= 0.98, `bunny00, ordinary file: final frame against tomview's, SSIM ${s3.toFixed(4)} (at least 0.98)`);

    // a textured asset: its embedded image decoded in the page and sampled as tomview samples it
    // (the image in the deferred block: the first frame before it, drawn untextured, then textured)
    const box = await page(server, 'file=/data/stream/BoxTextured.tom');
    judgePage(box, 'BoxTextured');
    const boxCase = box.cases[0] || {};
    check(boxCase.deferred && boxCase.deferred.endByte > boxCase.deferred.beginByte && boxCase.firstFrameBytes <= boxCase.deferred.beginByte,
      `BoxTextured: first frame after ${boxCase.firstFrameBytes} bytes, before its image (bytes ${boxCase.deferred && boxCase.deferred.beginByte} to ${boxCase.deferred && boxCase.deferred.endByte})`);
    const s2 = ssim(2, box.image);
    check(s2 >= 0.98, `BoxTextured: final frame against tomview's full detail, SSIM ${s2.toFixed(4)} (at least 0.98)`);

    // a fixed resolution: only a prefix is fetched (Range), and the level drawn is extraction's
    const tenth = await page(server, 'file=/data/stream/bunny00.tom&resolution=0.1');
    judgePage(tenth, 'bunny00 at 10%');
    const record = tenth.cases[0];
    const info = JSON.parse(run(path.join(args.tools, 'tominfo'), [path.join(work, 'stream/bunny00.tom'), '--json']));
    const chunks = info.stream.chunks;
    const need = chunks.find((c) => c.triangles >= Math.ceil(0.1 * chunks[chunks.length - 1].triangles)).end_byte;
    check(record.bytes >= need && record.bytes < Math.min(need + 65536, record.fileBytes / 2),
      `bunny00 at 10%: fetched ${record.bytes} bytes of ${record.fileBytes} (the level needs ${need})`);
    const obj = path.join(work, 'tenth.obj');
    run(path.join(args.tools, 'tomextract'), [path.join(work, 'plain/bunny00.tom'), '--fraction', '0.1', '-o', obj]);
    const faces = readFileSync(obj, 'utf8').split('\n').filter((l) => l.startsWith('f ')).length;
    check(record.triangles === faces, `bunny00 at 10%: ${record.triangles} triangles drawn, tomextract --fraction 0.1 gives ${faces}`);
    check(record.frames.every((f) => !f.problems.length), 'bunny00 at 10%: every frame a valid mesh');

    // automatic mode under a link budget of 60 kB/s: far away the first chunk, close every one;
    // the scheduler keeps to the budget (one second of credit and one run of chunks beyond it)
    // while the server could send the rest in under a second
    const budget = 60000;
    const auto = await page(server, `file=/data/stream/bunny00.tom&auto=1&budget=${budget}&scenario=automatic`);
    judgePage(auto, 'bunny00 automatic');
    const a = auto.cases[0].automatic;
    check(a.far.bytes < 0.1 * a.fileBytes, `bunny00 automatic, far: ${a.far.bytes} bytes fetched, ${a.far.triangles} triangles drawn`);
    check(a.near.bytes >= a.near.want && a.near.triangles > 4 * a.far.triangles && a.near.bytes === a.fileBytes,
      `bunny00 automatic, near: ${a.near.bytes} bytes fetched (its targets, ${a.near.targets} of ${a.near.totals} vertices, need ${a.near.want}), ${a.near.triangles} triangles drawn`);
    const seconds = (a.second.ms - a.far.ms) / 1000;
    const allowed = budget * (seconds + 1) + 64 * 1024;
    check(a.second.bytes - a.far.bytes <= allowed && a.second.bytes > a.far.bytes && a.second.bytes < a.fileBytes,
      `bunny00 automatic: ${a.second.bytes - a.far.bytes} bytes in the first ${seconds.toFixed(2)} s near (budget allows ${Math.round(allowed)})`);
    check(auto.cases[0].frames.every((f) => !f.problems.length), 'bunny00 automatic: every frame a valid mesh');
  } finally {
    server.server.kill();
  }
  if (failures.length) {
    console.log(`${failures.length} check(s) failed`);
    process.exit(1);
  }
  console.log('browser test passed');
}

main().catch((error) => {
  console.error(error.stack || String(error));
  process.exit(1);
});
