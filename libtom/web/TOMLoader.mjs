// A three.js loader for .tom files. load() fetches the file with a streamed body; a streamed
// .tom (tombuild --stream) is drawn from its first chunk on and refines in place as chunks arrive:
// each mesh's vertex and index buffers are allocated once at full size and only the new ranges
// are uploaded. An ordinary .tom is drawn once it is in.
//
// A TOMObject (the THREE.Group load() gives) draws its meshes at:
//   - full detail (the default): it fetches the whole file;
//   - setResolution(fraction | {fraction} | {vertices}): it fetches the prefix that resolution needs
//     (HTTP Range requests) and draws exactly that level;
//   - setAutomatic(true): every update(camera, height) picks each mesh's resolution from its
//     projected screen-space error (the error curve tombuild stored, Pasman & Jansen's D = k / N
//     beyond it) and fetches the bytes it needs; several objects under a TOMStreamScheduler share a
//     link budget (bytes per second), spent first where a byte buys the most error.

import {
  BufferAttribute,
  BufferGeometry,
  Color,
  DoubleSide,
  DynamicDrawUsage,
  FrontSide,
  Group,
  Loader,
  Matrix4,
  Mesh,
  MeshStandardMaterial,
  NoColorSpace,
  RepeatWrapping,
  ShaderMaterial,
  Sphere,
  SRGBColorSpace,
  Texture,
  TextureLoader,
  Vector3,
} from 'three';
import { createRuntime, TOMError } from './tom.mjs';

let sharedRuntime = null;

/** The runtime every loader shares unless given one (one wasm instance for the page). */
export function defaultRuntime() {
  if (!sharedRuntime) sharedRuntime = createRuntime();
  return sharedRuntime;
}

export class TOMLoader extends Loader {
  constructor(manager) {
    super(manager);
    this.runtime = null;
    this.shading = 'standard';
    this.resolution = null;
    this.automatic = null;
  }

  /** Objects loaded from now on start at this resolution (TOMObject.setResolution) and fetch only its bytes. */
  setResolution(resolution) {
    this.resolution = resolution;
    return this;
  }

  /** Objects loaded from now on start in automatic mode (TOMObject.setAutomatic). */
  setAutomatic(enabled, pixels = 1) {
    this.automatic = enabled ? { pixels } : null;
    return this;
  }

  /** A runtime from tom.mjs' createRuntime() (default: one shared by the page). */
  setRuntime(runtime) {
    this.runtime = runtime;
    return this;
  }

  /**
   * 'standard': the file's materials as MeshStandardMaterial (glTF's metallic-roughness model);
   * 'reference': tomview's shading (two directional lights and an ambient term per vertex, the
   * base colour, no tone mapping), to compare a frame with the native renderer's image.
   */
  setShading(shading) {
    this.shading = shading;
    return this;
  }

  /**
   * Starts loading `url`. onLoad(object) is called at the first frame that can be drawn (a stream's
   * first chunk of every mesh, an ordinary file's last byte); the object then refines in place and
   * its `loaded` promise settles when what it was asked for is in. onProgress receives
   * {loaded, total} after every piece of the body; onError a TOMError naming the URL and the problem.
   */
  load(url, onLoad, onProgress, onError) {
    const resolved = new URL(this.manager.resolveURL(this.path + url), globalThis.location ? globalThis.location.href : undefined).href;
    this.manager.itemStart(resolved);
    const object = new TOMObject(resolved, {
      shading: this.shading,
      headers: this.requestHeader,
      credentials: this.withCredentials ? 'include' : 'same-origin',
      onProgress,
    });
    if (this.resolution !== null) object.setResolution(this.resolution);
    if (this.automatic) object.setAutomatic(true, this.automatic.pixels);
    let first = true;
    object.addEventListener('firstframe', () => {
      first = false;
      if (onLoad) onLoad(object);
    });
    Promise.resolve(this.runtime || defaultRuntime())
      .then((runtime) => object.start(runtime))
      .then(
        () => this.manager.itemEnd(resolved),
        (error) => {
          if (onError) onError(error);
          else console.error(error);
          this.manager.itemError(resolved);
          this.manager.itemEnd(resolved);
          if (first) object.dispose();
        },
      );
  }
}

