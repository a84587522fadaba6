// The 3D view: branches as instanced cylinders drawn straight from the skeleton's
// typed arrays (a vertex shader places each unit cylinder between a node and its
// parent, scaled by the node's radius), solid obstacles as translucent boxes or
// prisms (a footprint with its holes, extruded over its z range) and clearance
// zones as fainter amber ones, the internodes inside a zone in a colour of their
// own, the stems of a stand that died (their snags) in bark grey, the ground with
// a 1 m grid and labelled scales, a light-slice heat map,
// orbit/front/side/top cameras and a compass that turns with them. The scene's
// axes are the model's (x east, y north, z up): world points go in as they are.
// The leaves (leaves.mjs) are lit by a sky light and a sun straight above (the
// zenith sky of the model's light), which casts the crown's shadow on the ground,
// under a sky-coloured background. The view measures its frames (frameMs: the time
// between two frames drawn one after the other) and lowers the leaves' budget
// of instances when they are slow.
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { isZone, markInZones, zonesOf } from './zones.mjs';
import { markDeadStems } from './stand.mjs';
import { Leaves } from './leaves.mjs';
import { stemShapes } from './stems.mjs';
import { LEAF_BUDGET, LEAF_BUDGET_MIN } from './foliage.mjs';

// Frames slower than this (ms, the median of FRAME_SAMPLES in a row) halve the
// leaves' budget, down to LEAF_BUDGET_MIN.
const FRAME_TARGET_MS = 50;
const FRAME_SAMPLES = 9;
const SKY_TOP = '#8ec3ec';
const SKY_HORIZON = '#e4f1fb';

// The background: a vertical gradient from the zenith's blue to a pale horizon.
function skyTexture() {
  const c = document.createElement('canvas');
  c.width = 2;
  c.height = 256;
  const g = c.getContext('2d');
  const grad = g.createLinearGradient(0, 0, 0, 256);
  grad.addColorStop(0, SKY_TOP);
  grad.addColorStop(1, SKY_HORIZON);
  g.fillStyle = grad;
  g.fillRect(0, 0, 2, 256);
  const t = new THREE.CanvasTexture(c);
  t.colorSpace = THREE.SRGBColorSpace;
  return t;
}

// The order of the opaque things drawn: the ground and its grid, then the
// see-through boxes of obstacles and zones (tinting the ground behind them), then
// the branches and leaves (order 0), which draw over the boxes' tint.
const GROUND_ORDER = -2;
const SEE_THROUGH_ORDER = -1;

// A see-through mesh of a geometry (MeshBasicMaterial options, with an opacity):
// blended over what is behind it, but
// drawn among the opaque things, after the ground and before the branches and
// leaves, without writing depth, so that a tree behind a facade keeps its own
// colours. (Drawn after them as a transparent thing, a box's tint took the leaves'
// green: the street's south crowns seen from the south looked leafless.) The
// canvas stays opaque: its alpha is not blended down.
function seeThrough(geometry, options) {
  const mesh = new THREE.Mesh(geometry, new THREE.MeshBasicMaterial({ ...options, depthWrite: false,
    transparent: false, blending: THREE.CustomBlending, blendSrcAlpha: THREE.ZeroFactor, blendDstAlpha: THREE.OneFactor }));
  mesh.renderOrder = SEE_THROUGH_ORDER;
  return mesh;
}

// The geometry of an obstacle, in world coordinates: a box's, or a prism's
// footprint (its polygon, its holes as paths; three.js's triangulation winds each
// ring as it needs) extruded from z[0] to z[1]. At least 1 mm along each axis.
function obstacleGeometry(o) {
  if (!o.polygon) {
    const size = [0, 1, 2].map((i) => Math.max(o.max[i] - o.min[i], 1e-3));
    return new THREE.BoxGeometry(...size).translate(...[0, 1, 2].map((i) => (o.min[i] + o.max[i]) / 2));
  }
  const ring = (pts) => pts.map(([x, y]) => new THREE.Vector2(x, y));
  const shape = new THREE.Shape(ring(o.polygon));
  for (const h of o.holes || []) shape.holes.push(new THREE.Path(ring(h)));
  const geo = new THREE.ExtrudeGeometry(shape, { depth: Math.max(o.z[1] - o.z[0], 1e-3), bevelEnabled: false });
  return geo.translate(0, 0, o.z[0]);
}

// The compass in a corner of the view: an arrow with an N, turned as north lies
// from the camera (see View.updateCompass).
const SVG_NS = 'http://www.w3.org/2000/svg';
// (a red with some green in it: the tests count the zone highlight's deeper red,
// ZONE_NODE_COLOR, in screenshots of the view, which show the compass too)
const NEEDLE_RED = '#d9534f';
function compassElement() {
  const el = (name, attrs) => {
    const e = document.createElementNS(SVG_NS, name);
    for (const [k, v] of Object.entries(attrs)) e.setAttribute(k, v);
    return e;
  };
  const svg = el('svg', { class: 'compass', viewBox: '-24 -24 48 48', role: 'img', 'aria-label': 'north' });
  const title = el('title', {});
  title.textContent = 'north';
  const n = el('text', { x: 0, y: -15, 'text-anchor': 'middle', 'font-size': 10, 'font-weight': 700, fill: '#333' });
  n.textContent = 'N';
  const needle = el('g', {});
  needle.append(el('circle', { r: 13, fill: '#fffc', stroke: '#8a8a8a', 'stroke-width': 1 }),
    el('path', { d: 'M0 11 L4 0 L-4 0 Z', fill: '#9a9a9a' }),
    el('path', { d: 'M0 -11 L4 0 L-4 0 Z', fill: NEEDLE_RED }), n);
  svg.append(title, needle);
  return svg;
}

