// mebake viewer: loads data/view.json, the light map and vector-irradiance maps of every
// atlas page (half floats, web_data.h), then the mesh chunks one after another, drawing as they arrive.
// URL parameters (all optional), the same as `mebake render`'s options:
//   eye=x,y,z target=x,y,z up=x,y,z fov=deg   camera (default: render's default view)
//   mode=lightmap|diffuse|glossy exposure=EV tonemap=filmic|reinhard|clamp
//   background=r,g,b (radiance of the background; default: the scene's sky)
//   exponent=k weight=w (override every material's glossy lobe) borders=1 leaves=1 ui=0
// window.mebakeView reports progress to tests and benchmarks (moduleMs: this module (and
// three.js) loaded and running; lightMapMs, mapsMs: light
// maps, all maps decoded; firstFrameMs: first chunk drawn (in light-map mode while the
// E maps decode), readyMs: all drawn; from navigation start; frames) and measureFrameTime(n) times n redraws.
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { MeshoptDecoder } from 'three/addons/libs/meshopt_decoder.module.js';

const state = { moduleMs: performance.now(), lightMapMs: null, mapsMs: null, firstFrameMs: null, readyMs: null, frames: 0, chunksLoaded: 0, error: null };
window.mebakeView = state;

const params = new URLSearchParams(location.search);
const MODES = { lightmap: 0, diffuse: 1, glossy: 2 };
const CURVES = { filmic: 0, reinhard: 1, clamp: 2 };

function vec3Param(name) {
  const s = params.get(name);
  if (!s) return null;
  const v = s.split(/[ ,]+/).map(Number);
  if (v.length !== 3 || v.some((x) => !Number.isFinite(x)))
    throw new Error(`URL parameter ${name}=${s}: expected three numbers x,y,z`);
  return new THREE.Vector3(v[0], v[1], v[2]);
}

async function fetchText(url) {
  const r = await fetch(url);
  if (!r.ok) throw new Error(`${url}: HTTP ${r.status}`);
  return r.text();
}

// A map page (web_data.h): inflated by the browser, then the byte deltas summed and the
// byte planes (low, high byte of R, G, B, A) interleaved back into RGBA half floats, rows
// from the top. Row 0 at t = 0 puts glTF's top-left uv origin right.
async function loadHalfMap(url, page) {
  const r = await fetch(url);
  if (!r.ok) throw new Error(`${url}: HTTP ${r.status}`);
  const planes = new Uint8Array(
    await new Response(r.body.pipeThrough(new DecompressionStream('deflate'))).arrayBuffer());
  const texels = page.width * page.height;
  if (planes.length !== 8 * texels)
    throw new Error(`${url}: ${planes.length} bytes, expected ${8 * texels} (${page.width}x${page.height} RGBA half)`);
  for (let i = 1; i < planes.length; ++i) planes[i] = (planes[i] + planes[i - 1]) & 255;
  const bytes = new Uint8Array(8 * texels);
  for (let c = 0; c < 4; ++c) {
    const lo = planes.subarray(c * texels), hi = planes.subarray((4 + c) * texels);
    for (let t = 0, o = 2 * c; t < texels; ++t, o += 8) {
      bytes[o] = lo[t];
      bytes[o + 1] = hi[t];
    }
  }
  const t = new THREE.DataTexture(new Uint16Array(bytes.buffer), page.width, page.height,
                                  THREE.RGBAFormat, THREE.HalfFloatType);
  t.minFilter = THREE.LinearFilter;
  t.magFilter = THREE.LinearFilter;
  t.generateMipmaps = false;
  t.wrapS = t.wrapT = THREE.ClampToEdgeWrapping;
  t.needsUpdate = true;
  return t;
}

const ui = {};
for (const id of ['mode', 'exposure', 'exposureValue', 'tonemap', 'override', 'exponent',
                  'exponentValue', 'weight', 'weightValue', 'borders', 'leaves', 'status', 'panel'])
  ui[id] = document.getElementById(id);