// tomview's lighting (samples/walkthrough/renderer.cpp): per vertex, written without tone
// mapping or colour-space conversion, as the native renderer writes it
const referenceVertex = `
uniform vec3 baseColor;
varying vec3 vShade;
#ifdef USE_IMAGE
varying vec2 vUv;
#endif
void main() {
  vec3 n = normalize(mat3(modelMatrix) * normal);
  float d = 0.15 + 0.65 * max(dot(n, normalize(vec3(0.4, 0.8, 0.5))), 0.0) + 0.3 * max(dot(n, normalize(vec3(-0.6, 0.2, -0.4))), 0.0);
  vShade = baseColor * d;
#ifdef USE_IMAGE
  vUv = uv;
#endif
  gl_Position = projectionMatrix * viewMatrix * modelMatrix * vec4(position, 1.0);
}`;
const referenceFragment = `
varying vec3 vShade;
#ifdef USE_IMAGE
varying vec2 vUv;
uniform sampler2D image;
#endif
void main() {
#ifdef USE_IMAGE
  gl_FragColor = vec4(vShade * texture2D(image, vUv).rgb, 1.0);
#else
  gl_FragColor = vec4(vShade, 1.0);
#endif
}`;

/** One mesh of a file: its geometry at full size and how far it is filled and drawn. */
class MeshSlot {
  constructor(totalVertices, totalTriangles, streams) {
    this.copied = 0; // vertices copied from the decoded streams
    this.drawn = 0; // the resolution drawn
    this.triangles = 0; // the triangles drawn
    this.geometry = new BufferGeometry();
    this.streams = streams; // names of the streams the mesh has
    const sizes = { position: 3, normal: 3, uv: 2, color: 4 };
    for (const name of streams) this.geometry.setAttribute(name, new BufferAttribute(new Float32Array(totalVertices * sizes[name]), sizes[name]));
    const index = new BufferAttribute(new Uint32Array(Math.max(3, 3 * totalTriangles)), 1);
    index.setUsage(DynamicDrawUsage);
    this.geometry.setIndex(index);
  }
}

// A material's base-colour texture on TEXCOORD_0, the one the loader draws (undefined when none).
const baseColorTexture = (mat) => mat.textures.find((t) => t.role === 'baseColor' && t.texcoord === 0);

export class TOMObject extends Group {
  constructor(url, options = {}) {
    super();
    this.name = url.split('/').pop();
    this.url = url;
    this.options = options;
    this.source = null;
    this.slots = [];
    this.chunkError = []; // per chunk: its mesh's error once decoded (object units)
    this.meshChunks = null; // per mesh, its chunks' indices (from the directory on)
    this.totals = []; // per mesh, its full {vertices, triangles}
    this.targets = []; // per mesh, the resolution asked for
    this.mode = 'full';
    this.pixels = 1;
    this.wantEnd = Infinity; // the bytes the targets need (from the directory on)
    this.grantedEnd = Infinity; // what a scheduler allows (from the directory on)
    this.fetching = false;
    this.error = null;
    this.bounds = null; // per mesh [min x, y, z, max x, y, z] of the full-detail mesh
    this.frames = 0;
    this.loaded = new Promise((resolve, reject) => {
      this.resolveLoaded = resolve;
      this.rejectLoaded = reject;
    });
    this.loaded.catch(() => {}); // also reported to onError
  }

  /** The bytes that had arrived when the first frame was drawn. */
  firstFrameBytes = 0;

  /** The textures being decoded or fetched; texturesLoaded() settles when they all have. */
  textureLoads = [];

