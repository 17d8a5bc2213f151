// SPDX-License-Identifier: BSD-3-Clause
//
// The page that `bayon viewer` writes: one textured model (glTF binary,
// embedded in the page as base64) in a full-window WebGL canvas, with orbit
// controls and four display modes. Bundled with three.js into one classic
// script (esbuild, at build time) so that the page runs from file:// as well
// as from any static server, offline: Chromium refuses ES module imports and
// fetch() of local files under file://, so nothing here is loaded at run time.
//
// The page reads two elements that tools/viewer.cc writes:
//   <script type="application/json" id="bayon-viewer-config">  options
//   <script type="application/octet-stream" id="bayon-model">   base64 .glb
// URL parameters override the options: ?mode=textured|shaded|wireframe|
// anaglyph, &azimuth=deg, &elevation=deg, &fov=deg. The first view follows
// bayon render's orbit views (ext/render/views.h): it looks at the centre of
// the model's bounding box from `azimuth` (counter-clockwise seen from above,
// from the datum's x axis) and `elevation` (above the horizontal), `fov` is
// the horizontal field of view, and the distance is the smallest at which
// every vertex lies inside the share FILL of the window; so the same angles
// in a window of render's shape show what render's view shows.
//
// For tests and scripts the state is on <body> (data-status = loading | ready
// | error, data-error, data-mode, data-vertices, data-faces, data-errors = the
// number of console errors) and on window.bayonViewer.
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { AnaglyphEffect } from 'three/addons/effects/AnaglyphEffect.js';

const MODES = ['textured', 'shaded', 'wireframe', 'anaglyph'];
const BACKGROUND = 0x262a31;
const SHADED_GREY = 0xbdbdbd;
const WIRE_COLOUR = 0xe8ecf2;
// Share of the window the model fills in its tighter direction in the first
// view, as bayon render's orbit views (OrbitOptions::fill).
const FILL = 0.8;

const body = document.body;
let numConsoleErrors = 0;

function setStatus(status) {
  body.dataset.status = status;
}

// Every console error counts (three.js reports shader and WebGL failures
// this way), so that a test sees them in the DOM.
const consoleError = console.error.bind(console);
console.error = (...args) => {
  numConsoleErrors += 1;
  body.dataset.errors = String(numConsoleErrors);
  consoleError(...args);
};

function fail(message) {
  console.error('bayon viewer: ' + message);
  setStatus('error');
  body.dataset.error = message;
  const box = document.getElementById('bayon-error');
  if (box) {
    box.textContent = message;
    box.style.display = 'block';
  }
}

window.addEventListener('error', (event) => {
  fail(event.message || String(event.error));
});
window.addEventListener('unhandledrejection', (event) => {
  fail(String(event.reason && event.reason.message ? event.reason.message
                                                   : event.reason));
});

function readConfig() {
  const element = document.getElementById('bayon-viewer-config');
  const config = element ? JSON.parse(element.textContent) : {};
  const params = new URLSearchParams(window.location.search);
  const number = (name, fallback) => {
    if (!params.has(name)) return fallback;
    const value = Number(params.get(name));
    if (!Number.isFinite(value)) {
      throw new Error(`URL parameter ${name} must be a number (got '` +
                      params.get(name) + `')`);
    }
    return value;
  };
  const mode = params.get('mode') || config.mode || 'textured';
  if (!MODES.includes(mode)) {
    throw new Error(`unknown mode '${mode}' (one of ${MODES.join(', ')})`);
  }
  return {
    title: config.title || document.title,
    mode,
    upAxis: config.up_axis || 'y',
    azimuthDeg: number('azimuth', config.azimuth_deg ?? 30),
    elevationDeg: number('elevation', config.elevation_deg ?? 20),
    fovDeg: number('fov', config.fov_deg ?? 40),
  };
}

function decodeBase64(text) {
  const binary = atob(text.replace(/\s+/g, ''));
  const bytes = new Uint8Array(binary.length);
  for (let i = 0; i < binary.length; ++i) bytes[i] = binary.charCodeAt(i);
  return bytes.buffer;
}