// One colour per plant (by its index in the snapshot), shared with the plots.
export const PALETTE = ['#2e8b3a', '#c46a1b', '#2f6fb3', '#b8326e', '#7d5bb5', '#1a9a8f', '#a08a12',
  '#d04a3a', '#4f7d1f', '#8a4b2a', '#3d8fd1', '#c27bb0'];
export const plantColor = (i) => PALETTE[i % PALETTE.length];
// Clearance zones (translucent boxes) and the internodes inside one.
export const ZONE_COLOR = '#f0a020';
export const ZONE_NODE_COLOR = '#e8112d';
// A dead stem's snag (stand.mjs), whatever its plant's colour; the zone colour
// still marks its internodes inside a zone.
export const DEAD_COLOR = '#8c8780';

const VERTEX = `
attribute vec3 aStart;
attribute vec3 aEnd;
attribute float aRadius;
attribute float aPlant;
attribute float aZone;       // 1 + the index of the zone the node is in, 0 for none
attribute float aDead;       // 1: the node's stem is dead
uniform vec3 uPalette[${PALETTE.length}];
uniform vec3 uZoneColor;
uniform vec3 uDeadColor;
uniform float uPixelPersp;   // world size of a pixel per unit of distance (perspective)
uniform float uPixelOrtho;   // world size of a pixel (orthographic)
uniform float uMinPixels;    // thinnest drawn radius, pixels
varying vec3 vNormal;
varying vec3 vColor;
void main() {
  vec3 axis = aEnd - aStart;
  float len = length(axis);
  vec3 dir = len > 1e-9 ? axis / len : vec3(0.0, 0.0, 1.0);
  vec3 helper = abs(dir.z) < 0.9 ? vec3(0.0, 0.0, 1.0) : vec3(1.0, 0.0, 0.0);
  vec3 u = normalize(cross(helper, dir));
  vec3 v = cross(dir, u);
  vec3 mid = 0.5 * (aStart + aEnd);
  float dist = length((modelViewMatrix * vec4(mid, 1.0)).xyz);
  float r = max(aRadius, uMinPixels * (uPixelPersp * dist + uPixelOrtho));
  r = len > 1e-9 ? r : 0.0;   // a root has no branch of its own
  vec3 p = aStart + axis * (position.y + 0.5) + (u * position.x + v * position.z) * r;
  vNormal = normalize(normalMatrix * (u * normal.x + v * normal.z));
  int k = int(aPlant + 0.5) - ${PALETTE.length} * (int(aPlant + 0.5) / ${PALETTE.length});
  vColor = aZone > 0.5 ? uZoneColor : aDead > 0.5 ? uDeadColor : uPalette[k];
  gl_Position = projectionMatrix * modelViewMatrix * vec4(p, 1.0);
}`;

const FRAGMENT = `
varying vec3 vNormal;
varying vec3 vColor;
void main() {
  vec3 n = normalize(vNormal);
  float light = 0.55 + 0.45 * max(dot(n, normalize(vec3(0.4, 0.5, 0.8))), 0.0);
  gl_FragColor = vec4(vColor * light, 1.0);
  #include <colorspace_fragment>
}`;

// The stems of a skeleton of `detail` "stems" (stems.mjs): a trunk and a crown
// each, in two instanced meshes made again from its stats at every show (a few
// hundred stems); nothing for a skeleton of nodes.
class StemModels {
  constructor(scene) {
    this.group = new THREE.Group();
    scene.add(this.group);
    this.trunkGeometry = new THREE.CylinderGeometry(1, 1, 1, 8).rotateX(Math.PI / 2).translate(0, 0, 0.5);
    this.crownGeometry = new THREE.SphereGeometry(1, 16, 10);
    this.trunkMaterial = new THREE.MeshLambertMaterial({ color: 0x6b4f35 });
    this.crownMaterial = new THREE.MeshLambertMaterial({ color: 0xffffff });
    this.trunks = 0;   // drawn
    this.crowns = 0;
  }

  sync(sk) {
    for (const m of this.group.children) m.dispose();
    this.group.clear();
    const shapes = sk.detail === 'stems' ? stemShapes(sk.plants, sk.stats, sk.plantIndex) : [];
    const crowned = shapes.filter((s) => s.crownRadius > 0);
    this.trunks = shapes.length;
    this.crowns = crowned.length;
    if (!shapes.length) return;
    const m = new THREE.Matrix4(), q = new THREE.Quaternion(), p = new THREE.Vector3(), s = new THREE.Vector3();
    const trunks = new THREE.InstancedMesh(this.trunkGeometry, this.trunkMaterial, shapes.length);
    shapes.forEach((t, i) => {
      const [x, y, z] = t.root;
      trunks.setMatrixAt(i, m.compose(p.set(x, y, z), q, s.set(t.trunkRadius, t.trunkRadius, Math.max(t.height, 1e-3))));
      trunks.setColorAt(i, new THREE.Color(t.dead ? DEAD_COLOR : 0x6b4f35));
    });
    trunks.name = 'stems:trunks';
    this.group.add(trunks);
    if (!crowned.length) return;
    const crowns = new THREE.InstancedMesh(this.crownGeometry, this.crownMaterial, crowned.length);
    crowned.forEach((c, i) => {
      const [x, y, z] = c.root, half = (c.height - c.crownBase) / 2;
      crowns.setMatrixAt(i, m.compose(p.set(x, y, z + c.crownBase + half), q, s.set(c.crownRadius, c.crownRadius, half)));
      crowns.setColorAt(i, new THREE.Color(plantColor(c.plant)));
    });
    crowns.name = 'stems:crowns';
    crowns.castShadow = true;
    this.group.add(crowns);
  }
}

