// libtom in the browser: the runtime compiled to WebAssembly (tom_wasm.mjs, built by
// scripts/build-web.sh) behind a JavaScript API. A TOMSource takes a .tom's bytes as they arrive;
// a streamed file (docs/FORMAT.md, "Streamed files") decodes chunk by chunk, each prefix a
// coarser mesh; an ordinary file opens once its last byte is in. snapshot() hands out what is
// decoded: the scene, vertex streams and index buffers extracted at any resolution.
//
// The chunks' meshopt codecs are decoded by meshoptimizer's own npm decoder.

import createTomWasm from './tom_wasm.mjs';
import { MeshoptDecoder } from 'meshoptimizer/decoder';

/** An error of the runtime: its message names the file, the byte offset, the field and the rule. */
export class TOMError extends Error {
  constructor(message) {
    super(message);
    this.name = 'TOMError';
  }
}

const STREAMS = { position: 0, normal: 1, uv: 2, color: 3 };
const COMPONENTS = { position: 3, normal: 3, uv: 2, color: 4 };

/**
 * Loads the WebAssembly runtime and meshoptimizer's decoder.
 * @param {{locateFile?: (path: string, prefix: string) => string}} [options] where tom_wasm.wasm is
 *   (default: beside tom_wasm.mjs)
 */
export async function createRuntime(options = {}) {
  await MeshoptDecoder.ready;
  const wasm = await createTomWasm(options.locateFile ? { locateFile: options.locateFile } : {});
  wasm.meshopt = MeshoptDecoder;
  return new TOMRuntime(wasm);
}

export class TOMRuntime {
  constructor(wasm) {
    this.wasm = wasm;
  }

  /** A new source; `name` stands for the file in error messages (a URL, a path). */
  openSource(name) {
    return new TOMSource(this, name);
  }

  /** Copies `bytes` into the wasm heap, calls f(pointer, length), frees them. */
  withBytes(bytes, f) {
    const w = this.wasm;
    const p = w._malloc(Math.max(1, bytes.length));
    try {
      w.HEAPU8.set(bytes, p);
      return f(p, bytes.length);
    } finally {
      w._free(p);
    }
  }

  withString(text, f) {
    const w = this.wasm;
    const n = w.lengthBytesUTF8(text) + 1;
    const p = w._malloc(n);
    try {
      w.stringToUTF8(text, p, n);
      return f(p);
    } finally {
      w._free(p);
    }
  }
}

/** A .tom being received. Call dispose() when done: the decoder lives in the wasm heap. */
export class TOMSource {
  constructor(runtime, name) {
    this.runtime = runtime;
    this.name = name;
    this.handle = runtime.withString(name, (p) => runtime.wasm._tomw_new(p));
    this.directory = null; // a stream's chunk table, once it is in
    this.failed = null; // the TOMError that stopped it
  }

  get wasm() {
    return this.runtime.wasm;
  }

  /**
   * Takes the next bytes of the file (a Uint8Array). Returns the number of decoded chunks
   * (0 for an ordinary file). Throws a TOMError on malformed input: the source keeps what it
   * decoded before and takes no more bytes.
   */
  append(bytes) {
    if (this.failed) throw this.failed;
    const ok = this.runtime.withBytes(bytes, (p, n) => this.wasm._tomw_append(this.handle, p, n));
    if (!ok) {
      this.failed = new TOMError(this.wasm.UTF8ToString(this.wasm._tomw_error(this.handle)));
      throw this.failed;
    }
    if (!this.directory && this.wasm._tomw_has_directory(this.handle)) {
      const d = JSON.parse(this.wasm.UTF8ToString(this.wasm._tomw_directory_json(this.handle)));
      this.directory = {
        fileBytes: d.file_bytes,
        bounds: d.bounds,
        chunks: d.chunks.map(([mesh, vertexBegin, vertexEnd, triangles, beginByte, endByte]) => ({ mesh, vertexBegin, vertexEnd, triangles, beginByte, endByte })),
        deferred: { afterChunk: d.deferred[0], beginByte: d.deferred[1], endByte: d.deferred[2] },
      };
    }
    return this.decodedChunks;
  }