// Unit vectors (e1, e2, up) of a right-handed frame whose third axis is the
// model's vertical: azimuth is measured from e1 towards e2. For y up (glTF's
// convention) the frame is the one of a z-up datum turned by -90 degrees
// about x, as bayon's .glb writer turns it: datum (x, y, z) = glTF (x, -z, y),
// so azimuth and elevation mean the same in the datum either way.
function viewFrame(upAxis) {
  const x = new THREE.Vector3(1, 0, 0);
  const y = new THREE.Vector3(0, 1, 0);
  const z = new THREE.Vector3(0, 0, 1);
  if (upAxis === 'y') return [x, z.clone().negate(), y];
  if (upAxis === 'x') return [y, z, x];
  return [x, y, z];
}

function buildPage(title) {
  const style = document.createElement('style');
  style.textContent = `
    html, body { margin: 0; height: 100%; overflow: hidden;
                 background: #262a31; color: #e8ecf2;
                 font: 13px/1.4 system-ui, sans-serif; }
    canvas { display: block; }
    #bayon-ui { position: absolute; top: 8px; left: 8px; }
    #bayon-ui button { margin-right: 4px; padding: 4px 10px; border: 0;
                       border-radius: 3px; background: #3b414b;
                       color: inherit; cursor: pointer; font: inherit; }
    #bayon-ui button.active { background: #5b8dd6; }
    #bayon-title { font-weight: 600; margin-bottom: 6px; }
    #bayon-info { position: absolute; bottom: 6px; left: 8px; opacity: 0.8; }
    #bayon-error { display: none; position: absolute; top: 40%; left: 10%;
                   right: 10%; padding: 12px; background: #8a2a2a; }`;
  document.head.appendChild(style);
  const ui = document.createElement('div');
  ui.id = 'bayon-ui';
  const heading = document.createElement('div');
  heading.id = 'bayon-title';
  heading.textContent = title;
  ui.appendChild(heading);
  MODES.forEach((mode, i) => {
    const button = document.createElement('button');
    button.textContent = `${i + 1} ${mode}`;
    button.dataset.mode = mode;
    ui.appendChild(button);
  });
  const info = document.createElement('div');
  info.id = 'bayon-info';
  const error = document.createElement('div');
  error.id = 'bayon-error';
  body.append(ui, info, error);
  return { ui, info };
}

// The three looks of every mesh: the atlas unlit (its colours are the
// photographs'), a grey lit surface, and hidden-line wireframe (the surface
// filled with the background, its edges drawn on top).
function prepareMaterials(root) {
  const found = [];
  root.traverse((object) => {
    if (object.isMesh) found.push(object);
  });
  // Wireframe children are added after the traversal, which would visit them.
  return found.map((object) => {
    const original = object.material;
    const hasNormals = object.geometry.hasAttribute('normal');
    const textured = new THREE.MeshBasicMaterial({
      map: original.map || null,
      color: original.map ? 0xffffff : original.color,
      vertexColors: object.geometry.hasAttribute('color'),
      side: THREE.DoubleSide,
    });
    const shaded = new THREE.MeshStandardMaterial({
      color: SHADED_GREY,
      roughness: 0.85,
      metalness: 0.0,
      flatShading: !hasNormals,
      side: THREE.DoubleSide,
    });
    const fill = new THREE.MeshBasicMaterial({
      color: BACKGROUND,
      polygonOffset: true,
      polygonOffsetFactor: 1,
      polygonOffsetUnits: 1,
      side: THREE.DoubleSide,
    });
    const wire = new THREE.Mesh(
        object.geometry,
        new THREE.MeshBasicMaterial({ color: WIRE_COLOUR, wireframe: true }));
    wire.visible = false;
    object.add(wire);
    return { object, wire, textured, shaded, fill };
  });
}