  texturesLoaded() {
    return Promise.all(this.textureLoads);
  }

  get bytesReceived() {
    return this.source ? this.source.bytesReceived : 0;
  }
  get fileBytes() {
    return this.source && this.source.directory ? this.source.directory.fileBytes : this.contentLength || 0;
  }
  get complete() {
    return !!this.source && (this.source.isStream ? this.source.complete : this.slots.length > 0);
  }
  /** Triangles and vertices drawn over every mesh (each instance counted once per mesh). */
  get drawnTriangles() {
    return this.slots.reduce((sum, s) => sum + s.triangles, 0);
  }
  get drawnVertices() {
    return this.slots.reduce((sum, s) => sum + s.drawn, 0);
  }

  async start(runtime) {
    this.source = runtime.openSource(this.url);
    await this.pump();
  }

  /** Draws every mesh at a fraction of its triangles, or at a vertex count ({vertices: n}, clamped per mesh). */
  setResolution(resolution) {
    this.mode = 'fixed';
    this.resolution = typeof resolution === 'number' ? (resolution <= 1 ? { fraction: resolution } : { vertices: resolution }) : resolution;
    this.retarget();
  }

  /** Automatic mode: each mesh at the coarsest resolution whose projected error is at most `pixels`. */
  setAutomatic(enabled, pixels = 1) {
    this.mode = enabled ? 'auto' : 'full';
    this.pixels = pixels;
    if (!enabled) {
      this.resolution = null;
      this.retarget();
    }
  }

  /**
   * Automatic mode's step, once per frame: picks each mesh's resolution for `camera` and a
   * viewport `height` pixels tall, redraws what changed and fetches what is missing (unless a
   * scheduler grants the bytes).
   */
  update(camera, height) {
    if (this.mode !== 'auto' || !this.slots.length || !this.meshChunks) return; // an ordinary file: all of it is in
    const chunks = this.source.directory.chunks;
    for (let m = 0; m < this.slots.length; ++m) {
      const scale = this.pixelsPerUnit(m, camera, height);
      let target = this.totals[m].vertices;
      for (const i of this.meshChunks[m])
        if (this.chunkError[i] * scale <= this.pixels) {
          target = chunks[i].vertexEnd;
          break;
        }
      this.targets[m] = target;
    }
    this.retarget();
  }

  /** Screen pixels per object unit of mesh m's nearest instance (its bounding sphere's near side). */
  pixelsPerUnit(m, camera, height) {
    const b = this.bounds[m];
    const centre = new Vector3((b[0] + b[3]) / 2, (b[1] + b[4]) / 2, (b[2] + b[5]) / 2);
    const radius = 0.5 * Math.hypot(b[3] - b[0], b[4] - b[1], b[5] - b[2]);
    const eye = new Vector3().setFromMatrixPosition(camera.matrixWorld);
    const focal = height / (2 * Math.tan(((camera.fov || 50) * Math.PI) / 360));
    let best = 0;
    for (const mesh of this.children) {
      if (mesh.userData.mesh !== m) continue;
      const scale = mesh.matrixWorld.getMaxScaleOnAxis();
      const distance = Math.max(centre.clone().applyMatrix4(mesh.matrixWorld).distanceTo(eye) - radius * scale, camera.near || 1e-3);
      best = Math.max(best, (focal * scale) / distance);
    }
    return best;
  }