// Branches of one skeleton: the GPU buffers follow the skeleton's arrays.
class Branches {
  constructor(scene, material) {
    this.scene = scene;
    this.material = material;
    this.version = -1;
    this.mesh = null;
    this.sk = null;   // the skeleton the buffers follow
    this.start = null;
    this.end = null;
    this.radius = null;
    this.plant = null;
    this.zone = null;       // the aZone attribute: its array is the page's own (zones.mjs)
    this.zones = [];        // the zones the marks are of
    this.zonesDirty = false; // the zones changed since the marks were made
    this.dead = null;       // the aDead attribute: 1 for a slot of a dead stem (stand.mjs)
    this.deadVersion = -1;  // the skeleton's deadVersion the marks are of
  }

  // The clearance zones whose internodes are drawn in the zone colour.
  setZones(zones) {
    this.zones = zones;
    this.zonesDirty = true;
  }

  // Internodes drawn in the zone colour (the marks of the live slots).
  highlighted() {
    if (!this.sk || !this.zone) return 0;
    const a = this.zone.array;
    let n = 0;
    for (let k = 0, count = this.sk.count; k < count; k++) if (a[k] > 0) n++;
    return n;
  }

  // Internodes drawn grey (dead stems' marks, as uploaded), by plant id.
  greyed() {
    const out = {};
    if (!this.sk || !this.dead) return out;
    const a = this.dead.array, { plant, plants } = this.sk;
    for (let k = 0, count = this.sk.count; k < count; k++) {
      if (a[k] === 0) continue;
      const id = plants[plant[k]]?.id ?? String(plant[k]);
      out[id] = (out[id] || 0) + 1;
    }
    return out;
  }

  rebuild(sk) {
    if (this.mesh) {
      this.scene.remove(this.mesh);
      this.mesh.geometry.dispose();
    }
    const base = new THREE.CylinderGeometry(1, 1, 1, 6, 1, true);
    const g = new THREE.InstancedBufferGeometry();
    g.index = base.index;
    g.setAttribute('position', base.getAttribute('position'));
    g.setAttribute('normal', base.getAttribute('normal'));
    this.start = new THREE.InstancedBufferAttribute(sk.start, 3);
    this.end = new THREE.InstancedBufferAttribute(sk.end, 3);
    this.radius = new THREE.InstancedBufferAttribute(sk.radius, 1);
    this.plant = new THREE.InstancedBufferAttribute(sk.plant, 1);
    const marks = new Float32Array(sk.capacity);
    markInZones(sk.end, sk.dead, 0, sk.count, this.zones, marks);
    this.zonesDirty = false;
    this.zone = new THREE.InstancedBufferAttribute(marks, 1);
    const dead = new Float32Array(sk.capacity);
    markDeadStems(sk.plant, sk.stem, sk.dead, 0, sk.count, sk.deadStems, dead);
    this.deadVersion = sk.deadVersion;
    this.dead = new THREE.InstancedBufferAttribute(dead, 1);
    for (const a of [this.start, this.end, this.radius, this.plant, this.zone, this.dead]) a.setUsage(THREE.DynamicDrawUsage);
    g.setAttribute('aStart', this.start);
    g.setAttribute('aEnd', this.end);
    g.setAttribute('aRadius', this.radius);
    g.setAttribute('aPlant', this.plant);
    g.setAttribute('aZone', this.zone);
    g.setAttribute('aDead', this.dead);
    g.instanceCount = sk.count;
    this.mesh = new THREE.Mesh(g, this.material);
    this.mesh.frustumCulled = false;
    this.scene.add(this.mesh);
    this.version = sk.version;
    this.sk = sk;
  }

  // Uploads what changed since the last sync: the moved and added slots, and the
  // radii (changed radii are spread over the skeleton, so all of them go up); the
  // zone marks of the changed slots, or of every slot when the zones changed; the
  // dead stems' marks likewise, of every slot when a stem died.
  sync(sk) {
    if (this.sk !== sk || this.version !== sk.version) {
      this.rebuild(sk);
      sk.takeChanges();
      return;
    }
    const from = sk.takeChanges();
    const n = sk.count;
    for (const [attr, size] of [[this.start, 3], [this.end, 3], [this.plant, 1]]) {
      attr.clearUpdateRanges();
      if (from < n) {
        attr.addUpdateRange(from * size, (n - from) * size);
        attr.needsUpdate = true;
      }
    }
    this.radius.clearUpdateRanges();
    this.radius.addUpdateRange(0, n);
    this.radius.needsUpdate = true;
    const zfrom = this.zonesDirty ? 0 : from;
    this.zonesDirty = false;
    this.zone.clearUpdateRanges();
    if (zfrom < n) {
      markInZones(sk.end, sk.dead, zfrom, n, this.zones, this.zone.array);
      this.zone.addUpdateRange(zfrom, n - zfrom);
      this.zone.needsUpdate = true;
    }
    const dfrom = this.deadVersion !== sk.deadVersion ? 0 : from;
    this.deadVersion = sk.deadVersion;
    this.dead.clearUpdateRanges();
    if (dfrom < n) {
      markDeadStems(sk.plant, sk.stem, sk.dead, dfrom, n, sk.deadStems, this.dead.array);
      this.dead.addUpdateRange(dfrom, n - dfrom);
      this.dead.needsUpdate = true;
    }
    this.mesh.geometry.instanceCount = n;
  }
}

