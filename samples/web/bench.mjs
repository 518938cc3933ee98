// Decode speed in the browser (scripts/bench-web.sh opens this page): a streamed .tom decoded by
// the wasm runtime against meshoptimizer's npm decoder on the reference blocks tomstreambench
// wrote for the same mesh (--reference-out), medians of `repeats` runs after unmeasured runs of
// each (`warmups` and two seconds at least), as the native tomstreambench measures them; and
// progressively, the bytes fed to each chunk boundary with a snapshot after every chunk, as the
// loader refines.
// ?reference=URL of NAME.meshopt.json [&repeats=7] [&warmups=5] [&report=1: POST the figures to /report].
import { MeshoptDecoder } from 'meshoptimizer/decoder';
import { createRuntime } from './tom.mjs';

const params = new URLSearchParams(location.search);
const median = (values) => values.slice().sort((a, b) => a - b)[Math.floor(values.length / 2)];

async function bytesOf(url) {
  const response = await fetch(url);
  if (!response.ok) throw new Error(`${url}: HTTP ${response.status}`);
  return new Uint8Array(await response.arrayBuffer());
}

async function measure() {
  const referenceUrl = new URL(params.get('reference'), location.href);
  const reference = await (await fetch(referenceUrl)).json();
  const stream = await bytesOf(new URL(reference.stream, referenceUrl));
  const blocks = await bytesOf(new URL(reference.blocks, referenceUrl));
  const repeats = Number(params.get('repeats') || 7), warmups = Number(params.get('warmups') || 5);
  const runtime = await createRuntime();
  await MeshoptDecoder.ready;
  const decode = [], image = [], meshopt = [], progressive = [];
  let snapshots = 0;
  let triangles = 0;
  const decodeTom = (record) => {
    const source = runtime.openSource('bench');
    let t0 = performance.now();
    source.append(stream);
    const decoded = performance.now() - t0;
    t0 = performance.now();
    const snapshot = source.snapshot();
    const imaged = performance.now() - t0;
    triangles = snapshot.meshes.reduce((sum, m) => sum + m.triangles, 0);
    source.dispose();
    if (record) decode.push(decoded), image.push(imaged);
  };
  const decodeProgressively = (record) => {
    const source = runtime.openSource('bench');
    const t0 = performance.now();
    let images = 0;
    for (let at = 0; at < stream.length; ) {
      const next = Math.min(Math.max(source.nextBoundary, at + 1), stream.length);
      const before = source.decodedChunks;
      source.append(stream.subarray(at, next));
      at = next;
      if (source.decodedChunks > before) source.snapshot(), ++images;
    }
    if (record) progressive.push(performance.now() - t0), (snapshots = images);
    source.dispose();
  };
  const decodeMeshopt = (record) => {
    const t0 = performance.now();
    for (const m of reference.meshes) {
      const block = ([at, n]) => blocks.subarray(at, at + n);
      MeshoptDecoder.decodeIndexBuffer(new Uint8Array(4 * m.index_count), m.index_count, 4, block(m.indices));
      MeshoptDecoder.decodeVertexBuffer(new Uint8Array(8 * m.vertex_count), m.vertex_count, 8, block(m.positions));
      if (m.normals[1]) MeshoptDecoder.decodeVertexBuffer(new Uint8Array(4 * m.vertex_count), m.vertex_count, 4, block(m.normals));
    }
    if (record) meshopt.push(performance.now() - t0);
  };
  // unmeasured runs of each first, at least `warmups` and for at least two seconds: they grow the
  // wasm's memory and bring its hot code past the baseline tier, which V8 does over the first
  // runs (they took 2-5x the later ones, meshoptimizer's too); then they alternate, so that all
  // see the same moments of this shared machine
  const warmStart = performance.now();
  for (let r = 0; r < 200 && (r < warmups || performance.now() - warmStart < 2000); ++r) decodeTom(false), decodeMeshopt(false), decodeProgressively(false);
  for (let r = 0; r < repeats; ++r) decodeTom(true), decodeMeshopt(true), decodeProgressively(true);
  const total = median(decode) + median(image);
  return {
    stream: reference.stream, triangles, stream_bytes: stream.length, meshopt_bytes: blocks.length,
    decode_ms: median(decode), image_ms: median(image), decode_mb_per_s: stream.length / total / 1e3,
    decode_tris_per_s: (triangles / total) * 1e3, meshopt_decode_ms: median(meshopt), meshopt_tris_per_s: (triangles / median(meshopt)) * 1e3,
    speed_over_meshopt: median(meshopt) / total, progressive_ms: median(progressive), progressive_images: snapshots, user_agent: navigator.userAgent,
    runs_ms: { decode, image, meshopt, progressive },
  };
}

measure().then(
  async (figures) => {
    document.getElementById('out').textContent = JSON.stringify(figures, null, 2);
    if (params.get('report') === '1') await fetch('/report', { method: 'POST', body: JSON.stringify(figures) });
  },
  async (error) => {
    document.getElementById('out').textContent = `error: ${error.message}`;
    if (params.get('report') === '1') await fetch('/report', { method: 'POST', body: JSON.stringify({ error: error.message }) });
  },
);