  // Each mesh's target (full detail, the fixed resolution, or automatic mode's last pick), the
  // bytes they need, and the draws within what is decoded.
  retarget() {
    if (!this.meshChunks) {
      this.redraw(); // an ordinary file (or nothing yet): all there is is in
      return;
    }
    const chunks = this.source.directory.chunks;
    const r = this.resolution;
    for (let m = 0; m < this.totals.length; ++m) {
      const total = this.totals[m];
      if (this.mode === 'auto') {
        if (this.targets[m] === undefined) this.targets[m] = chunks[this.meshChunks[m][0]].vertexEnd; // until the first update
      } else if (this.mode === 'full' || !r) {
        this.targets[m] = total.vertices;
      } else if (r.vertices !== undefined) {
        this.targets[m] = Math.min(total.vertices, Math.max(1, Math.floor(r.vertices)));
      } else {
        // the first chunk reaching the fraction's triangles; extraction then picks the exact level
        this.targets[m] = total.vertices;
        for (const i of this.meshChunks[m])
          if (chunks[i].triangles >= Math.ceil(r.fraction * total.triangles)) {
            this.targets[m] = chunks[i].vertexEnd;
            break;
          }
      }
    }
    let end = 0;
    for (const c of chunks) if (c.vertexBegin < this.targets[c.mesh]) end = Math.max(end, c.endByte);
    // the deferred block too: every resolution is drawn with the file's images
    this.wantEnd = Math.max(end, this.source.directory.deferred.endByte);
    this.redraw();
    this.pump().catch(() => {}); // an error is the object's: its 'error' event and `loaded`
  }

  // Where the current fetch should end: before a stream's directory, the whole file (full
  // detail) or the next boundary (header, then directory: a range client reads them first);
  // then what the targets need, within what a scheduler granted (automatic mode only: a fixed or
  // full resolution is fetched as asked).
  fetchEnd() {
    const s = this.source;
    if (s.directory) return Math.min(this.wantEnd, this.mode === 'auto' ? this.grantedEnd : Infinity, s.directory.fileBytes);
    if (this.mode === 'full' || (s.bytesReceived >= 8 && !s.isStream)) return this.contentLength || Infinity; // the whole, however long
    return s.nextBoundary;
  }

  // Fetches [received, min(wantEnd, grantedEnd)) with a streamed body, as Range requests from
  // the second on; a server that ignores Range answers 200 and the bytes already held are skipped.
  async pump() {
    if (this.fetching || this.error) return;
    this.fetching = true;
    try {
      for (;;) {
        const end = this.fetchEnd();
        const received = this.source.bytesReceived;
        if (received >= end) break;
        const headers = Object.assign({}, this.options.headers);
        if (received > 0 || end !== Infinity) headers.Range = `bytes=${received}-${end === Infinity ? '' : end - 1}`;
        const response = await fetch(this.url, { headers, credentials: this.options.credentials });
        if (response.status === 416 && this.source.directory) throw this.truncated();
        if (!response.ok) throw new TOMError(`${this.url}: HTTP ${response.status} ${response.statusText}`);
        // the object's size as the server has it: shorter than the stream declares is a truncation
        const size = response.status === 200 ? Number(response.headers.get('Content-Length')) : Number((response.headers.get('Content-Range') || '').split('/')[1]);
        if (size) this.contentLength = size;
        if (size && this.source.directory && size < this.source.directory.fileBytes) throw this.truncated(size);
        let skip = response.status === 200 ? received : 0;
        const reader = response.body.getReader();
        for (;;) {
          const { done, value } = await reader.read();
          if (done) break;
          let bytes = value;
          if (skip) {
            const n = Math.min(skip, bytes.length);
            bytes = bytes.subarray(n);
            skip -= n;
          }
          if (bytes.length) this.take(bytes);
          if (this.error) break;
          if (this.source.bytesReceived >= this.fetchEnd()) {
            await reader.cancel();
            break;
          }
        }
        if (this.error) throw this.error;
        if (this.source.bytesReceived === received) break; // nothing more to come
      }
      this.finishIfDone();
    } catch (error) {
      this.fail(error instanceof TOMError ? error : new TOMError(`${this.url}: ${error.message || error}`));
    } finally {
      this.fetching = false;
    }
    if (this.error) throw this.error;
  }