function label(text, size = 0.35) {
  const c = document.createElement('canvas');
  c.width = 128;
  c.height = 64;
  const g = c.getContext('2d');
  g.font = '36px system-ui, sans-serif';
  g.fillStyle = '#333';
  g.textAlign = 'center';
  g.textBaseline = 'middle';
  g.fillText(text, 64, 32);
  const s = new THREE.Sprite(new THREE.SpriteMaterial({ map: new THREE.CanvasTexture(c), depthTest: false }));
  s.scale.set(size * 2, size, 1);
  return s;
}

// The colour of v (0..1) on a ramp of [position, [r, g, b]] stops.
function rampColor(stops, v) {
  for (let i = 1; i < stops.length; i++) {
    if (v <= stops[i][0]) {
      const [a, ca] = stops[i - 1], [b, cb] = stops[i];
      const t = (v - a) / (b - a);
      return ca.map((x, k) => Math.round(x + (cb[k] - x) * t));
    }
  }
  return stops[stops.length - 1][1];
}

// Colour map for light 0..1: deep blue shade through green to yellow sun.
const LIGHT_STOPS = [[0, [20, 30, 90]], [0.35, [40, 110, 160]], [0.65, [90, 180, 90]], [1, [250, 230, 80]]];
export const lightColor = (v) => rampColor(LIGHT_STOPS, v);

// Colour map for tree shade 0..1 (of the shade layer's scale): pale sand where the
// trees take no sun, through sky blue to deep violet where they take the most.
const SHADE_STOPS = [[0, [242, 236, 214]], [0.25, [170, 196, 232]], [0.6, [86, 104, 200]], [1, [52, 26, 120]]];
export const shadeColor = (v) => rampColor(SHADE_STOPS, v);

// A DataTexture of nu x nv values (u fastest, rows from the bottom), each coloured
// by shadeColor(value / scale).
function shadeTexture(values, nu, nv, scale) {
  const rgba = new Uint8Array(nu * nv * 4);
  for (let i = 0; i < nu * nv; i++) {
    const [r, g, b] = shadeColor(Math.min(1, values[i] / scale));
    rgba.set([r, g, b, 255], i * 4);
  }
  const tex = new THREE.DataTexture(rgba, nu, nv, THREE.RGBAFormat);
  tex.colorSpace = THREE.SRGBColorSpace;
  tex.magFilter = THREE.NearestFilter;
  tex.needsUpdate = true;
  return tex;
}

// How a face of the shade layer lies: the axes of its texture (u along the face,
// v up) and its outward normal, by the face's name.
const FACE_AXES = {
  '+x': [[0, 1, 0], [0, 0, 1], [1, 0, 0]], '-x': [[0, 1, 0], [0, 0, 1], [-1, 0, 0]],
  '+y': [[1, 0, 0], [0, 0, 1], [0, 1, 0]], '-y': [[1, 0, 0], [0, 0, 1], [0, -1, 0]],
};
// How far the layer's quads stand off the ground and the faces, m.
const SHADE_LIFT = 0.01;
// How a face of the shade layer lies, as FACE_AXES: from its `along` and `normal`
// (a prism's walls, and boxes' faces from a daemon that sends them), else by its
// name; null for a face the page cannot place.
function faceAxes(f) {
  if (f.along && f.normal) return [[f.along[0], f.along[1], 0], [0, 0, 1], [f.normal[0], f.normal[1], 0]];
  return FACE_AXES[f.face] ?? null;
}

