// posefix 3D viewer (reports/<library>/viewer.html): every pose's target, its repairs and the reference, one
// camera for all. Data: the JSON of posefix.report.viewer (positions as float32 bits XOR their base mesh's, byte
// planes, deflate, base64; faces once per library). State from and to the URL hash:
// #pose=NAME&mesh=NAME&mode=faces|heat|regions|distortion&left=NAME (side by side with NAME on the left)&dump=NAME.
import * as THREE from "three";
import { OrbitControls } from "three/addons/controls/OrbitControls.js";

const DATA = JSON.parse(document.getElementById("posefix-data").textContent);
const C = DATA.colors;
const state = { pose: 0, mesh: "target", mode: "faces", left: null };
const cache = new Map();  // pose index -> Promise of its decoded meshes
let faces = null;  // Uint32Array (m * 3)

function bytes(text) {
  const raw = atob(text);
  const out = new Uint8Array(raw.length);
  for (let i = 0; i < raw.length; i++) out[i] = raw.charCodeAt(i);
  return out;
}

async function decodeArray(text, itemsize) {  // inverse of posefix.report.viewer.encode_array
  const stream = new Blob([bytes(text)]).stream().pipeThrough(new DecompressionStream("deflate"));
  const planes = new Uint8Array(await new Response(stream).arrayBuffer());
  const count = planes.length / itemsize;
  const out = new Uint8Array(planes.length);
  for (let b = 0; b < itemsize; b++) {
    for (let i = 0, o = b; i < count; i++, o += itemsize) out[o] = planes[b * count + i];
  }
  return out.buffer;
}

async function decodeMask(text) {
  const packed = new Uint8Array(await decodeArray(text, 1));
  const mask = new Uint8Array(DATA.face_count);
  for (let i = 0; i < mask.length; i++) mask[i] = (packed[i >> 3] >> (7 - (i & 7))) & 1;
  return mask;
}

async function decodeMesh(record, base) {  // {name, X: Float32Array (n * 3), hit: Uint8Array (m)}
  const bits = new Uint32Array(await decodeArray(record.X, 4));
  if (base) {
    const other = new Uint32Array(base.X.buffer);
    for (let i = 0; i < bits.length; i++) bits[i] ^= other[i];
  }
  return { name: record.name, X: new Float32Array(bits.buffer), hit: await decodeMask(record.hit),
    distorted: await decodeMask(record.distorted) };
}

const reference = (async () => {
  faces = new Uint32Array(await decodeArray(DATA.faces, 4));
  return decodeMesh(DATA.reference, null);
})();

function loadPose(index) {
  if (!cache.has(index)) {
    cache.set(index, (async () => {
      const pose = DATA.poses[index];
      const ref = await reference;
      const meshes = { reference: ref };
      for (const record of pose.meshes) meshes[record.name] = await decodeMesh(record, meshes[record.base]);
      const regions = new Uint8Array(await decodeArray(pose.regions, 1));
      return { meshes, regions };
    })());
  }
  return cache.get(index);
}

function meshNames(pose) {
  return [...pose.meshes.map((m) => m.name), "reference"];
}

// ---- colours per face ----
function rgb(hex) {  // linear RGB (three.js's working colour space) of an sRGB colour
  const c = new THREE.Color(hex);
  return [c.r, c.g, c.b];
}
const LUT = DATA.heat.colors.map(rgb);

function faceColors(mesh, decoded, pose) {
  const m = DATA.face_count;
  const out = new Float32Array(m * 3);
  const put = (f, c) => { out[3 * f] = c[0]; out[3 * f + 1] = c[1]; out[3 * f + 2] = c[2]; };
  const refHit = decoded.meshes.reference.hit;
  if (state.mode === "heat") {
    const X = mesh.X, T = decoded.meshes.target.X, top = pose.heat_limit * DATA.diagonal;
    const dev = new Float32Array(X.length / 3);
    for (let v = 0; v < dev.length; v++) {
      dev[v] = Math.hypot(X[3 * v] - T[3 * v], X[3 * v + 1] - T[3 * v + 1], X[3 * v + 2] - T[3 * v + 2]);
    }
    for (let f = 0; f < m; f++) {
      const value = (dev[faces[3 * f]] + dev[faces[3 * f + 1]] + dev[faces[3 * f + 2]]) / 3 / top;
      put(f, LUT[Math.round(Math.min(Math.max(value, 0), 1) * (LUT.length - 1))]);
    }
  } else if (state.mode === "regions") {
    const r = decoded.regions, cs = [rgb(C.free), rgb(C.constrained), rgb(C.pass_through)];
    for (let f = 0; f < m; f++) {
      const a = r[faces[3 * f]], b = r[faces[3 * f + 1]], c = r[faces[3 * f + 2]];
      put(f, cs[(a | b | c) & 2 ? 2 : (a & b & c & 1)]);
    }
  } else if (state.mode === "distortion") {
    const cs = [rgb(C.surface), rgb(C.distorted)];
    for (let f = 0; f < m; f++) put(f, cs[mesh.distorted[f]]);
  } else {
    const cs = [rgb(C.surface), rgb(C.highlight), rgb(C.secondary)];
    for (let f = 0; f < m; f++) put(f, cs[mesh.hit[f] ? (refHit[f] ? 2 : 1) : 0]);
  }
  return out;
}