function countElements(meshes) {
  let vertices = 0;
  let faces = 0;
  for (const { object } of meshes) {
    const geometry = object.geometry;
    vertices += geometry.attributes.position.count;
    faces += (geometry.index ? geometry.index.count
                             : geometry.attributes.position.count) / 3;
  }
  return { vertices, faces };
}

function main() {
  setStatus('loading');
  const config = readConfig();
  const { ui, info } = buildPage(config.title);

  const renderer = new THREE.WebGLRenderer({
    antialias: true,
    // Keeps the last frame for screenshots taken between draws.
    preserveDrawingBuffer: true,
  });
  renderer.setPixelRatio(window.devicePixelRatio);
  renderer.setSize(window.innerWidth, window.innerHeight);
  renderer.setClearColor(BACKGROUND);
  body.prepend(renderer.domElement);
  const anaglyph = new AnaglyphEffect(renderer,
                                      window.innerWidth,
                                      window.innerHeight);

  const scene = new THREE.Scene();
  const [e1, e2, up] = viewFrame(config.upAxis);
  const camera = new THREE.PerspectiveCamera(
      40, window.innerWidth / window.innerHeight, 0.01, 1000);
  // Keeps the horizontal field of view (bayon render's convention) whatever
  // the window's shape.
  function setAspect(aspect) {
    const horizontal = THREE.MathUtils.degToRad(config.fovDeg);
    camera.aspect = aspect;
    camera.fov = THREE.MathUtils.radToDeg(
        2 * Math.atan(Math.tan(horizontal / 2) / aspect));
    camera.updateProjectionMatrix();
  }
  setAspect(window.innerWidth / window.innerHeight);
  camera.up.copy(up);
  scene.add(camera);
  // A headlight from above left of the viewer, and some ambient light, for
  // the shaded mode (the other modes are unlit).
  scene.add(new THREE.AmbientLight(0xffffff, 0.45));
  const headlight = new THREE.DirectionalLight(0xffffff, 2.2);
  headlight.position.set(-0.4, 0.5, 1.0);
  camera.add(headlight);
  camera.add(headlight.target);
  headlight.target.position.set(0, 0, -1);

  const controls = new OrbitControls(camera, renderer.domElement);
  controls.enableDamping = false;

  let meshes = [];
  let mode = config.mode;
  let points = [];  // the model's vertices in the scene's frame
  let centre = null;  // of their bounding box
  // Until the user moves the camera, a resized window is framed anew (the
  // first view is then the same at any window size; headless browsers also
  // resize the page before they take a screenshot).
  let userMoved = false;
  controls.addEventListener('start', () => {
    userMoved = true;
  });

  function draw() {
    if (mode === 'anaglyph') {
      anaglyph.eyeSep = camera.position.distanceTo(controls.target) / 30;
      anaglyph.planeDistance = camera.position.distanceTo(controls.target);
      anaglyph.render(scene, camera);
    } else {
      renderer.render(scene, camera);
    }
  }

  function setMode(name) {
    if (!MODES.includes(name)) {
      throw new Error(`unknown mode '${name}' (one of ${MODES.join(', ')})`);
    }
    mode = name;
    for (const m of meshes) {
      const wireframe = name === 'wireframe';
      m.object.material = wireframe ? m.fill
                          : name === 'shaded' ? m.shaded : m.textured;
      m.wire.visible = wireframe;
    }
    for (const button of ui.querySelectorAll('button')) {
      button.classList.toggle('active', button.dataset.mode === name);
    }
    body.dataset.mode = name;
    draw();
  }

  // Looks at `centre` from (azimuth, elevation) at the smallest distance at
  // which every vertex lies inside the share FILL of the window: a point p
  // (relative to the centre, in camera axes x right, y up, z towards the
  // camera) at camera distance d is inside when |p.x| <= tan_x (d - p.z)
  // and |p.y| <= tan_y (d - p.z).
  function setView(azimuthDeg, elevationDeg, centre) {
    const az = THREE.MathUtils.degToRad(azimuthDeg);
    const el = THREE.MathUtils.degToRad(elevationDeg);
    const tanY = FILL * Math.tan(THREE.MathUtils.degToRad(camera.fov) / 2);
    const tanX = tanY * camera.aspect;
    const direction = new THREE.Vector3()
                          .addScaledVector(e1, Math.cos(el) * Math.cos(az))
                          .addScaledVector(e2, Math.cos(el) * Math.sin(az))
                          .addScaledVector(up, Math.sin(el));
    camera.position.copy(centre).add(direction);
    camera.lookAt(centre);
    camera.updateMatrixWorld();
    const [xAxis, yAxis, zAxis] = [new THREE.Vector3(), new THREE.Vector3(),
                                   new THREE.Vector3()];
    camera.matrixWorld.extractBasis(xAxis, yAxis, zAxis);
    let distance = 0;
    let extent = 0;
    const p = new THREE.Vector3();
    for (const point of points) {
      p.subVectors(point, centre);
      const z = p.dot(zAxis);
      distance = Math.max(distance,
                          Math.abs(p.dot(xAxis)) / tanX + z,
                          Math.abs(p.dot(yAxis)) / tanY + z);
      extent = Math.max(extent, p.length());
    }
    // Flat models seen edge-on: keep some distance.
    distance = Math.max(distance, 1e-3 * (2 * extent + 1e-9));
    controls.target.copy(centre);
    camera.position.copy(centre).addScaledVector(direction, distance);
    // Depth range for zooming in and out from here.
    camera.near = distance / 1000;
    camera.far = 100 * distance + 2 * extent;
    controls.maxDistance = 50 * distance;
    camera.updateProjectionMatrix();
    controls.update();
  }

  const api = {
    ready: false,
    mode: () => mode,
    setMode,
    setView: (az, el) => {
      userMoved = true;
      setView(az, el, controls.target.clone());
      draw();
    },
  };
  window.bayonViewer = api;

  const element = document.getElementById('bayon-model');
  if (!element) throw new Error('the page carries no model (#bayon-model)');
  new GLTFLoader().parse(decodeBase64(element.textContent), '', (gltf) => {
    const root = gltf.scene;
    scene.add(root);
    meshes = prepareMaterials(root);
    if (meshes.length === 0) {
      fail('the model has no meshes');
      return;
    }
    root.updateMatrixWorld(true);
    const box = new THREE.Box3();
    for (const { object } of meshes) {
      const position = object.geometry.attributes.position;
      for (let i = 0; i < position.count; ++i) {
        const point = new THREE.Vector3().fromBufferAttribute(position, i)
                          .applyMatrix4(object.matrixWorld);
        points.push(point);
        box.expandByPoint(point);
      }
    }
    centre = box.getCenter(new THREE.Vector3());
    setView(config.azimuthDeg, config.elevationDeg, centre);
    controls.addEventListener('change', draw);

    const { vertices, faces } = countElements(meshes);
    body.dataset.vertices = String(vertices);
    body.dataset.faces = String(faces);
    info.textContent = `${vertices.toLocaleString('en')} vertices, ` +
                       `${faces.toLocaleString('en')} faces · drag: orbit, ` +
                       'right drag: pan, wheel: zoom · keys 1-4: mode';
    setMode(mode);
    api.ready = true;
    if (body.dataset.status !== 'error') setStatus('ready');
  }, (error) => fail('cannot read the model: ' + (error.message || error)));

  ui.addEventListener('click', (event) => {
    const name = event.target.dataset && event.target.dataset.mode;
    if (name) setMode(name);
  });
  window.addEventListener('keydown', (event) => {
    const index = Number(event.key) - 1;
    if (index >= 0 && index < MODES.length) setMode(MODES[index]);
  });
  window.addEventListener('resize', () => {
    setAspect(window.innerWidth / window.innerHeight);
    if (centre && !userMoved) {
      setView(config.azimuthDeg, config.elevationDeg, centre);
    }
    renderer.setSize(window.innerWidth, window.innerHeight);
    anaglyph.setSize(window.innerWidth, window.innerHeight);
    draw();
  });
}

try {
  main();
} catch (error) {
  fail(error.message || String(error));
}