const settings = {
  mode: params.get('mode') || 'glossy',
  exposure: Number(params.get('exposure') || 0),
  tonemap: params.get('tonemap') || 'filmic',
  override: params.has('exponent') || params.has('weight'),
  exponent: Number(params.get('exponent') || 30),
  weight: Number(params.get('weight') || 0.2),
  borders: params.get('borders') === '1',
  leaves: params.get('leaves') === '1',
};
if (!(settings.mode in MODES)) throw new Error(`mode=${settings.mode}: expected lightmap, diffuse or glossy`);
if (!(settings.tonemap in CURVES)) throw new Error(`tonemap=${settings.tonemap}: expected filmic, reinhard or clamp`);
if (params.get('ui') === '0') ui.panel.style.display = 'none';

const renderer = new THREE.WebGLRenderer({ antialias: false, preserveDrawingBuffer: true });
renderer.setPixelRatio(1);  // one shaded sample per pixel, as `mebake render --samples 1`
renderer.setSize(window.innerWidth, window.innerHeight);
renderer.autoClear = true;
document.body.appendChild(renderer.domElement);

const scene = new THREE.Scene();
const camera = new THREE.PerspectiveCamera(50, window.innerWidth / window.innerHeight);
const controls = new OrbitControls(camera, renderer.domElement);
const surfaces = [];  // RawShaderMaterials of the surfaces
const borders = [];   // chart outline line segments
let sky = null;
let irradianceReady = false;  // until then surfaces show the light map
let needsDraw = true;

function applySettings() {
  for (const m of surfaces) {
    m.uniforms.mode.value = irradianceReady ? MODES[settings.mode] : MODES.lightmap;
    m.uniforms.leaves.value = settings.leaves;
    // Surfaces a little behind their depth so that chart borders drawn on them show; only
    // then, as the slope-scaled offset can let a back face win at a silhouette.
    m.polygonOffset = settings.borders;
    m.uniforms.exposure.value = settings.exposure;
    m.uniforms.curve.value = CURVES[settings.tonemap];
    const own = m.userData.mebake;
    m.uniforms.glossyExponent.value = settings.override ? settings.exponent : own.glossy_exponent;
    m.uniforms.glossyWeight.value = settings.override ? settings.weight : own.glossy_weight;
  }
  if (sky) {
    sky.material.uniforms.exposure.value = settings.exposure;
    sky.material.uniforms.curve.value = CURVES[settings.tonemap];
  }
  for (const b of borders) b.visible = settings.borders;
  ui.exposureValue.textContent = settings.exposure.toFixed(1);
  ui.exponentValue.textContent = settings.exponent.toFixed(0);
  ui.weightValue.textContent = settings.weight.toFixed(2);
  needsDraw = true;
}

function bindUi() {
  ui.mode.value = settings.mode;
  ui.exposure.value = settings.exposure;
  ui.tonemap.value = settings.tonemap;
  ui.override.checked = settings.override;
  ui.exponent.value = settings.exponent;
  ui.weight.value = settings.weight;
  ui.borders.checked = settings.borders;
  ui.leaves.checked = settings.leaves;
  ui.mode.onchange = () => { settings.mode = ui.mode.value; applySettings(); };
  ui.tonemap.onchange = () => { settings.tonemap = ui.tonemap.value; applySettings(); };
  ui.exposure.oninput = () => { settings.exposure = Number(ui.exposure.value); applySettings(); };
  ui.override.onchange = () => { settings.override = ui.override.checked; applySettings(); };
  ui.exponent.oninput = () => { settings.exponent = Number(ui.exponent.value); settings.override = ui.override.checked = true; applySettings(); };
  ui.weight.oninput = () => { settings.weight = Number(ui.weight.value); settings.override = ui.override.checked = true; applySettings(); };
  ui.borders.onchange = () => { settings.borders = ui.borders.checked; applySettings(); };
  ui.leaves.onchange = () => { settings.leaves = ui.leaves.checked; applySettings(); };
}

function setupCamera(view) {
  const def = view.camera;
  const eye = vec3Param('eye') || new THREE.Vector3(...def.eye);
  const target = vec3Param('target') || new THREE.Vector3(...def.target);
  const up = vec3Param('up') || new THREE.Vector3(...def.up);
  const fov = Number(params.get('fov') || def.fov);
  if (!(fov > 0 && fov < 180)) throw new Error(`fov=${params.get('fov')}: expected (0, 180) degrees`);
  const lo = new THREE.Vector3(...view.bbox[0]), hi = new THREE.Vector3(...view.bbox[1]);
  const radius = Math.max(0.5 * lo.distanceTo(hi), 1e-9);
  const far = eye.distanceTo(lo.clone().add(hi).multiplyScalar(0.5)) + 2 * radius;
  camera.fov = fov;
  camera.near = far * 1e-4;
  camera.far = far * 4;
  camera.up.copy(up.normalize());
  camera.position.copy(eye);
  controls.target.copy(target);
  camera.lookAt(target);
  camera.updateProjectionMatrix();
  controls.update();
  controls.addEventListener('change', () => { needsDraw = true; });
}

