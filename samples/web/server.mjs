// A static HTTP server for the viewer that honours Range requests (one range: "bytes=a-b",
// "bytes=a-", "bytes=-n"), as a browser streaming a .tom needs. No dependency beyond node.
//
//   node server.mjs [--port 8080] [--host 127.0.0.1] [--throttle BYTES_PER_SECOND]
//                   [--piece BYTES] [--mount /prefix=DIR ...] DIR
//
// Serves DIR at /, and each mounted DIR at its prefix. --throttle sends .tom files at that rate (in
// pieces of --piece bytes, default 16 KiB), to watch a stream refine. POST /report stores the body in --report FILE and
// exits when --exit-on-report is given (the browser test's channel back from the page).
import { createReadStream, promises as fs, writeFileSync } from 'node:fs';
import http from 'node:http';
import path from 'node:path';

const types = {
  '.html': 'text/html; charset=utf-8',
  '.mjs': 'text/javascript',
  '.js': 'text/javascript',
  '.css': 'text/css',
  '.wasm': 'application/wasm',
  '.json': 'application/json',
  '.png': 'image/png',
  '.jpg': 'image/jpeg',
  '.tom': 'application/octet-stream',
  '.ts': 'text/plain',
};

function parseArguments(argv) {
  const options = { port: 8080, host: '127.0.0.1', throttle: 0, piece: 16384, mounts: [], root: null, report: null, exitOnReport: false };
  for (let i = 0; i < argv.length; ++i) {
    const a = argv[i];
    if (a === '--port') options.port = Number(argv[++i]);
    else if (a === '--host') options.host = argv[++i];
    else if (a === '--throttle') options.throttle = Number(argv[++i]);
    else if (a === '--piece') options.piece = Number(argv[++i]);
    else if (a === '--report') options.report = argv[++i];
    else if (a === '--exit-on-report') options.exitOnReport = true;
    else if (a === '--mount') {
      const [prefix, dir] = argv[++i].split('=');
      options.mounts.push([prefix.replace(/\/$/, '') + '/', path.resolve(dir)]);
    } else options.root = path.resolve(a);
  }
  if (!options.root) throw new Error('usage: node server.mjs [--port P] [--throttle B/s] [--mount /prefix=DIR] DIR');
  options.mounts.sort((a, b) => b[0].length - a[0].length);
  options.mounts.push(['/', options.root]);
  return options;
}

// The file a URL path names, never outside its mount.
function resolve(options, urlPath) {
  const decoded = decodeURIComponent(urlPath.split('?')[0]);
  for (const [prefix, dir] of options.mounts) {
    if (!decoded.startsWith(prefix)) continue;
    const file = path.resolve(dir, '.' + path.posix.normalize('/' + decoded.slice(prefix.length)));
    return file.startsWith(dir) ? file : null;
  }
  return null;
}

// [start, end] inclusive for a Range header over `size` bytes; null: the whole; 'bad': 416.
function range(header, size) {
  if (!header) return null;
  const m = /^bytes=(\d*)-(\d*)$/.exec(header.trim());
  if (!m || (m[1] === '' && m[2] === '')) return 'bad';
  let start, end;
  if (m[1] === '') {
    start = Math.max(0, size - Number(m[2]));
    end = size - 1;
  } else {
    start = Number(m[1]);
    end = m[2] === '' ? size - 1 : Math.min(Number(m[2]), size - 1);
  }
  return start > end || start >= size ? 'bad' : [start, end];
}

async function send(options, request, response) {
  if (request.method === 'POST' && request.url === '/report') {
    const body = [];
    for await (const piece of request) body.push(piece);
    if (options.report) writeFileSync(options.report, Buffer.concat(body));
    response.writeHead(204).end();
    if (options.exitOnReport) setTimeout(() => process.exit(0), 50);
    return;
  }
  let file = resolve(options, request.url);
  let stat = null;
  try {
    stat = file && (await fs.stat(file));
    if (stat && stat.isDirectory()) {
      file = path.join(file, 'index.html'); // a folder: its page
      stat = await fs.stat(file);
    }
  } catch {
    stat = null;
  }
  if (!stat || !stat.isFile()) {
    console.error(`404 ${request.url}`);
    response.writeHead(404, { 'Content-Type': 'text/plain' }).end(`not found: ${request.url}\n`);
    return;
  }
  const headers = { 'Content-Type': types[path.extname(file)] || 'application/octet-stream', 'Accept-Ranges': 'bytes', 'Cache-Control': 'no-store' };
  const r = range(request.headers.range, stat.size);
  if (r === 'bad') {
    response.writeHead(416, { 'Content-Range': `bytes */${stat.size}` }).end();
    return;
  }
  const [start, end] = r || [0, stat.size - 1];
  headers['Content-Length'] = String(stat.size ? end - start + 1 : 0);
  if (r) headers['Content-Range'] = `bytes ${start}-${end}/${stat.size}`;
  response.writeHead(r ? 206 : 200, headers);
  if (request.method === 'HEAD' || stat.size === 0) {
    response.end();
    return;
  }
  const body = createReadStream(file, { start, end, highWaterMark: options.piece });
  if (!options.throttle || path.extname(file) !== '.tom') {
    body.pipe(response);
    return;
  }
  // at the throttled rate: each piece after the time it takes at that rate
  for await (const piece of body) {
    if (response.destroyed) break;
    response.write(piece);
    await new Promise((done) => setTimeout(done, (1000 * piece.length) / options.throttle));
  }
  response.end();
}

const options = parseArguments(process.argv.slice(2));
const server = http.createServer((request, response) => {
  send(options, request, response).catch((error) => {
    if (!response.headersSent) response.writeHead(500, { 'Content-Type': 'text/plain' });
    response.end(String(error));
  });
});
server.listen(options.port, options.host, () => {
  const address = server.address();
  console.log(`serving ${options.root} at http://${address.address}:${address.port}/`);
});