  // Appends a piece of the body; draws what new chunks made decodable. Until the first frame the
  // piece is cut where the decoder can go on, so that frame is drawn from the fewest bytes even
  // when the network hands over several chunks at once.
  take(bytes) {
    // (the first 8 bytes alone: the magic says whether the file is a stream)
    while (!this.slots.length && (this.source.isStream || this.source.bytesReceived < 8) && !this.error) {
      const cut = this.source.nextBoundary - this.source.bytesReceived;
      if (cut <= 0 || cut >= bytes.length) break;
      this.takePiece(bytes.subarray(0, cut));
      bytes = bytes.subarray(cut);
    }
    if (!this.error) this.takePiece(bytes);
  }

  takePiece(bytes) {
    const before = this.source.decodedChunks;
    const imagesBefore = this.source.isStream && this.source.deferredReceived;
    try {
      this.source.append(bytes);
    } catch (error) {
      this.fail(error);
      return;
    }
    if (this.options.onProgress) this.options.onProgress({ loaded: this.source.bytesReceived, total: this.fileBytes, lengthComputable: this.fileBytes > 0 });
    if (this.source.directory && !this.meshChunks) this.onDirectory();
    const news = this.source.decodedChunks > before || (!imagesBefore && this.source.deferredReceived);
    if (this.source.isStream && news && this.source.decodedChunks >= this.totals.length) this.refine();
  }

  // A stream's directory: its meshes' chunks, sizes and bounds, the error after each chunk, and
  // the targets (so a range client asks for no more than they need).
  onDirectory() {
    const d = this.source.directory;
    this.meshChunks = d.bounds.map(() => []);
    d.chunks.forEach((c, i) => this.meshChunks[c.mesh].push(i));
    this.totals = this.meshChunks.map((list) => ({ vertices: d.chunks[list[list.length - 1]].vertexEnd, triangles: d.chunks[list[list.length - 1]].triangles }));
    this.bounds = d.bounds;
    this.errorModel(this.source.snapshot()); // the meshes are empty; their metadata (the error curves) is in
    this.retarget();
  }

  finishIfDone() {
    if (!this.source.isStream) {
      if (!this.slots.length) this.refine(); // an ordinary file: all of it is in
      this.resolveLoaded(this);
      return;
    }
    const d = this.source.directory;
    if (!d) throw new TOMError(`${this.url}: the stream ends after ${this.source.bytesReceived} bytes, before its directory`);
    const end = Math.min(this.wantEnd, d.fileBytes);
    if (this.source.bytesReceived < end && this.fetchEnd() >= end) throw this.truncated();
    if (this.source.bytesReceived >= end) this.resolveLoaded(this);
  }

  truncated(size = this.source.bytesReceived) {
    return new TOMError(`${this.url}: the stream ends after ${size} of its ${this.source.directory.fileBytes} bytes`);
  }

  fail(error) {
    if (this.error) return;
    this.error = error;
    this.rejectLoaded(error);
    this.dispatchEvent({ type: 'error', error });
  }

  // A new snapshot: the scene on the first, then the new vertices and every mesh's draw.
  refine() {
    const snapshot = this.source.snapshot();
    const first = !this.slots.length;
    if (first) this.build(snapshot);
    if (!this.imagesIn && this.source.deferredReceived) this.attachImages(snapshot);
    for (let m = 0; m < this.slots.length; ++m) this.copyVertices(snapshot, m);
    this.snapshot = snapshot;
    this.redraw();
    if (first) {
      this.firstFrameBytes = this.source.bytesReceived;
      this.dispatchEvent({ type: 'firstframe' });
    }
  }