function makeSky(view, shaders) {
  const bg = vec3Param('background');
  const type = bg ? 1 : { none: 0, uniform: 1, overcast: 2 }[view.sky.type];
  const geometry = new THREE.BufferGeometry();
  geometry.setAttribute('position', new THREE.Float32BufferAttribute([-1, -1, 0, 3, -1, 0, -1, 3, 0], 3));
  const material = new THREE.RawShaderMaterial({
    glslVersion: THREE.GLSL3,
    vertexShader: shaders.skyVert,
    fragmentShader: shaders.skyFrag,
    depthWrite: false,
    depthTest: false,
    uniforms: {
      forward: { value: new THREE.Vector3() }, right: { value: new THREE.Vector3() },
      up: { value: new THREE.Vector3() }, skyType: { value: type },
      skyRadiance: { value: bg || new THREE.Vector3(...view.sky.radiance) },
      skyUp: { value: new THREE.Vector3(...view.sky.up) },
      exposure: { value: 0 }, curve: { value: 0 },
    },
  });
  const mesh = new THREE.Mesh(geometry, material);
  mesh.frustumCulled = false;
  mesh.renderOrder = -1;
  scene.add(mesh);
  return mesh;
}

function updateSky() {
  // The ray of NDC (x, y): forward + right tan(fov/2) aspect x + up tan(fov/2) y, as
  // render.cpp builds its primary rays.
  const u = sky.material.uniforms;
  const t = Math.tan(THREE.MathUtils.degToRad(camera.fov) / 2);
  camera.getWorldDirection(u.forward.value);
  u.right.value.crossVectors(u.forward.value, camera.up).normalize();
  u.up.value.crossVectors(u.right.value, u.forward.value);
  u.right.value.multiplyScalar(t * camera.aspect);
  u.up.value.multiplyScalar(t);
}

function setIrradiance(m, textures) {
  const page = textures[m.userData.mebake.page];
  m.uniforms.irradianceX.value = page.x;
  m.uniforms.irradianceY.value = page.y;
  m.uniforms.irradianceZ.value = page.z;
}

function surfaceMaterial(extras, textures, shaders, hasColor, radiosity) {
  const page = textures[extras.page];
  const m = new THREE.RawShaderMaterial({
    glslVersion: THREE.GLSL3,
    vertexShader: shaders.vert,
    fragmentShader: shaders.frag,
    side: THREE.DoubleSide,
    polygonOffsetFactor: 1, polygonOffsetUnits: 1,
    defines: hasColor ? { HAS_COLOR: 1 } : {},
    uniforms: {
      // The light map stands in for E until the irradiance maps are decoded.
      lightMap: { value: page.lightmap }, irradianceX: { value: page.x || page.lightmap },
      irradianceY: { value: page.y || page.lightmap }, irradianceZ: { value: page.z || page.lightmap },
      mode: { value: 2 }, radiosity: { value: radiosity }, exposure: { value: 0 },
      curve: { value: 0 }, eye: { value: new THREE.Vector3() },
      albedo: { value: new THREE.Vector3(...extras.albedo) },
      emission: { value: new THREE.Vector3(...extras.emission) },
      useVertexColors: { value: extras.use_vertex_colors },
      colorFactor: { value: extras.color_factor },
      glossyExponent: { value: extras.glossy_exponent },
      glossyWeight: { value: extras.glossy_weight },
      leaves: { value: false },
    },
  });
  m.userData.mebake = extras;
  return m;
}