// ---- the scene: one camera, one or two meshes ----
const view = document.getElementById("view");
const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
renderer.setPixelRatio(window.devicePixelRatio);
renderer.setClearColor(0xffffff);
view.prepend(renderer.domElement);
const camera = new THREE.PerspectiveCamera(30, 1, DATA.diagonal / 100, DATA.diagonal * 20);
const headlight = new THREE.DirectionalLight(0xffffff, 2.2);  // from above right of the camera, moving with it
headlight.position.set(0.4, 0.6, 0.8);
headlight.target.position.set(0, 0, -1);
camera.add(headlight, headlight.target);
const controls = new OrbitControls(camera, renderer.domElement);
const scenes = [0, 1].map(() => {  // per pane: the mesh, and its intersecting faces again on top ("x-ray")
  const scene = new THREE.Scene();
  scene.add(new THREE.AmbientLight(0xffffff, 0.9));
  const mesh = new THREE.Mesh(new THREE.BufferGeometry(), new THREE.MeshLambertMaterial(
    { vertexColors: true, flatShading: true, side: THREE.DoubleSide }));
  const xray = new THREE.Mesh(new THREE.BufferGeometry(), new THREE.MeshLambertMaterial(
    { vertexColors: true, flatShading: true, side: THREE.DoubleSide, transparent: true, opacity: 0.5,
      depthTest: false }));
  for (const m of [mesh, xray]) { m.frustumCulled = false; scene.add(m); }
  return { scene, mesh, xray };
});

const DISTANCE = DATA.diagonal * 1.5;  // of the camera from the reference's centre, before orbit and zoom

function resetCamera() {
  const v = DATA.view, c = new THREE.Vector3(...v.center);
  camera.up.set(...v.up);
  camera.position.copy(c).addScaledVector(new THREE.Vector3(...v.toward), DISTANCE);
  controls.target.copy(c);
  controls.update();
}

function fill(slot, mesh, colors) {  // non-indexed geometry: corner k of face f is vertex faces[3f + k]
  const m = DATA.face_count, P = new Float32Array(m * 9), K = new Float32Array(m * 9);
  for (let f = 0; f < m; f++) {
    for (let k = 0; k < 3; k++) {
      const v = faces[3 * f + k], o = 9 * f + 3 * k;
      P[o] = mesh.X[3 * v]; P[o + 1] = mesh.X[3 * v + 1]; P[o + 2] = mesh.X[3 * v + 2];
      K[o] = colors[3 * f]; K[o + 1] = colors[3 * f + 1]; K[o + 2] = colors[3 * f + 2];
    }
  }
  const geometry = scenes[slot].mesh.geometry, xray = scenes[slot].xray.geometry;
  geometry.setAttribute("position", new THREE.BufferAttribute(P, 3));
  geometry.setAttribute("color", new THREE.BufferAttribute(K, 3));
  geometry.computeVertexNormals();
  const shown = [];  // the corners of the faces drawn again on top: the intersecting ones, in the faces mode
  for (let f = 0; f < m && state.mode === "faces"; f++) if (mesh.hit[f]) shown.push(3 * f, 3 * f + 1, 3 * f + 2);
  for (const name of ["position", "color", "normal"]) xray.setAttribute(name, geometry.getAttribute(name));
  xray.setIndex(shown);
  return P;
}