  build(snapshot) {
    if (!this.source.isStream) {
      // an ordinary file: whole, at full detail unless asked otherwise
      this.totals = snapshot.meshes.map((m) => ({ vertices: m.vertices, triangles: m.triangles }));
      this.bounds = snapshot.meshes.map((m) => [...m.bounds_min, ...m.bounds_max]);
      this.targets = this.totals.map((t) => t.vertices);
    }
    this.slots = snapshot.meshes.map((mesh, m) => {
      const streams = ['position'];
      if (mesh.normals) streams.push('normal');
      if (mesh.texcoords) streams.push('uv');
      if (mesh.colors) streams.push('color');
      const slot = new MeshSlot(this.totals[m].vertices, this.totals[m].triangles, streams);
      const b = this.bounds[m];
      slot.geometry.boundingSphere = new Sphere(new Vector3((b[0] + b[3]) / 2, (b[1] + b[4]) / 2, (b[2] + b[5]) / 2), 0.5 * Math.hypot(b[3] - b[0], b[4] - b[1], b[5] - b[2]));
      return slot;
    });
    const materials = snapshot.materials.map((mat) => this.makeMaterial(snapshot, mat));
    this.materialUses = materials.map((m) => [m]); // per material of the file, the three.js materials drawing it
    this.imagesIn = !this.source.isStream || this.source.deferredReceived;
    const fallback = this.makeMaterial(snapshot, null);
    for (const instance of snapshot.instances) {
      const parts = snapshot.meshes[instance.mesh].parts;
      const slot = this.slots[instance.mesh];
      const list = parts.map((p) => {
        const mat = p.material >= 0 && p.material < materials.length ? materials[p.material] : fallback;
        if (!slot.streams.includes('color') || !mat.isMeshStandardMaterial) return mat;
        const withColors = mat.clone();
        withColors.vertexColors = true;
        if (this.materialUses[p.material]) this.materialUses[p.material].push(withColors);
        return withColors;
      });
      const mesh = new Mesh(slot.geometry, list);
      mesh.name = instance.name;
      mesh.userData.mesh = instance.mesh;
      mesh.matrixAutoUpdate = false;
      mesh.matrix.copy(new Matrix4().fromArray(instance.transform));
      this.add(mesh);
    }
  }

  // Per chunk, the error its mesh shows once it is decoded: the stored curve's Hausdorff distance
  // at the chunk's triangles (a bound on any point's deviation, as a screen-space error wants;
  // the mean would let most of the surface sit within a pixel while a silhouette is off by
  // several); without a curve D = k / N, k set by the first chunk at 1% of the diagonal. A mesh's
  // last chunk is its full detail: 0.
  errorModel(snapshot) {
    const d = this.source.directory;
    if (!d) return;
    this.chunkError = d.chunks.map((c, i) => {
      const chunks = this.meshChunks[c.mesh];
      if (chunks[chunks.length - 1] === i) return 0;
      const e = snapshot.estimateError(c.mesh, c.triangles, true);
      if (e !== null) return e;
      const b = this.bounds[c.mesh];
      const first = d.chunks[chunks[0]].triangles;
      return (0.01 * Math.hypot(b[3] - b[0], b[4] - b[1], b[5] - b[2]) * first) / Math.max(1, c.triangles);
    });
  }

  makeMaterial(snapshot, mat) {
    const base = mat ? mat.base_color : [0.7, 0.7, 0.7, 1];
    const texture = mat && baseColorTexture(mat);
    const map = texture ? this.makeTexture(snapshot, texture) : null;
    if (this.options.shading === 'reference') {
      const m = new ShaderMaterial({
        uniforms: { baseColor: { value: new Color(base[0], base[1], base[2]) }, image: { value: map } },
        vertexShader: referenceVertex,
        fragmentShader: referenceFragment,
        side: DoubleSide,
      });
      if (map) this.useMap(m, map);
      return m;
    }
    const m = new MeshStandardMaterial({
      color: new Color(base[0], base[1], base[2]),
      opacity: base[3],
      metalness: mat ? mat.metallic : 0,
      roughness: mat ? mat.roughness : 0.8,
      emissive: mat ? new Color(mat.emissive[0], mat.emissive[1], mat.emissive[2]) : new Color(0, 0, 0),
      transparent: !!mat && mat.alpha_mode === 2,
      alphaTest: mat && mat.alpha_mode === 1 ? mat.alpha_cutoff : 0,
      side: mat && mat.double_sided ? DoubleSide : FrontSide,
      map,
    });
    if (mat) m.name = mat.name;
    return m;
  }