function addChunk(gltf, textures, shaders, radiosity) {
  gltf.scene.traverse((o) => {
    const extras = o.material ? o.material.userData : null;
    if (!extras) return;
    if (o.isLineSegments) {
      o.material = new THREE.LineBasicMaterial({ color: 0xff3080 });
      o.visible = settings.borders;
      borders.push(o);
    } else if (o.isMesh) {
      o.material = surfaceMaterial(extras, textures, shaders, !!o.geometry.attributes.color, radiosity);
      surfaces.push(o.material);
    }
  });
  scene.add(gltf.scene);
  applySettings();
}

function draw() {
  updateSky();
  for (const m of surfaces) m.uniforms.eye.value.copy(camera.position);
  renderer.render(scene, camera);
  state.frames++;
}

function loop() {
  if (needsDraw) {
    needsDraw = false;
    draw();
    if (state.firstFrameMs === null && state.chunksLoaded > 0) state.firstFrameMs = performance.now();
  }
  requestAnimationFrame(loop);
}

// Times n full redraws, each waited for by reading a pixel back (software GL has no
// faster fence). Milliseconds per frame.
state.measureFrameTime = (n) => {
  const gl = renderer.getContext();
  const px = new Uint8Array(4);
  draw();
  gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, px);
  const t0 = performance.now();
  for (let i = 0; i < n; ++i) {
    draw();
    gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, px);
  }
  return (performance.now() - t0) / n;
};

async function main() {
  bindUi();
  const [view, vert, frag, skyVert, skyFrag] = await Promise.all([
    fetch('data/view.json').then((r) => {
      if (!r.ok) throw new Error(`data/view.json: HTTP ${r.status}`);
      return r.json();
    }),
    fetchText('shade.vert'), fetchText('shade.frag'), fetchText('sky.vert'), fetchText('sky.frag')]);
  const shaders = { vert, frag, skyVert, skyFrag };
  setupCamera(view);
  sky = makeSky(view, shaders);
  applySettings();
  requestAnimationFrame(loop);

  // The light maps first: chunks are drawn in light-map mode as soon as they arrive, while
  // the vector-irradiance maps (three times the data) are still decoding.
  ui.status.textContent = `loading light map (${view.pages.length} page${view.pages.length > 1 ? 's' : ''})`;
  const textures = await Promise.all(view.pages.map(async (page, p) => ({
    lightmap: await loadHalfMap(`data/lightmap.${p}.half`, page), x: null, y: null, z: null })));
  state.lightMapMs = performance.now();
  const irradiance = Promise.all(view.pages.map(async (page, p) => {
    const [x, y, z] = await Promise.all(['E.x', 'E.y', 'E.z'].map((n) => loadHalfMap(`data/${n}.${p}.half`, page)));
    Object.assign(textures[p], { x, y, z });
  })).then(() => {
    for (const m of surfaces) setIrradiance(m, textures);
    irradianceReady = true;
    state.mapsMs = performance.now();
    applySettings();
  });
  const loader = new GLTFLoader();
  loader.setMeshoptDecoder(MeshoptDecoder);
  const radiosity = view.unknown === 'radiosity';
  // Chunks in order, the next one fetched while the last is decoded and drawn.
  let next = loader.loadAsync(`data/${view.chunks[0]}`);
  for (let i = 0; i < view.chunks.length; ++i) {
    const gltf = await next;
    if (i + 1 < view.chunks.length) next = loader.loadAsync(`data/${view.chunks[i + 1]}`);
    addChunk(gltf, textures, shaders, radiosity);
    state.chunksLoaded = i + 1;
    ui.status.textContent = `${view.triangles.toLocaleString()} triangles: chunk ${i + 1} of ${view.chunks.length}`;
  }
  await irradiance;
  // Ready once a frame with every chunk and every map has been drawn.
  needsDraw = true;
  await new Promise((resolve) => {
    const wait = () => (needsDraw ? requestAnimationFrame(wait) : resolve());
    requestAnimationFrame(wait);
  });
  state.readyMs = performance.now();
  ui.status.textContent = `${view.triangles.toLocaleString()} triangles, ${view.charts} charts`;
}

window.addEventListener('resize', () => {
  camera.aspect = window.innerWidth / window.innerHeight;
  camera.updateProjectionMatrix();
  renderer.setSize(window.innerWidth, window.innerHeight);
  needsDraw = true;
});

main().catch((e) => {
  state.error = String(e && e.message ? e.message : e);
  ui.status.textContent = `error: ${state.error}`;
  console.error(e);
});
