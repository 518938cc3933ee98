// The TOM viewer: loads .tom files (streamed or not) with TOMLoader and shows them refining as
// their bytes arrive, with the bytes received, the vertices and triangles drawn and the frame
// time; a slider sets the resolution, a toggle hands it to the automatic mode.
//
// URL parameters: file=URL (repeatable), resolution=FRACTION, auto=1, budget=BYTES_PER_SECOND
// (automatic mode under a link budget), shading=reference (tomview's lighting, no antialiasing,
// linear output: what the browser test compares with the native renderer), size=WxH (a fixed
// canvas), probe=MODULE (a same-origin module given the viewer: the browser test's checks).
import * as THREE from 'three';
import { OrbitControls } from './vendor/three/OrbitControls.js';
import { TOMLoader, TOMStreamScheduler } from './TOMLoader.mjs';

const params = new URLSearchParams(location.search);
const reference = params.get('shading') === 'reference';
const background = [0.92, 0.93, 0.95]; // tomview's

export class Viewer {
  constructor(canvas) {
    this.canvas = canvas;
    this.renderer = new THREE.WebGLRenderer({ canvas, antialias: !reference, preserveDrawingBuffer: true });
    this.renderer.setPixelRatio(reference ? 1 : window.devicePixelRatio);
    // reference shading writes its values as they are, like the native renderer
    if (reference) this.renderer.outputColorSpace = THREE.LinearSRGBColorSpace;
    this.scene = new THREE.Scene();
    this.scene.background = new THREE.Color(...background);
    this.scene.add(new THREE.HemisphereLight(0xffffff, 0x8d8d8d, 1.6));
    const sun = new THREE.DirectionalLight(0xffffff, 2.2);
    sun.position.set(0.4, 0.8, 0.5);
    this.scene.add(sun);
    this.camera = new THREE.PerspectiveCamera(50, 1, 0.01, 100);
    this.controls = new OrbitControls(this.camera, canvas);
    this.loader = new TOMLoader().setShading(reference ? 'reference' : 'standard');
    if (params.has('resolution')) this.loader.setResolution(Number(params.get('resolution')));
    if (params.get('auto') === '1') this.loader.setAutomatic(true);
    this.scheduler = params.has('budget') ? new TOMStreamScheduler(Number(params.get('budget'))) : null;
    this.objects = [];
    this.errors = [];
    this.frameMs = 0;
    this.fixedSize = params.has('size') ? params.get('size').split('x').map(Number) : null;
    this.last = performance.now();
    this.resize();
    window.addEventListener('resize', () => this.resize());
    this.renderer.setAnimationLoop(() => this.frame());
  }

  resize() {
    const [w, h] = this.fixedSize || [this.canvas.clientWidth, this.canvas.clientHeight];
    this.renderer.setSize(w, h, !!this.fixedSize); // a fixed size sets the canvas style; otherwise CSS sizes it
    this.camera.aspect = w / h;
    this.camera.updateProjectionMatrix();
  }

  /** Loads `url`; resolves with the object at its first frame, or rejects (and shows the error). */
  async load(url) {
    try {
      const object = await this.loader.loadAsync(url, () => this.showStats());
      if (this.scheduler) this.scheduler.add(object);
      object.addEventListener('refine', () => this.showStats());
      object.addEventListener('error', (event) => this.showError(event.error));
      object.loaded.then(() => this.showStats(), () => {});
      this.objects.push(object);
      this.scene.add(object);
      this.frameAll();
      return object;
    } catch (error) {
      this.showError(error);
      throw error;
    }
  }

  // tomview's framing (samples/walkthrough/tomview.cpp): the world box of every instance's
  // full-detail box, seen from centre + (1.3, 0.9, 1.8) radius with a 50 degree field of view
  frameAll() {
    const box = new THREE.Box3();
    for (const object of this.objects) {
      object.updateMatrixWorld(true);
      for (const mesh of object.children) {
        const b = object.bounds[mesh.userData.mesh];
        box.union(new THREE.Box3(new THREE.Vector3(b[0], b[1], b[2]), new THREE.Vector3(b[3], b[4], b[5])).applyMatrix4(mesh.matrixWorld));
      }
    }
    const centre = box.getCenter(new THREE.Vector3());
    const radius = Math.max(1e-6, 0.5 * box.getSize(new THREE.Vector3()).length());
    this.camera.position.copy(centre).add(new THREE.Vector3(1.3, 0.9, 1.8).multiplyScalar(radius));
    this.camera.near = 0.05 * radius;
    this.camera.far = 10 * radius;
    this.camera.updateProjectionMatrix();
    this.controls.target.copy(centre);
    this.controls.update();
  }

  /** Every object at a fraction of its triangles. */
  setResolution(fraction) {
    for (const object of this.objects) object.setResolution(fraction);
  }

  setAutomatic(enabled) {
    for (const object of this.objects) object.setAutomatic(enabled);
  }

  frame() {
    const now = performance.now();
    const seconds = (now - this.last) / 1000;
    this.last = now;
    const height = this.renderer.domElement.height;
    if (this.scheduler) this.scheduler.update(this.camera, height, seconds);
    else for (const object of this.objects) object.update(this.camera, height);
    const t0 = performance.now();
    this.renderer.render(this.scene, this.camera);
    this.frameMs = 0.9 * this.frameMs + 0.1 * (performance.now() - t0);
    this.frames = (this.frames || 0) + 1;
    if (this.frames % 15 === 0) this.showStats();
  }

  showStats() {
    const rows = [];
    for (const o of this.objects) {
      const total = o.fileBytes;
      rows.push([o.name, `${o.bytesReceived.toLocaleString()} of ${total.toLocaleString()} bytes (${total ? ((100 * o.bytesReceived) / total).toFixed(1) : 0}%)`]);
      rows.push(['drawn', `${o.drawnVertices.toLocaleString()} vertices, ${o.drawnTriangles.toLocaleString()} triangles`]);
    }
    rows.push(['frame', `${this.frameMs.toFixed(2)} ms to render`]);
    document.getElementById('stats').innerHTML = rows.map(([k, v]) => `<tr><td>${k}</td><td>${v}</td></tr>`).join('');
  }

  showError(error) {
    this.errors.push(error);
    const box = document.getElementById('error');
    box.textContent = (box.textContent ? box.textContent + '\n' : '') + (error.message || String(error));
  }
}

const viewer = new Viewer(document.getElementById('view'));
window.viewer = viewer;

const slider = document.getElementById('resolution');
const automatic = document.getElementById('auto');
automatic.checked = params.get('auto') === '1';
if (params.has('resolution')) {
  slider.value = params.get('resolution');
  document.getElementById('fraction').textContent = `${(100 * Number(slider.value)).toFixed(1)}%`;
}
slider.addEventListener('input', () => {
  automatic.checked = false;
  document.getElementById('fraction').textContent = `${(100 * Number(slider.value)).toFixed(1)}%`;
  viewer.setResolution(Number(slider.value));
});
automatic.addEventListener('change', () => viewer.setAutomatic(automatic.checked));
document.getElementById('open').addEventListener('submit', (event) => {
  event.preventDefault();
  const url = document.getElementById('url').value.trim();
  if (url) viewer.load(url).catch(() => {});
});

const probe = params.get('probe');
if (probe && new URL(probe, location.href).origin === location.origin) {
  import(new URL(probe, location.href).href).then((m) => m.attach(viewer, params));
} else {
  for (const url of params.getAll('file')) viewer.load(url).catch(() => {});
}