function render() {
  const w = view.clientWidth, h = view.clientHeight, panes = state.left ? 2 : 1;
  renderer.setSize(w, h, false);
  camera.aspect = w / panes / h;
  const [wx, wy] = DATA.view.extent, reach = DISTANCE * Math.tan(THREE.MathUtils.degToRad(camera.fov / 2));
  camera.zoom = Math.min(reach / wy, (reach * camera.aspect) / wx);  // each pane shows the whole reference
  camera.updateProjectionMatrix();
  renderer.setScissorTest(true);
  for (let i = 0; i < panes; i++) {
    renderer.setViewport((i * w) / panes, 0, w / panes, h);
    renderer.setScissor((i * w) / panes, 0, w / panes, h);
    const scene = scenes[panes === 2 ? i : 1].scene;
    scene.add(camera);  // the camera carries the headlight into the scene it draws
    renderer.render(scene, camera);
  }
}
controls.addEventListener("change", render);
window.addEventListener("resize", render);

// ---- the page around it ----
const STATUS_COLORS = DATA.status_colors;

function countsText(pose) {
  return pose.meshes.map((m) => `${m.name} ${m.faces}` + (m.name === "target" ? "" : ` (${m.new} new)`)).join(" · ");
}

function buildList() {
  const list = document.getElementById("poses");
  DATA.poses.forEach((pose, i) => {
    const li = document.createElement("li");
    li.dataset.index = i;
    li.title = pose.reason || pose.status;
    li.innerHTML = `<span class="status" style="background:${STATUS_COLORS[pose.status]}"></span><b></b><br>` +
      `<span class="counts"></span>`;
    li.children[0].textContent = pose.status;
    li.children[1].textContent = pose.name;
    li.children[3].textContent = countsText(pose);
    li.addEventListener("click", () => show({ pose: i }));
    list.append(li);
  });
  document.getElementById("filter").addEventListener("input", (e) => {
    const word = e.target.value.toLowerCase();
    for (const li of list.children) {
      const pose = DATA.poses[li.dataset.index];
      li.hidden = word && !(pose.name.toLowerCase().includes(word) || pose.status.includes(word));
    }
  });
}

function button(label, on, extra, action) {
  const b = document.createElement("button");
  b.textContent = label;
  b.className = (on ? "on " : "") + extra;
  b.addEventListener("click", action);
  return b;
}

function toolbar(pose) {
  const bar = document.getElementById("bar");
  bar.replaceChildren();
  meshNames(pose).forEach((name, i) => {
    const b = button(`${i + 1} ${name}`, state.mesh === name, state.left === name ? "left" : "",
      (e) => show(e.shiftKey ? { left: name } : { mesh: name }));
    b.dataset.mesh = name;
    bar.append(b);
  });
  bar.append(button("h heat map", state.mode === "heat", "", () => show({ mode: state.mode === "heat" ? "faces" : "heat" })));
  bar.append(button("r regions", state.mode === "regions", "",
    () => show({ mode: state.mode === "regions" ? "faces" : "regions" })));
  bar.append(button("d distortion", state.mode === "distortion", "",
    () => show({ mode: state.mode === "distortion" ? "faces" : "distortion" })));
  bar.append(button("s side by side", !!state.left, "", () => show(sideBySide())));
  bar.append(button("c camera", false, "", () => { resetCamera(); render(); }));
  const help = document.createElement("span");
  help.id = "help";
  help.textContent = "keys: 1-9 mesh (shift: left pane), h heat map, r regions, d distortion, s side by side, " +
    "j/k next/previous pose, c camera; drag: orbit, right drag: pan, wheel: zoom";
  bar.append(help);
}

function sideBySide() {  // on: the target on the left, against the space-time repair unless a repair is shown
  if (state.left) return { left: null };
  return { left: "target", mesh: state.mesh === "target" ? "space-time" : state.mesh };
}

function swatch(color, label) {
  return `<span class="swatch" style="background:${color}"></span>${label}`;
}

function legend(pose) {
  const el = document.getElementById("legend");
  if (state.mode === "heat") {
    const stops = DATA.heat.colors.filter((c, i) => i % 15 === 0 || i === DATA.heat.colors.length - 1);
    el.innerHTML = `0<span id="colorbar" style="background:linear-gradient(to right,${stops.join(",")})"></span>` +
      `≥ ${pose.heat_limit.toPrecision(2)} &nbsp; |mesh − target| / bbox diagonal (the report's deviation scale)`;
  } else if (state.mode === "distortion") {
    el.innerHTML = swatch(C.distorted, `stretched or crushed beyond ${DATA.distortion_limit}x (edge-length or area ` +
      "ratio) against both the target and the reference; the target's against the reference");
  } else if (state.mode === "regions") {
    el.innerHTML = swatch(C.constrained, "V_C (constrained)") + swatch(C.free, "free (integrated through the field)") +
      swatch(C.pass_through, "pass-through (copied from the target)");
  } else {
    el.innerHTML = swatch(C.highlight, "intersecting, not in the reference (new)") +
      swatch(C.secondary, "intersecting in the reference too");
  }
}