  // A stream's images, once its deferred block is in (after every mesh's first chunk): each
  // material's base-colour texture, which the frames before drew without.
  attachImages(snapshot) {
    this.imagesIn = true;
    snapshot.materials.forEach((mat, i) => {
      const ref = baseColorTexture(mat);
      if (!ref || ref.image < 0 || !this.materialUses[i]) return;
      const map = this.makeTexture(snapshot, ref);
      for (const m of this.materialUses[i]) this.useMap(m, map);
    });
  }

  useMap(m, map) {
    if (m.isShaderMaterial) {
      m.uniforms.image.value = map;
      m.defines.USE_IMAGE = '';
      map.colorSpace = NoColorSpace;
    } else {
      m.map = map;
    }
    m.needsUpdate = true;
  }

  // A base-colour texture: an image stored in the file, or one the source referenced beside it
  makeTexture(snapshot, ref) {
    const texture = new Texture();
    texture.flipY = false; // glTF's convention, kept by the .tom
    texture.wrapS = texture.wrapT = RepeatWrapping;
    texture.colorSpace = SRGBColorSpace;
    if (ref.image >= 0) {
      const blob = new Blob([snapshot.image(ref.image)], { type: snapshot.images[ref.image].mime_type });
      const load = createImageBitmap(blob, { colorSpaceConversion: 'none' }).then(
        (bitmap) => {
          texture.image = bitmap;
          texture.needsUpdate = true;
        },
        (error) => console.warn(`${this.url}: image ${ref.image} does not decode (${error.message}); drawn without it`),
      );
      this.textureLoads.push(load);
    } else if (ref.uri) {
      const load = new TextureLoader()
        .loadAsync(new URL(ref.uri.replace(/\\/g, '/'), this.url).href)
        .then(
          (loaded) => {
            texture.image = loaded.image;
            texture.needsUpdate = true;
          },
          () => console.warn(`${this.url}: texture '${ref.uri}' is not beside the file; drawn without it`),
        );
      this.textureLoads.push(load);
    } else {
      return null;
    }
    return texture;
  }

  // Copies mesh m's vertices decoded since the last snapshot into its attributes.
  copyVertices(snapshot, m) {
    const slot = this.slots[m];
    const n = snapshot.meshes[m].vertices;
    if (n <= slot.copied) return;
    for (const name of slot.streams) {
      const attribute = slot.geometry.getAttribute(name);
      const values = snapshot.stream(m, name);
      const k = attribute.itemSize;
      attribute.array.set(values.subarray(slot.copied * k, n * k), slot.copied * k);
      attribute.addUpdateRange(slot.copied * k, (n - slot.copied) * k);
      attribute.needsUpdate = true;
    }
    slot.copied = n;
  }

  // The resolution mesh m is drawn at: its target within what is decoded (a fraction: the exact
  // level of that many triangles).
  resolutionOf(m) {
    const copied = this.slots[m].copied;
    const r = this.resolution;
    if (this.mode === 'fixed' && r && r.fraction !== undefined && copied > 0)
      return Math.min(copied, this.snapshot.vertexCountForTriangles(m, Math.ceil(r.fraction * this.totals[m].triangles)));
    if (this.mode === 'fixed' && r && r.vertices !== undefined) return Math.min(copied, Math.max(1, Math.floor(r.vertices)));
    return Math.min(copied, this.targets[m] === undefined ? copied : this.targets[m]);
  }

