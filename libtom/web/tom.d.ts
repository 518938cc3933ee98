// TypeScript declarations of tom.mjs: libtom's runtime in WebAssembly.

export class TOMError extends Error {}

export interface StreamChunk {
  mesh: number;
  vertexBegin: number;
  vertexEnd: number;
  /** the mesh's live triangles once the chunk is decoded */
  triangles: number;
  beginByte: number;
  endByte: number;
}

export interface StreamDirectory {
  fileBytes: number;
  /** per mesh, the full-detail bounds [min x, y, z, max x, y, z] */
  bounds: number[][];
  chunks: StreamChunk[];
  /** the sections no frame needs to draw (images, provenance, source glTF), stored after chunk afterChunk - 1; empty when beginByte === endByte */
  deferred: { afterChunk: number; beginByte: number; endByte: number };
}

export interface TextureRef { /** 'baseColor', 'metallicRoughness', 'normal', 'occlusion' or 'emissive' */ role: string; texcoord: number; uri: string; image: number }
export interface MaterialInfo {
  name: string;
  base_color: [number, number, number, number];
  metallic: number;
  roughness: number;
  emissive: [number, number, number];
  /** 0 opaque, 1 mask, 2 blend */
  alpha_mode: number;
  alpha_cutoff: number;
  double_sided: boolean;
  textures: TextureRef[];
}
export interface InstanceInfo { mesh: number; name: string; transform: number[] }
export interface ImageInfo { name: string; mime_type: string; bytes: number }
export interface MeshInfo {
  name: string;
  /** decoded resolution */
  vertices: number;
  triangles: number;
  min_vertices: number;
  floor: number;
  normals: boolean;
  texcoords: boolean;
  colors: boolean;
  bounds_min: [number, number, number];
  bounds_max: [number, number, number];
  parts: { material: number; triangles: number }[];
  curve: { diagonal: number; k_mean: number; points: [number, number, number][] } | null;
}

export interface Extraction {
  /** the resolution drawn: every index is below it */
  vertices: number;
  triangles: number;
  /** a view of the wasm heap, valid until the next call into the runtime */
  indices: Uint32Array;
  draws: { firstIndex: number; indexCount: number; material: number }[];
}

export function createRuntime(options?: { locateFile?: (path: string, prefix: string) => string }): Promise<TOMRuntime>;

export class TOMRuntime {
  openSource(name: string): TOMSource;
}

export class TOMSource {
  readonly name: string;
  readonly directory: StreamDirectory | null;
  readonly failed: TOMError | null;
  readonly isStream: boolean;
  readonly bytesReceived: number;
  readonly decodedChunks: number;
  readonly nextBoundary: number;
  /** every chunk decoded and the deferred block in */
  readonly complete: boolean;
  /** the deferred block is in: snapshots hold the file's images from then on */
  readonly deferredReceived: boolean;
  /** Takes the next bytes; returns the decoded chunk count. Throws TOMError on malformed input. */
  append(bytes: Uint8Array): number;
  snapshot(): TOMSnapshot;
  dispose(): void;
}

export class TOMSnapshot {
  readonly materials: MaterialInfo[];
  readonly instances: InstanceInfo[];
  readonly images: ImageInfo[];
  readonly meshes: MeshInfo[];
  stream(mesh: number, name: 'position' | 'normal' | 'uv' | 'color'): Float32Array | null;
  image(index: number): Uint8Array | null;
  vertexCountForTriangles(mesh: number, triangles: number): number;
  /** object units: the mean distance, or with `max` the Hausdorff distance; null without a stored curve */
  estimateError(mesh: number, triangles: number, max?: boolean): number | null;
  extract(mesh: number, vertexCount: number): Extraction;
}
