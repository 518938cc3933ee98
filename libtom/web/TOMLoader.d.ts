// TypeScript declarations of TOMLoader.mjs: the three.js loader of .tom files.
import { Camera, Group, Loader, LoadingManager } from 'three';
import { TOMError, TOMRuntime } from './tom.js';

export type Resolution = number | { fraction: number } | { vertices: number };

export function defaultRuntime(): Promise<TOMRuntime>;

export class TOMLoader extends Loader<TOMObject> {
  constructor(manager?: LoadingManager);
  setRuntime(runtime: TOMRuntime): this;
  setShading(shading: 'standard' | 'reference'): this;
  setResolution(resolution: Resolution | null): this;
  setAutomatic(enabled: boolean, pixels?: number): this;
  load(url: string, onLoad?: (object: TOMObject) => void, onProgress?: (event: { loaded: number; total: number }) => void,
       onError?: (error: TOMError) => void): void;
}

export class TOMObject extends Group {
  readonly url: string;
  readonly bytesReceived: number;
  readonly fileBytes: number;
  /** the bytes that had arrived when the first frame was drawn */
  readonly firstFrameBytes: number;
  readonly complete: boolean;
  readonly drawnTriangles: number;
  readonly drawnVertices: number;
  readonly error: TOMError | null;
  /** per mesh, the full-detail bounds [min x, y, z, max x, y, z] */
  readonly bounds: number[][];
  /** settles when what the object was asked for is in */
  readonly loaded: Promise<TOMObject>;
  /** settles when every texture has been decoded or fetched (or failed, with a warning) */
  texturesLoaded(): Promise<void[]>;
  setResolution(resolution: Resolution): void;
  setAutomatic(enabled: boolean, pixels?: number): void;
  update(camera: Camera, height: number): void;
  drawnIndices(mesh: number): { indices: Uint32Array; vertices: number; decoded: number };
  dispose(): void;
}

export class TOMStreamScheduler {
  constructor(bytesPerSecond: number);
  add(object: TOMObject): void;
  update(camera: Camera, height: number, seconds: number): void;
}