function labels(pose) {
  const el = document.getElementById("labels");
  const names = state.left ? [state.left, state.mesh] : [state.mesh];
  el.replaceChildren(...names.map((name, i) => {
    const span = document.createElement("span");
    const record = pose.meshes.find((m) => m.name === name) || DATA.reference;
    span.textContent = `${name}: ${record.faces} intersecting faces` + (name === "reference" ? "" : `, ${record.new} new`) +
      (state.mode === "distortion" && name !== "reference" ? `, ${record.distorted_count} distorted` : "");
    span.style.left = state.left ? `calc(${i * 50}% + 8px)` : "auto";
    span.style.right = state.left ? "auto" : "8px";
    return span;
  }));
}

function dumpMesh(mesh, P) {  // the decoded positions and the corners drawn (float32, base64) for the tests
  const b64 = (array) => {
    const u8 = new Uint8Array(array.buffer);
    let s = "";
    for (let i = 0; i < u8.length; i += 0x8000) s += String.fromCharCode.apply(null, u8.subarray(i, i + 0x8000));
    return btoa(s);
  };
  document.getElementById("dump").textContent = JSON.stringify({ mesh: mesh.name, positions: b64(mesh.X), corners: b64(P) });
}

let showing = Promise.resolve();

function show(change) {  // apply a change of state, redraw; one at a time
  showing = showing.then(() => update(change), () => update(change));  // a failed change does not stop the next
  return showing;
}

async function update(change) {
  Object.assign(state, change);
  const pose = DATA.poses[state.pose];
  const decoded = await loadPose(state.pose);
  const names = meshNames(pose);
  if (!names.includes(state.mesh)) state.mesh = "target";
  if (state.left && !names.includes(state.left)) state.left = "target";
  const panes = state.left ? [state.left, state.mesh] : [state.mesh];
  let drawn = null;
  panes.forEach((name, i) => {
    const mesh = decoded.meshes[name];
    const P = fill(state.left ? i : 1, mesh, faceColors(mesh, decoded, pose));
    if (name === state.dump) drawn = [mesh, P];
  });
  if (drawn) dumpMesh(...drawn);
  toolbar(pose);
  legend(pose);
  labels(pose);
  document.getElementById("info").textContent = `${pose.name}: ${pose.status}` + (pose.reason ? ` (${pose.reason})` : "");
  for (const li of document.getElementById("poses").children) {
    li.classList.toggle("current", +li.dataset.index === state.pose);
    if (+li.dataset.index === state.pose) li.scrollIntoView({ block: "nearest" });
  }
  const hash = new URLSearchParams({ pose: pose.name, mesh: state.mesh, mode: state.mode });
  if (state.left) hash.set("left", state.left);
  if (state.dump) hash.set("dump", state.dump);
  history.replaceState(null, "", "#" + hash);
  render();
}

function fromHash() {
  const p = new URLSearchParams(location.hash.slice(1));
  const index = DATA.poses.findIndex((pose) => pose.name === p.get("pose"));
  return { pose: Math.max(index, 0), mesh: p.get("mesh") || "target", mode: p.get("mode") || "faces",
    left: p.get("left"), dump: p.get("dump") };
}

document.addEventListener("keydown", (e) => {
  if (e.target.tagName === "INPUT") return;
  const names = meshNames(DATA.poses[state.pose]);
  const digit = e.code.startsWith("Digit") ? +e.code.slice(5) : 0;
  if (digit >= 1 && digit <= names.length) show(e.shiftKey ? { left: names[digit - 1] } : { mesh: names[digit - 1] });
  else if (e.key === "h") show({ mode: state.mode === "heat" ? "faces" : "heat" });
  else if (e.key === "r") show({ mode: state.mode === "regions" ? "faces" : "regions" });
  else if (e.key === "d") show({ mode: state.mode === "distortion" ? "faces" : "distortion" });
  else if (e.key === "s") show(sideBySide());
  else if (e.key === "c") { resetCamera(); render(); }
  else if (e.key === "j" || e.key === "ArrowDown") show({ pose: Math.min(state.pose + 1, DATA.poses.length - 1) });
  else if (e.key === "k" || e.key === "ArrowUp") show({ pose: Math.max(state.pose - 1, 0) });
});

buildList();
resetCamera();
show(fromHash()).then(() => {
  if (!document.body.dataset.status.startsWith("error")) document.body.dataset.status = "ready";
});