export class View {
  constructor(container) {
    this.container = container;
    this.renderer = new THREE.WebGLRenderer({ antialias: true });
    this.renderer.setPixelRatio(Math.min(window.devicePixelRatio, 2));
    this.renderer.setClearColor(SKY_HORIZON);
    // the shadow map is drawn again only when the leaves or the world change
    this.renderer.shadowMap.enabled = true;
    this.renderer.shadowMap.autoUpdate = false;
    container.appendChild(this.renderer.domElement);
    this.scene = new THREE.Scene();
    this.scene.background = skyTexture();
    this.hemi = new THREE.HemisphereLight(0xeaf4ff, 0x9a9077, 2.0);
    this.hemi.position.set(0, 0, 1);   // its sky is up (z)
    this.sun = new THREE.DirectionalLight(0xffffff, 1.9);
    this.sun.castShadow = true;
    this.sun.shadow.mapSize.set(2048, 2048);
    this.sun.shadow.bias = -0.0005;
    this.scene.add(this.hemi, this.sun, this.sun.target);
    this.material = new THREE.ShaderMaterial({
      vertexShader: VERTEX, fragmentShader: FRAGMENT,
      uniforms: {
        uPalette: { value: PALETTE.map((c) => new THREE.Color(c)) },
        uZoneColor: { value: new THREE.Color(ZONE_NODE_COLOR) },
        uDeadColor: { value: new THREE.Color(DEAD_COLOR) },
        uPixelPersp: { value: 0 }, uPixelOrtho: { value: 0 }, uMinPixels: { value: 0.6 },
      },
    });
    this.branches = new Branches(this.scene, this.material);
    this.stems = new StemModels(this.scene);
    // (the leaves' work done in slices of their own: the cards drawn again, and
    // the crown's shadow)
    this.leaves = new Leaves(this.scene, () => {
      if (this.leaves.takeSettled()) this.shadowDirty = true;
      this.invalidate();
    });
    this.leafMs = 0;        // the leaves' part of the last show(), ms
    this.leafBudgetSet = false;  // the leaves' budget was set (setLeafBudget), not lowered by frames
    this.frameMs = [];      // time between two frames drawn in a row, ms
    this.shadowDirty = true;
    this.worldGroup = new THREE.Group();     // ground, grid, scales
    this.obstacleGroup = new THREE.Group();
    this.scene.add(this.worldGroup, this.obstacleGroup);
    this.persp = new THREE.PerspectiveCamera(40, 1, 0.05, 500);
    this.persp.up.set(0, 0, 1);
    this.ortho = new THREE.OrthographicCamera(-1, 1, 1, -1, -500, 500);
    this.ortho.up.set(0, 0, 1);
    this.camera = this.persp;
    this.viewName = 'persp';
    this.orthoHalf = 0;   // half the height the orthographic views show (0: not fitted to a world)
    this.controls = new OrbitControls(this.camera, this.renderer.domElement);
    this.controls.addEventListener('change', () => this.invalidate());
    this.worldKey = '';
    this.world = null;
    this.ground = null;
    this.obstacleKey = '';
    this.slice = null;
    this.shadeGroup = new THREE.Group();   // the shade layer: 'shade:ground', 'shade:OBSTACLE:FACE'
    this.scene.add(this.shadeGroup);
    // the compass: north is the world's +y (the daemon sends no other north)
    this.north = [0, 1];
    this.compass = compassElement();
    this.compassAngle = null;   // degrees clockwise on screen from up to north, as drawn
    container.appendChild(this.compass);
    this.dirty = true;
    this.frames = 0;
    this.renderMs = [];
    new ResizeObserver(() => this.resize()).observe(container);
    this.resize();
    let last = -1;   // when the frame before was drawn (-1: it was not)
    const loop = (now) => {
      requestAnimationFrame(loop);
      if (!this.dirty) {
        last = -1;
        return;
      }
      this.render();
      if (last >= 0) this.frame(now - last);
      last = now;
    };
    requestAnimationFrame(loop);
  }

  // A frame drawn right after another took ms: kept, and slow frames with leaves
  // drawn halve the leaves' budget.
  frame(ms) {
    this.frameMs.push(ms);
    if (this.frameMs.length > 200) this.frameMs.shift();
    if (this.leafBudgetSet) return;
    const l = this.leaves;
    // (not while cards are being placed: the frames are of neither stride)
    if (!l.visible || l.live === 0 || l.budget <= LEAF_BUDGET_MIN || l.pending()) return;
    this.slow = (this.slow || []).concat(ms).slice(-FRAME_SAMPLES);
    if (this.slow.length < FRAME_SAMPLES) return;
    const median = this.slow.slice().sort((a, b) => a - b)[FRAME_SAMPLES >> 1];
    if (median <= FRAME_TARGET_MS || l.live <= LEAF_BUDGET_MIN) return;
    this.slow = [];
    l.setBudget(Math.max(LEAF_BUDGET_MIN, Math.floor(l.budget / 2)));
    if (this.shown) this.show(this.shown);
  }

  // Sets the leaves' budget of cards, which slow frames then leave alone; null: the
  // default budget, halved by slow frames.
  setLeafBudget(budget) {
    this.leafBudgetSet = budget !== null;
    this.slow = [];
    this.leaves.setBudget(budget ?? LEAF_BUDGET);
    if (this.shown) this.show(this.shown);
  }

  // Turns the camera by angle (radians) around the vertical through its target.
  orbit(angle) {
    const t = this.controls.target, p = this.camera.position;
    const x = p.x - t.x, y = p.y - t.y, c = Math.cos(angle), s = Math.sin(angle);
    p.set(t.x + c * x - s * y, t.y + s * x + c * y, p.z);
    this.camera.lookAt(t);
    this.invalidate();
  }

  // Leaves drawn (true) or the bare skeleton (false).
  setLeaves(on) {
    this.leaves.setVisible(on);
    if (on && this.shown) this.show(this.shown);
    this.shadowDirty = true;
    this.invalidate();
  }

  invalidate() { this.dirty = true; }

  resize() {
    const w = Math.max(1, this.container.clientWidth), h = Math.max(1, this.container.clientHeight);
    this.renderer.setSize(w, h);
    this.persp.aspect = w / h;
    this.persp.updateProjectionMatrix();
    this.fitOrtho();
    this.invalidate();
  }

  fitOrtho() {
    const w = Math.max(1, this.container.clientWidth), h = Math.max(1, this.container.clientHeight);
    const half = this.orthoHalf || 6;
    this.ortho.left = -half * w / h;
    this.ortho.right = half * w / h;
    this.ortho.top = half;
    this.ortho.bottom = -half;
    this.ortho.updateProjectionMatrix();
  }

  render() {
    this.dirty = false;
    const h = Math.max(1, this.container.clientHeight);
    const u = this.material.uniforms;
    if (this.camera === this.persp) {
      u.uPixelPersp.value = 2 * Math.tan(THREE.MathUtils.degToRad(this.persp.fov) / 2) / h;
      u.uPixelOrtho.value = 0;
    } else {
      u.uPixelPersp.value = 0;
      u.uPixelOrtho.value = (this.ortho.top - this.ortho.bottom) / this.ortho.zoom / h;
    }
    if (this.shadowDirty) {
      this.renderer.shadowMap.needsUpdate = true;
      this.shadowDirty = false;
    }
    const t0 = performance.now();
    this.renderer.render(this.scene, this.camera);
    this.renderMs.push(performance.now() - t0);
    if (this.renderMs.length > 200) this.renderMs.shift();
    this.frames++;
    this.updateCompass();
  }