  // Every mesh at its resolution: its index buffer and its parts' groups.
  redraw() {
    if (!this.snapshot) return;
    let changed = false;
    for (let m = 0; m < this.slots.length; ++m) {
      const slot = this.slots[m];
      const n = this.resolutionOf(m);
      if (n === slot.drawn) continue; // the same level: the same triangles
      changed = true;
      const e = this.snapshot.extract(m, n);
      const index = slot.geometry.index;
      index.array.set(e.indices);
      index.clearUpdateRanges();
      index.addUpdateRange(0, e.indices.length);
      index.needsUpdate = true;
      slot.geometry.clearGroups();
      e.draws.forEach((d, p) => slot.geometry.addGroup(d.firstIndex, d.indexCount, p));
      slot.drawn = e.vertices;
      slot.triangles = e.triangles;
    }
    if (!changed) return;
    this.frames += 1;
    this.dispatchEvent({ type: 'refine', bytes: this.source.bytesReceived, frame: this.frames });
  }

  /** The index buffer drawn for mesh m and its resolution, for checks: {indices, vertices}. */
  drawnIndices(m) {
    const slot = this.slots[m];
    return { indices: slot.geometry.index.array.subarray(0, 3 * slot.triangles), vertices: slot.drawn, decoded: slot.copied };
  }

  dispose() {
    for (const slot of this.slots) slot.geometry.dispose();
    this.traverse((o) => {
      if (o.material) for (const m of [].concat(o.material)) m.dispose();
    });
    if (this.source) this.source.dispose();
  }
}

/**
 * Shares a link budget (bytes per second, Pasman & Jansen's link load) among objects in automatic
 * mode: each update grants the next run of chunks that buys the most screen-space error per byte,
 * across all objects, while the budget lasts.
 */
export class TOMStreamScheduler {
  constructor(bytesPerSecond) {
    this.bytesPerSecond = bytesPerSecond;
    this.objects = [];
    this.credit = 0;
  }

  add(object) {
    object.grantedEnd = 0;
    this.objects.push(object);
  }

  update(camera, height, seconds) {
    this.credit = Math.min(this.credit + this.bytesPerSecond * seconds, this.bytesPerSecond);
    for (const o of this.objects) o.update(camera, height);
    while (this.credit > 0) {
      let best = null;
      for (const o of this.objects) {
        const run = this.nextRun(o, camera, height);
        if (run && (!best || run.gain / run.bytes > best.gain / best.bytes)) best = run;
      }
      if (!best) break;
      best.object.grantedEnd = best.end;
      this.credit -= best.bytes;
      best.object.pump().catch(() => {});
    }
  }

  // An object's next chunks up to the first one its targets need: their bytes and the pixels of
  // error that chunk removes.
  nextRun(o, camera, height) {
    if (o.mode !== 'auto' || !o.source || !o.source.directory || !o.slots.length || o.error) return null;
    const chunks = o.source.directory.chunks;
    const start = Math.max(o.grantedEnd, o.source.bytesReceived);
    for (let i = 0; i < chunks.length; ++i) {
      const c = chunks[i];
      if (c.endByte <= start || c.vertexBegin >= o.targets[c.mesh]) continue;
      const scale = o.pixelsPerUnit(c.mesh, camera, height);
      const previous = o.meshChunks[c.mesh].indexOf(i);
      const before = previous > 0 ? o.chunkError[o.meshChunks[c.mesh][previous - 1]] : Infinity;
      const gain = Math.min(before * scale, 1e9) - o.chunkError[i] * scale;
      return { object: o, end: c.endByte, bytes: c.endByte - start, gain: Math.max(gain, 1e-9) };
    }
    // nothing the targets need: the deferred block (the images), when the budget buys nothing better
    const deferred = o.source.directory.deferred;
    if (deferred.endByte > start) return { object: o, end: deferred.endByte, bytes: deferred.endByte - start, gain: 1e-9 };
    return null;
  }
}