  get isStream() {
    return this.wasm._tomw_is_stream(this.handle) !== 0;
  }
  get bytesReceived() {
    return this.wasm._tomw_bytes_received(this.handle);
  }
  /** The byte count at which decoding can go on (a stream's header, directory or next chunk end); 0 for an ordinary file. */
  get nextBoundary() {
    return this.wasm._tomw_next_boundary(this.handle);
  }
  get decodedChunks() {
    return this.wasm._tomw_decoded_chunks(this.handle);
  }
  /** True when every chunk of a stream is decoded and its deferred block is in. */
  get complete() {
    return !!this.directory && this.wasm._tomw_complete(this.handle) !== 0;
  }
  /** True when a stream's deferred block (images, provenance, source glTF) is in: snapshots hold its images from then on. */
  get deferredReceived() {
    return this.wasm._tomw_deferred_received(this.handle) !== 0;
  }

  /**
   * A validated .tom of what is decoded (an ordinary file: all of it, once complete). Replaces
   * the previous snapshot. Throws a TOMError.
   */
  snapshot() {
    if (!this.wasm._tomw_snapshot(this.handle)) throw new TOMError(this.wasm.UTF8ToString(this.wasm._tomw_error(this.handle)));
    return new TOMSnapshot(this);
  }

  dispose() {
    if (this.handle) this.wasm._tomw_delete(this.handle);
    this.handle = 0;
  }
}

/**
 * The decoded file at one moment: valid until the source's next snapshot(). The typed arrays it
 * returns are views of the wasm heap, valid until the next call into the runtime: copy them.
 */
export class TOMSnapshot {
  constructor(source) {
    this.source = source;
    const s = JSON.parse(source.wasm.UTF8ToString(source.wasm._tomw_scene_json(source.handle)));
    this.materials = s.materials;
    this.instances = s.instances;
    this.images = s.images;
    this.meshes = s.meshes;
  }

  get wasm() {
    return this.source.wasm;
  }

  /** Mesh m's stream ('position', 'normal', 'uv', 'color') over its decoded vertices, or null. */
  stream(m, name) {
    const p = this.wasm._tomw_stream(this.source.handle, m, STREAMS[name]);
    if (!p) return null;
    return new Float32Array(this.wasm.HEAPU8.buffer, p, this.meshes[m].vertices * COMPONENTS[name]);
  }

  /** Image i's bytes (a copy), for a Blob. */
  image(i) {
    const p = this.wasm._tomw_image_data(this.source.handle, i);
    return p ? this.wasm.HEAPU8.slice(p, p + this.images[i].bytes) : null;
  }

  /** The resolution of mesh m with at least `triangles` live triangles (at its usable floor or above). */
  vertexCountForTriangles(m, triangles) {
    return this.wasm._tomw_vertex_count_for_triangles(this.source.handle, m, triangles);
  }

  /**
   * Mesh m's estimated error at `triangles` in object units (the stored curve, k / N beyond it):
   * the mean distance, or with `max` the Hausdorff distance; null without a curve.
   */
  estimateError(m, triangles, max = false) {
    const e = this.wasm._tomw_estimate_error(this.source.handle, m, triangles, max ? 1 : 0);
    return e < 0 ? null : e;
  }

  /**
   * Mesh m's index buffer at resolution n (clamped to what is decoded): `indices` (a view of
   * 3 * triangles indices, each < vertices) and per part its draw {firstIndex, indexCount, material}.
   */
  extract(m, n) {
    const w = this.wasm;
    const h = this.source.handle;
    const triangles = w._tomw_extract(h, m, n);
    if (triangles < 0) throw new TOMError(`${this.source.name}: mesh ${m} does not exist`);
    const vertices = w._tomw_extracted_vertices(h);
    const indices = new Uint32Array(w.HEAPU8.buffer, w._tomw_indices(h), 3 * triangles);
    const raw = new Int32Array(w.HEAPU8.buffer, w._tomw_draws(h), 3 * this.meshes[m].parts.length);
    const draws = [];
    for (let p = 0; p < this.meshes[m].parts.length; ++p) draws.push({ firstIndex: raw[3 * p], indexCount: raw[3 * p + 1], material: raw[3 * p + 2] });
    return { vertices, triangles, indices, draws };
  }
}