  // Turns the compass by the camera's heading: the needle points up when the
  // camera looks north and turns as the camera orbits about the vertical (the
  // azimuth only, not the tilt). The heading is the camera's forward direction
  // on the ground, or, looking straight down, its screen's up on the ground.
  updateCompass() {
    const f = this.camera.getWorldDirection(new THREE.Vector3());
    if (Math.hypot(f.x, f.y) < 1e-9) f.set(0, 1, 0).applyQuaternion(this.camera.quaternion);
    const heading = Math.atan2(f.x, f.y), north = Math.atan2(this.north[0], this.north[1]);
    let angle = THREE.MathUtils.radToDeg(north - heading) % 360;
    if (angle < 0) angle += 360;
    angle = Math.round(angle * 100) / 100;
    if (angle === this.compassAngle) return;
    this.compassAngle = angle;
    this.compass.lastElementChild.setAttribute('transform', `rotate(${angle})`);
  }

  // Shows a skeleton (the live one or a stored iteration's).
  show(sk) {
    this.setWorld(sk.world);
    this.setObstacles(sk.obstacles);
    this.branches.sync(sk);
    this.stems.sync(sk);
    if (this.stems.trunks) this.shadowDirty = true;
    this.shown = sk;
    const t0 = performance.now();
    this.leaves.sync(sk);
    if (this.leaves.takeSettled()) this.shadowDirty = true;
    this.leafMs = performance.now() - t0;
    this.invalidate();
  }

  setWorld(world) {
    if (!world) return;
    const key = JSON.stringify(world);
    if (key === this.worldKey) return;
    const first = this.worldKey === '';
    this.worldKey = key;
    this.world = world;
    this.worldGroup.clear();
    const [x0, y0] = world.min, [x1, y1, z1] = world.max;
    const ground = new THREE.Mesh(new THREE.PlaneGeometry(x1 - x0, y1 - y0),
      new THREE.MeshLambertMaterial({ color: 0xd9d2bf, side: THREE.DoubleSide }));
    ground.position.set((x0 + x1) / 2, (y0 + y1) / 2, -0.002);
    ground.name = 'ground';
    ground.receiveShadow = true;
    // the sun straight above the world's centre, its shadow camera over the whole box
    const cx = (x0 + x1) / 2, cy = (y0 + y1) / 2, sc = this.sun.shadow.camera;
    this.sun.position.set(cx, cy, z1 + 1);
    this.sun.target.position.set(cx, cy, 0);
    this.sun.target.updateMatrixWorld();
    const half = Math.max(x1 - x0, y1 - y0) / 2;
    sc.left = sc.bottom = -half;
    sc.right = sc.top = half;
    sc.near = 0.5;
    sc.far = z1 + 2 - world.min[2];
    sc.updateProjectionMatrix();
    this.shadowDirty = true;
    this.ground = ground;
    this.worldGroup.add(ground);
    // a 1 m grid over the ground
    const pts = [];
    for (let x = Math.ceil(x0); x <= x1; x++) pts.push(x, y0, 0, x, y1, 0);
    for (let y = Math.ceil(y0); y <= y1; y++) pts.push(x0, y, 0, x1, y, 0);
    const grid = new THREE.BufferGeometry();
    grid.setAttribute('position', new THREE.Float32BufferAttribute(pts, 3));
    this.worldGroup.add(new THREE.LineSegments(grid, new THREE.LineBasicMaterial({ color: 0xb3aa94 })));
    // scales in metres: along x at the front edge and a vertical ruler at a corner
    const step = Math.max(1, Math.round((x1 - x0) / 10));
    for (let x = Math.ceil(x0); x <= x1; x += step) {
      const s = label(`${x}`);
      s.position.set(x, y0 - 0.4, 0);
      this.worldGroup.add(s);
    }
    const ruler = [];
    for (let z = 0; z <= z1; z++) {
      ruler.push(x0, y0, z, x0 + 0.25, y0, z);
      const s = label(`${z} m`);
      s.position.set(x0 - 0.5, y0, z);
      this.worldGroup.add(s);
    }
    ruler.push(x0, y0, 0, x0, y0, Math.floor(z1));
    const rg = new THREE.BufferGeometry();
    rg.setAttribute('position', new THREE.Float32BufferAttribute(ruler, 3));
    this.worldGroup.add(new THREE.LineSegments(rg, new THREE.LineBasicMaterial({ color: 0x555555 })));
    for (const m of this.worldGroup.children) m.renderOrder = GROUND_ORDER;
    if (first) this.setView('persp');
  }

  // Solid obstacles (`obstacle:ID`) and clearance zones (`zone:ID`), boxes or
  // prisms, each a see-through mesh and its edges.
  setObstacles(obstacles) {
    const key = JSON.stringify(obstacles);
    if (key === this.obstacleKey) return;
    this.obstacleKey = key;
    for (const m of this.obstacleGroup.children) {
      m.geometry?.dispose();
      m.material?.dispose();
    }
    this.obstacleGroup.clear();
    for (const o of obstacles) {
      const zone = isZone(o);
      const geo = obstacleGeometry(o);
      const mesh = seeThrough(geo, { color: zone ? ZONE_COLOR : 0x8c7b6b, opacity: zone ? 0.25 : 0.35 });
      mesh.name = `${zone ? 'zone' : 'obstacle'}:${o.id}`;
      const edges = new THREE.LineSegments(new THREE.EdgesGeometry(geo),
        new THREE.LineBasicMaterial({ color: zone ? 0xb87400 : 0x5a4a3a }));
      mesh.userData.id = edges.userData.id = o.id;
      mesh.userData.shape = o.polygon ? 'prism' : 'box';
      this.obstacleGroup.add(mesh, edges);
    }
    this.branches.setZones(zonesOf(obstacles));
    this.invalidate();
  }

  // The obstacles of a kind ('obstacle' or 'zone') as drawn, from their meshes:
  // [{id, shape ('box' or 'prism'), min, max}], the bounds of each mesh.
  drawnBounds(kind) {
    const prefix = `${kind}:`;
    return this.obstacleGroup.children.filter((m) => m.name.startsWith(prefix)).map((m) => {
      if (!m.geometry.boundingBox) m.geometry.computeBoundingBox();
      const b = m.geometry.boundingBox;
      return { id: m.name.slice(prefix.length), shape: m.userData.shape, min: b.min.toArray(), max: b.max.toArray() };
    });
  }

  // The mesh of an obstacle or zone (id) measured: {name, shape, triangles, volume
  // (m³, from its triangles: positive when they face outwards)}, or null.
  obstacleMesh(id) {
    const m = this.obstacleGroup.children.find((c) => c.isMesh && c.userData.id === id);
    if (!m) return null;
    const g = m.geometry, pos = g.getAttribute('position'), idx = g.index;
    const n = idx ? idx.count : pos.count;
    const a = new THREE.Vector3(), b = new THREE.Vector3(), c = new THREE.Vector3();
    let volume = 0;
    for (let i = 0; i < n; i += 3) {
      const [i0, i1, i2] = idx ? [idx.getX(i), idx.getX(i + 1), idx.getX(i + 2)] : [i, i + 1, i + 2];
      a.fromBufferAttribute(pos, i0);
      b.fromBufferAttribute(pos, i1);
      c.fromBufferAttribute(pos, i2);
      volume += a.dot(b.cross(c)) / 6;
    }
    return { name: m.name, shape: m.userData.shape, triangles: n / 3, volume };
  }

  // The obstacles and zones whose drawn tops a vertical ray down through (x, y)
  // meets (their meshes' faces that face up, so a prism's holes let it through),
  // from the highest: [{id, z}].
  obstaclesAt(x, y) {
    let top = this.world?.max[2] ?? 0;
    for (const m of this.obstacleGroup.children) {
      if (!m.geometry.boundingBox) m.geometry.computeBoundingBox();
      top = Math.max(top, m.geometry.boundingBox.max.z);
    }
    const ray = new THREE.Raycaster(new THREE.Vector3(x, y, top + 1), new THREE.Vector3(0, 0, -1));
    const meshes = this.obstacleGroup.children.filter((m) => m.isMesh);
    return ray.intersectObjects(meshes, false).map((h) => ({ id: h.object.userData.id, z: h.point.z }));
  }

  // Cameras: 'persp' orbits; 'front' (looking along +y), 'side' (along -x) and
  // 'top' are orthographic, like the paper's figures.
  setView(name) {
    const w = this.world || { min: [-5, -5, 0], max: [5, 5, 10] };
    const c = [(w.min[0] + w.max[0]) / 2, (w.min[1] + w.max[1]) / 2, 0];
    const span = Math.max(w.max[0] - w.min[0], w.max[1] - w.min[1], w.max[2] - w.min[2]);
    const target = new THREE.Vector3(c[0], c[1], name === 'top' ? 0 : Math.min(w.max[2], span) * 0.35);
    this.controls.dispose();
    if (name === 'persp') {
      this.camera = this.persp;
      this.persp.position.set(c[0] + span * 0.9, c[1] - span * 1.3, span * 0.7);
    } else {
      this.camera = this.ortho;
      this.orthoHalf = span * 0.6;
      this.ortho.zoom = 1;
      this.fitOrtho();
      const d = span * 2;
      if (name === 'front') this.ortho.position.set(target.x, target.y - d, target.z);
      else if (name === 'side') this.ortho.position.set(target.x + d, target.y, target.z);
      else this.ortho.position.set(target.x, target.y - 1e-4, d);
    }
    this.controls = new OrbitControls(this.camera, this.renderer.domElement);
    this.controls.target.copy(target);
    this.controls.enableRotate = name === 'persp';
    this.controls.screenSpacePanning = true;
    this.controls.addEventListener('change', () => this.invalidate());
    this.controls.update();
    this.viewName = name;
    this.invalidate();
  }

  // The perspective camera at `from`, looking at `to` (world points [x, y, z]).
  lookAt(from, to) {
    this.setView('persp');
    this.persp.position.set(...from);
    this.controls.target.set(...to);
    this.controls.update();
    this.invalidate();
  }

  // Shows or hides the box of an obstacle or zone (id), and its edges.
  setObstacleVisible(id, on) {
    for (const m of this.obstacleGroup.children) if (m.userData.id === id) m.visible = on;
    this.invalidate();
  }

  // The ground point (z = 0) under a pixel of the canvas, or null.
  groundAt(clientX, clientY) {
    const r = this.renderer.domElement.getBoundingClientRect();
    const ndc = new THREE.Vector2(((clientX - r.left) / r.width) * 2 - 1, -((clientY - r.top) / r.height) * 2 + 1);
    const ray = new THREE.Raycaster();
    ray.setFromCamera(ndc, this.camera);
    const p = new THREE.Vector3();
    if (!ray.ray.intersectPlane(new THREE.Plane(new THREE.Vector3(0, 0, 1), 0), p)) return null;
    if (this.world && (p.x < this.world.min[0] || p.x > this.world.max[0] ||
        p.y < this.world.min[1] || p.y > this.world.max[1])) return null;
    return [p.x, p.y];
  }

  // Canvas pixel (CSS px from the canvas's top left) of a world point.
  project(x, y, z) {
    const v = new THREE.Vector3(x, y, z).project(this.camera);
    const el = this.renderer.domElement;
    return [(v.x + 1) / 2 * el.clientWidth, (1 - v.y) / 2 * el.clientHeight];
  }

  // The shade layer (the daemon's /shade JSON): the ground's cells as a texture on
  // a plane just above the ground, drawn with the ground (before the see-through
  // boxes and the trees), and each face's cells as a texture on a quad just off
  // the face, blended like the boxes; colours by shadeColor(value / scale). null
  // takes it away.
  setShade(data, scale = 1) {
    for (const m of this.shadeGroup.children) {
      m.geometry.dispose();
      m.material.map.dispose();
      m.material.dispose();
    }
    this.shadeGroup.clear();
    if (data) {
      const v = data.voxel;
      const ground = new THREE.Mesh(new THREE.PlaneGeometry(data.nx * v, data.ny * v),
        new THREE.MeshBasicMaterial({ map: shadeTexture(data.ground, data.nx, data.ny, scale), side: THREE.DoubleSide }));
      ground.position.set(data.origin[0] + data.nx * v / 2, data.origin[1] + data.ny * v / 2, data.origin[2] + SHADE_LIFT);
      ground.name = 'shade:ground';
      ground.renderOrder = GROUND_ORDER;
      this.shadeGroup.add(ground);
      for (const f of data.faces) {
        const axes = faceAxes(f);
        if (!axes) continue;
        const [u, up, n] = axes.map((a) => new THREE.Vector3(...a)), du = f.du ?? v;
        const quad = seeThrough(new THREE.PlaneGeometry(f.nu * du, f.nz * v),
          { map: shadeTexture(f.added, f.nu, f.nz, scale), side: THREE.DoubleSide, opacity: 0.8 });
        // (the plane's own normal is u x up, which is -n on some faces: it is drawn
        // from both sides)
        quad.quaternion.setFromRotationMatrix(new THREE.Matrix4().makeBasis(u, up, new THREE.Vector3().crossVectors(u, up)));
        const c = new THREE.Vector3(...f.first).addScaledVector(u, (f.nu - 1) * du / 2)
          .addScaledVector(up, (f.nz - 1) * v / 2).addScaledVector(n, SHADE_LIFT);
        quad.position.copy(c);
        quad.name = `shade:${f.obstacle}:${f.face}`;
        this.shadeGroup.add(quad);
      }
    }
    this.invalidate();
  }

  // The shade layer's quads of faces as drawn: [{name, centre, normal (of the
  // plane, drawn from both sides), width, height}].
  shadeQuads() {
    return this.shadeGroup.children.filter((m) => m.name !== 'shade:ground').map((m) => ({
      name: m.name, centre: m.position.toArray(), normal: new THREE.Vector3(0, 0, 1).applyQuaternion(m.quaternion).toArray(),
      width: m.geometry.parameters.width, height: m.geometry.parameters.height,
    }));
  }

  // The colour [r, g, b] of the shade layer's ground texture at (x, y), or null.
  shadeTexel(x, y) {
    const g = this.shadeGroup.getObjectByName('shade:ground');
    if (!g) return null;
    const { data, width, height } = g.material.map.image, p = g.geometry.parameters;
    const i = Math.floor((x - g.position.x + p.width / 2) / p.width * width);
    const j = Math.floor((y - g.position.y + p.height / 2) / p.height * height);
    if (i < 0 || j < 0 || i >= width || j >= height) return null;
    return Array.from(data.slice((i + width * j) * 4, (i + width * j) * 4 + 3));
  }

  // A light slice as a heat map plane at its height; null hides it.
  setSlice(msg) {
    if (this.slice) {
      this.scene.remove(this.slice);
      this.slice.geometry.dispose();
      this.slice.material.map.dispose();
      this.slice.material.dispose();
      this.slice = null;
    }
    if (msg) {
      const bytes = Uint8Array.from(atob(msg.values), (ch) => ch.charCodeAt(0));
      const rgba = new Uint8Array(msg.nx * msg.ny * 4);
      for (let i = 0; i < bytes.length; i++) {
        const [r, g, b] = lightColor(bytes[i] / 255);
        rgba.set([r, g, b, 200], i * 4);
      }
      const tex = new THREE.DataTexture(rgba, msg.nx, msg.ny, THREE.RGBAFormat);
      tex.colorSpace = THREE.SRGBColorSpace;
      tex.magFilter = THREE.NearestFilter;
      tex.needsUpdate = true;
      const w = msg.nx * msg.voxel, h = msg.ny * msg.voxel;
      const plane = new THREE.Mesh(new THREE.PlaneGeometry(w, h), new THREE.MeshBasicMaterial({
        map: tex, transparent: true, opacity: 0.8, side: THREE.DoubleSide, depthWrite: false }));
      plane.position.set(msg.origin[0] + w / 2, msg.origin[1] + h / 2, msg.z);
      this.slice = plane;
      this.scene.add(plane);
    }
    this.invalidate();
  }
}
