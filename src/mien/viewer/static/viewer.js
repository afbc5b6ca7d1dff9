// mien viewer: a character's head in 3D (three.js morph targets), driven live by the server's WebSocket.
//
// Data flow: controls -> JSON commands over the WebSocket (HTTP API when it is closed) -> the server's
// scheduler -> one binary frame per tick -> morph-target weights and head/eye pose -> a render when they
// change. The head is the glTF at the character's head_url (GET /api/characters): mien's glTF of its rig, or
// the user's own file (textures, hair, skin) placed in mien's frame by the character's file_to_rig. Weights
// arrive in the order of the character's target_names and drive every morph mesh's target OF THAT NAME (a
// shape on the head and the teeth moves both). Control lists come from /viewer/controls.json, built from the
// package's catalogues.
import * as THREE from "three";
import { GLTFLoader } from "three/addons/loaders/GLTFLoader.js";
import { DRACOLoader } from "three/addons/loaders/DRACOLoader.js";
import { MeshoptDecoder } from "three/addons/libs/meshopt_decoder.module.js";
import { OrbitControls } from "three/addons/controls/OrbitControls.js";
import { decodeFrame } from "./frame.js";
import { framedTurn, poseNodeRole, poseQuaternion, vrmPoseNodes } from "./pose.js";
import { SpeechPlayer, frameAt } from "./speech.js";

const params = new URLSearchParams(location.search);
const token = params.get("token") || "";
const $ = (id) => document.getElementById(id);

// ---------------------------------------------------------------------------------------------------------
// State shared by the parts of the page.
const state = {
  controls: null,
  character: params.get("character"),
  characters: new Map(), // id -> the server's character info (GET /api/characters)
  ws: null,
  wsOpen: false,
  reconnectMs: 500,
  frame: null, // latest decoded frame, applied on the next animation frame
  frameDirty: false,
  shown: null, // the frame the view last drew (null: none on this head yet)
  lastTick: null,
  ticksSeen: 0,
  head: null, // { root, pivot, poseNode, turnHead, meshes: [{ mesh, map: Int32Array }], names, eyes: [turn] }
  needsRender: true,
  renders: 0,
  loadingHead: null,
  speech: null, // the SpeechPlayer: each announced utterance's sound, in step with the frames (speech.js)
  speechLog: [], // while a sound plays, per animation frame (server seconds): the shown frame's time, the sound's
  //                and the next received frame's (null: none yet) { frameS, soundS, nextS }, the newest 2000
  recent: [], // the frames of the last 2 s, oldest first: while a sound plays, the face shows the sound's frame
};
window.mienViewer = state; // for tests and the curious: read-only use

function setStatus(message) {
  $("status-message").textContent = message;
}

function setConnection(text, good) {
  const el = $("status-connection");
  el.textContent = text;
  el.className = good ? "good" : "bad";
}

// ---------------------------------------------------------------------------------------------------------
// Server access.
function authHeaders() {
  return token ? { Authorization: `Bearer ${token}` } : {};
}

function withToken(url) {
  if (!token) return url;
  return url + (url.includes("?") ? "&" : "?") + "token=" + encodeURIComponent(token);
}

async function api(method, path, body, contentType = "application/json") {
  const init = { method, headers: { ...authHeaders() } };
  if (body !== undefined) {
    init.headers["Content-Type"] = contentType;
    init.body = contentType === "application/json" ? JSON.stringify(body) : body;
  }
  const response = await fetch(withToken(path), init);
  const text = await response.text();
  let data = null;
  try {
    data = text ? JSON.parse(text) : null;
  } catch {
    data = text;
  }
  if (!response.ok) {
    const detail = data && typeof data === "object" ? data.detail || data.error || JSON.stringify(data) : text;
    throw new Error(`${method} ${path}: ${response.status} ${typeof detail === "string" ? detail : JSON.stringify(detail)}`);
  }
  return data;
}

/** The HTTP API route and body of a socket command (used while the WebSocket is closed), or null. */
function httpCommand(command) {
  if ("emotion" in command) return ["emotion", { emotion: command.emotion, intensity: command.intensity }];
  if ("pad" in command) {
    const [pleasure, arousal, dominance] = command.pad;
    return ["pad", { pleasure, arousal, dominance }];
  }
  if ("laugh" in command) return ["laughter", { type: command.laugh, intensity: command.intensity }];
  if ("idle" in command) return ["idle", command.idle];
  if ("say" in command) return ["say", typeof command.say === "string" ? { text: command.say } : command.say];
  const aus = Object.fromEntries(Object.entries(command).filter(([key]) => /^AU\d/.test(key)));
  if (Object.keys(aus).length) return ["aus", { aus, speed: command.Speed ?? null }];
  return null;
}

/** Send a JSON command for the watched character: over the WebSocket, or the HTTP API when it is closed. */
function send(command) {
  if (state.wsOpen) {
    state.ws.send(JSON.stringify(command));
    return;
  }
  const http = httpCommand(command);
  if (!state.character || !http) {
    setStatus("not connected: command not sent");
    return;
  }
  const [route, body] = http;
  api("POST", `/api/characters/${encodeURIComponent(state.character)}/${route}`, body).catch((e) => setStatus(e.message));
}

function connect() {
  if (!state.character) return;
  const scheme = location.protocol === "https:" ? "wss:" : "ws:";
  const url = withToken(`${scheme}//${location.host}/ws?character=${encodeURIComponent(state.character)}`);
  const ws = new WebSocket(url);
  ws.binaryType = "arraybuffer";
  state.ws = ws;
  setConnection("connecting", false);
  ws.onopen = () => {
    state.wsOpen = true;
    state.reconnectMs = 500;
    state.speech.resetClock(); // a restarted server starts its clock again
    setConnection("live", true);
  };
  ws.onmessage = (event) => {
    if (typeof event.data === "string") {
      onServerText(event.data);
      return;
    }
    const frame = decodeFrame(event.data);
    if (frame.error) {
      setStatus(frame.error);
      return;
    }
    state.speech.noteFrame(frame.timeS);
    state.recent.push(frame);
    if (state.recent.length > 120) state.recent.shift();
    state.frame = frame;
    state.frameDirty = true;
    state.ticksSeen += 1;
  };
  ws.onclose = (event) => {
    if (state.ws !== ws) return; // replaced on purpose
    state.wsOpen = false;
    setConnection("disconnected", false);
    if (event.reason) setStatus(`server closed the stream: ${event.reason}`);
    setTimeout(() => state.ws === ws && connect(), state.reconnectMs);
    state.reconnectMs = Math.min(state.reconnectMs * 2, 5000);
  };
}

function onServerText(text) {
  let message;
  try {
    message = JSON.parse(text);
  } catch {
    setStatus(text.slice(0, 120));
    return;
  }
  if (message.speech) {
    if (String(message.speech.character) !== state.character) return;
    state.speech
      .play(message.speech)
      .then((line) => line && setStatus(`${message.speech.character} ${line}`))
      .catch((error) => setStatus(`speech sound: ${error.message || error}`));
    return;
  }
  if (message.error) setStatus(`server: ${message.error}`);
  else if (message.info || message.message) setStatus(String(message.info || message.message));
}

function watch(characterId) {
  if (characterId === state.character && state.head) return;
  state.character = characterId;
  const url = new URL(location.href);
  url.searchParams.set("character", characterId);
  history.replaceState(null, "", url);
  state.frame = null;
  state.recent = [];
  state.speech.stop();
  showIdle(state.characters.get(characterId));
  loadHead(characterId);
  if (state.wsOpen) {
    state.ws.send(JSON.stringify({ watch: characterId }));
    return;
  }
  const old = state.ws; // connecting to another character, closing, or closed: start over
  state.ws = null;
  if (old && old.readyState <= 1) old.close();
  connect();
}

// ---------------------------------------------------------------------------------------------------------
// The 3D scene.
const canvas = $("view");
/** True on a CPU rasteriser (SwiftShader, llvmpipe): multisampling there costs more than it shows. */
function softwareRenderer() {
  const gl = document.createElement("canvas").getContext("webgl2");
  const info = gl && gl.getExtension("WEBGL_debug_renderer_info");
  const name = info ? String(gl.getParameter(info.UNMASKED_RENDERER_WEBGL)) : "";
  gl?.getExtension("WEBGL_lose_context")?.loseContext();
  return /swiftshader|llvmpipe|softpipe|software/i.test(name);
}
const renderer = new THREE.WebGLRenderer({ canvas, antialias: !softwareRenderer() });
renderer.setPixelRatio(Math.min(window.devicePixelRatio, 2));
renderer.toneMapping = THREE.ACESFilmicToneMapping;
renderer.toneMappingExposure = 1.05;
const scene = new THREE.Scene();
scene.background = new THREE.Color(0x1d2023);
const camera = new THREE.PerspectiveCamera(22, 1, 0.05, 50);
camera.position.set(0, -0.03, 1);
const orbit = new OrbitControls(camera, canvas);
orbit.target.set(0, -0.03, 0);
orbit.enableDamping = false;
orbit.addEventListener("change", () => (state.needsRender = true));

// A key light above-right of the face, a softer fill from the left, a rim from behind, sky/ground ambient.
scene.add(new THREE.HemisphereLight(0xdfe6f0, 0x3a3430, 1.1));
const key = new THREE.DirectionalLight(0xfff3e6, 2.2);
key.position.set(0.6, 0.8, 1.2);
scene.add(key);
const fill = new THREE.DirectionalLight(0xdde6ff, 0.7);
fill.position.set(-1.0, 0.2, 0.8);
scene.add(fill);
const rim = new THREE.DirectionalLight(0xffffff, 0.9);
rim.position.set(0.0, 0.6, -1.2);
scene.add(rim);

function resize() {
  const width = canvas.clientWidth;
  const height = canvas.clientHeight;
  if (!width || !height) return;
  renderer.setSize(width, height, false);
  camera.aspect = width / height;
  camera.updateProjectionMatrix();
  state.needsRender = true;
}
new ResizeObserver(resize).observe(canvas);

function applyCameraPreset(preset) {
  camera.fov = preset.fov_deg;
  camera.position.set(...preset.position_m);
  orbit.target.set(...preset.target_m);
  camera.updateProjectionMatrix();
  orbit.update();
  document.querySelectorAll("#camera-buttons button").forEach((b) => b.classList.toggle("active", b.dataset.name === preset.name));
  state.needsRender = true;
}

const NECK_PIVOT_M = [0, -0.09, -0.04]; // fallback pivot (rig frame) when the glTF has no head node

// Decoders of compressed avatars (EXT_meshopt_compression, KHR_draco_mesh_compression), from the npm three
// package mien serves; the Draco decoder's WebAssembly loads only when a file needs it.
const dracoLoader = new DRACOLoader();
dracoLoader.setDecoderPath("/vendor/three/examples/jsm/libs/draco/gltf/");

async function loadHead(characterId) {
  const loading = (state.loadingHead = characterId);
  setStatus(`loading ${characterId}'s head...`);
  const info = state.characters.get(characterId) || {};
  const loader = new GLTFLoader();
  loader.setRequestHeader(authHeaders());
  loader.setMeshoptDecoder(MeshoptDecoder);
  loader.setDRACOLoader(dracoLoader);
  let gltf;
  try {
    gltf = await loader.loadAsync(withToken(info.head_url || `/api/characters/${encodeURIComponent(characterId)}/head.glb`));
  } catch (error) {
    if (state.loadingHead === loading) setStatus(`could not load the head of ${characterId}: ${error.message || error}`);
    return;
  }
  if (state.loadingHead !== loading) return; // another character was picked meanwhile
  if (state.head) {
    scene.remove(state.head.pivot);
    state.head.pivot.traverse((o) => {
      if (o.geometry) o.geometry.dispose();
    });
  }
  state.head = prepareHead(gltf, info);
  scene.add(state.head.pivot);
  state.frameDirty = state.frame !== null;
  state.shown = null;
  state.needsRender = true;
  const what = info.head_file ? `${info.head_file}, ` : "";
  setStatus(info.head_note || `${characterId}: ${what}${state.head.names.length} morph targets`);
}

/** The nodes head pose and gaze turn: a VRM file's humanoid bones, else nodes named as pose.js lists. */
function poseNodes(gltf) {
  const root = gltf.scene;
  const vrm = vrmPoseNodes(gltf.parser && gltf.parser.json);
  const byIndex = new Map();
  const associations = gltf.parser && gltf.parser.associations;
  if (associations && (vrm.head !== null || vrm.eyes.length)) {
    root.traverse((o) => {
      const index = associations.get(o)?.nodes;
      if (index !== undefined && !byIndex.has(index)) byIndex.set(index, o);
    });
  }
  let head = vrm.head !== null ? byIndex.get(vrm.head) || null : null;
  let eyes = vrm.eyes.map((i) => byIndex.get(i)).filter(Boolean);
  const named = { head: null, eyes: [] };
  root.traverse((o) => {
    if (o.isMesh) return;
    const role = poseNodeRole(o.name);
    if (role === "head" && !named.head) named.head = o;
    else if (role === "eye") named.eyes.push(o);
  });
  if (!head) head = named.head;
  if (!eyes.length) eyes = named.eyes;
  return { head, eyes };
}

/**
 * mien's glb gives each vertex its own paint texcoords and strength (attribute _PAINT: u, v, strength, as
 * mien.render.face_paint makes them): draw the paint texture with them, faded by the strength, as mien's
 * renderer does. Its TEXCOORD_0, for other glTF viewers, parks unpainted vertices on the texture's border, so
 * a triangle from a painted vertex to a parked one spans the whole texture and samples its coarsest mipmap:
 * thin red lines along the paint's edge (ICT's neck and chest).
 */
function paintLikeTheRenderer(object) {
  if (!object.isMesh || !object.geometry.attributes._paint || !object.material.map) return;
  const material = object.material;
  material.onBeforeCompile = (shader) => {
    shader.vertexShader = shader.vertexShader
      .replace("#include <common>", "#include <common>\nattribute vec3 _paint;\nvarying vec3 vMienPaint;")
      .replace("#include <uv_vertex>", "#include <uv_vertex>\n\tvMienPaint = _paint;");
    shader.fragmentShader = shader.fragmentShader
      .replace("#include <common>", "#include <common>\nvarying vec3 vMienPaint;")
      .replace(
        "#include <map_fragment>",
        [
          "#ifdef USE_MAP",
          "\tvec4 mienPaint = texture2D( map, vMienPaint.xy );",
          "\tdiffuseColor.rgb *= mix( vec3( 1.0 ), mienPaint.rgb, clamp( vMienPaint.z, 0.0, 1.0 ) );",
          "#endif",
        ].join("\n"),
      );
  };
  material.customProgramCacheKey = () => "mien-paint";
  material.needsUpdate = true;
}

/**
 * Wrap the glTF scene for posing, place a head file in mien's frame (file_to_rig), and map every morph mesh's
 * targets onto the frame's weight order by name (the character's target_names; a server that gives none: the
 * largest morph mesh's names).
 */
function prepareHead(gltf, info) {
  const root = gltf.scene;
  const morphMeshes = [];
  root.traverse((o) => {
    if (o.isMesh && o.morphTargetDictionary) morphMeshes.push(o);
  });
  const namesOf = (mesh) => {
    const names = [];
    for (const [name, index] of Object.entries(mesh.morphTargetDictionary)) names[index] = name;
    return names;
  };
  morphMeshes.sort((a, b) => b.morphTargetInfluences.length - a.morphTargetInfluences.length);
  const names = Array.isArray(info.target_names) ? info.target_names : morphMeshes.length ? namesOf(morphMeshes[0]) : [];
  const order = new Map(names.map((n, i) => [n, i]));
  const meshes = morphMeshes.map((mesh) => ({
    mesh,
    map: Int32Array.from(namesOf(mesh), (n) => (order.has(n) ? order.get(n) : -1)),
  }));
  root.traverse(paintLikeTheRenderer);
  // A head file sits in its own frame (a full body's head 1.6 m up, centimetres...): file_to_rig puts it in
  // mien's (metres, origin between the eyes), where the camera presets look.
  const placed = new THREE.Group();
  placed.name = "mien-placed";
  if (Array.isArray(info.file_to_rig) && info.file_to_rig.length === 16) {
    new THREE.Matrix4().set(...info.file_to_rig).decompose(placed.position, placed.quaternion, placed.scale);
  }
  placed.add(root);
  // Head pose turns the glTF's head node or bone (mien's glb puts one at the neck pivot); a head without one is
  // wrapped in a group at a typical neck position. Turns are in mien's axes, whatever a bone's local axes are.
  const found = poseNodes(gltf);
  const pivot = new THREE.Group();
  pivot.name = "mien-head";
  if (found.head) {
    pivot.add(placed);
  } else {
    const offset = new THREE.Group();
    offset.position.set(-NECK_PIVOT_M[0], -NECK_PIVOT_M[1], -NECK_PIVOT_M[2]);
    offset.add(placed);
    pivot.add(offset);
    pivot.position.set(...NECK_PIVOT_M);
  }
  pivot.updateMatrixWorld(true);
  const frameOf = (node) => {
    const q = new THREE.Quaternion();
    if (node.parent && node !== pivot) node.parent.getWorldQuaternion(q);
    return q;
  };
  const poseNode = found.head || pivot;
  const turnHead = poseNode === pivot ? framedTurn(pivot, new THREE.Quaternion()) : framedTurn(poseNode, frameOf(poseNode));
  const eyes = found.eyes.map((node) => framedTurn(node, frameOf(node)));
  return { root, pivot, poseNode, turnHead, meshes, names, eyes };
}

const gazeQuaternion = new THREE.Quaternion();
const headQuaternion = new THREE.Quaternion();

function applyFrame(frame) {
  const head = state.head;
  if (!head) return;
  const w = frame.weights;
  if (w.length !== head.names.length) return; // a frame of the previous character (another head) in flight
  for (const { mesh, map } of head.meshes) {
    const influences = mesh.morphTargetInfluences;
    for (let i = 0; i < map.length; i++) influences[i] = map[i] >= 0 && map[i] < w.length ? w[map[i]] : 0;
  }
  const [yaw, pitch, roll, gazeYaw, gazePitch] = frame.pose;
  head.turnHead(poseQuaternion(yaw, pitch, roll, headQuaternion));
  if (head.eyes.length) {
    poseQuaternion(gazeYaw, gazePitch, 0, gazeQuaternion); // gaze: mien.rig.pose.gaze_rotation, in the head's frame
    for (const turnEye of head.eyes) turnEye(gazeQuaternion);
  }
}

/** True when two frames show the same face (weights and pose): a still face is not drawn again. */
function sameFace(a, b) {
  if (!a || !b || a.weights.length !== b.weights.length) return false;
  for (let i = 0; i < a.weights.length; i++) if (a.weights[i] !== b.weights[i]) return false;
  for (let i = 0; i < 5; i++) if (a.pose[i] !== b.pose[i]) return false;
  return true;
}

// Render on demand: only when the face, the camera or the window changed (cheap on a laptop's battery, and a
// CPU rasteriser drawing a textured avatar is free for the next change as soon as the face is still).
let fpsCount = 0;
let fpsSince = performance.now();
function animate(now) {
  // while a sound plays, the face shows the frame of the sound's time (speech.js), else the newest frame
  const soundS = state.speech.soundTimeS();
  const frame = soundS === null ? state.frame : frameAt(state.recent, soundS) || state.frame;
  if ((state.frameDirty || soundS !== null) && frame) {
    if (!sameFace(frame, state.shown)) {
      applyFrame(frame);
      state.shown = state.head ? frame : null;
      state.needsRender = true;
    }
    state.frameDirty = false;
    if (frame.tick !== state.lastTick) {
      state.lastTick = frame.tick;
      $("status-tick").textContent = `tick ${frame.tick}  t ${frame.timeS.toFixed(2)} s`;
    }
  }
  if (soundS !== null && frame) {
    const next = state.recent[state.recent.indexOf(frame) + 1];
    state.speechLog.push({ frameS: frame.timeS, soundS, nextS: next ? next.timeS : null });
    if (state.speechLog.length > 2000) state.speechLog.shift();
  }
  if (state.needsRender) {
    renderer.render(scene, camera);
    state.needsRender = false;
    state.renders += 1;
    fpsCount += 1;
  }
  if (now - fpsSince >= 1000) {
    $("status-fps").textContent = `${Math.round((fpsCount * 1000) / (now - fpsSince))} fps`;
    fpsCount = 0;
    fpsSince = now;
  }
  requestAnimationFrame(animate);
}

// ---------------------------------------------------------------------------------------------------------
// Controls.
function button(label, onClick, extra = {}) {
  const b = document.createElement("button");
  b.type = "button";
  b.textContent = label;
  Object.assign(b.dataset, extra.data || {});
  if (extra.title) b.title = extra.title;
  if (extra.className) b.className = extra.className;
  b.addEventListener("click", onClick);
  return b;
}

function bindOutput(input, output, digits) {
  const update = () => (output.textContent = Number(input.value).toFixed(digits));
  input.addEventListener("input", update);
  update();
}

function buildCameras(cameras) {
  const box = $("camera-buttons");
  for (const preset of cameras) {
    const [view, distance] = preset.name.split("-");
    box.append(button(`${view} ${distance.replace("m", " m")}`, () => applyCameraPreset(preset), { data: { name: preset.name } }));
  }
  applyCameraPreset(cameras[0]);
}

function buildEmotions(controls) {
  const box = $("emotion-buttons");
  const intensity = $("emotion-intensity");
  intensity.max = controls.emotion_intensity_max;
  bindOutput(intensity, $("emotion-intensity-value"), 1);
  const emote = (name) => send({ emotion: name, intensity: Number(intensity.value) });
  for (const name of controls.emotions) box.append(button(name, () => emote(name), { data: { emotion: name } }));
  for (const name of controls.blends) {
    box.append(button(name, () => emote(name), { data: { emotion: name }, className: "blend", title: "blend" }));
  }
}

function buildPad() {
  const pad = $("pad");
  const context = pad.getContext("2d");
  const dominance = $("pad-dominance");
  bindOutput(dominance, $("pad-dominance-value"), 2);
  let point = [0, 0];
  const draw = () => {
    const { width, height } = pad;
    context.clearRect(0, 0, width, height);
    context.strokeStyle = "#3a4046";
    context.beginPath();
    context.moveTo(width / 2, 0);
    context.lineTo(width / 2, height);
    context.moveTo(0, height / 2);
    context.lineTo(width, height / 2);
    context.stroke();
    context.fillStyle = "#9aa3ab";
    context.font = "10px system-ui";
    context.fillText("pleasure \u2192", width - 62, height / 2 - 4);
    context.fillText("arousal \u2191", width / 2 + 4, 11);
    const x = ((point[0] + 1) / 2) * width;
    const y = ((1 - point[1]) / 2) * height;
    context.fillStyle = "#6fb3d9";
    context.beginPath();
    context.arc(x, y, 5, 0, 2 * Math.PI);
    context.fill();
    $("pad-value").textContent = `P ${point[0].toFixed(2)} A ${point[1].toFixed(2)}`;
  };
  const sendPad = () => send({ pad: [point[0], point[1], Number(dominance.value)] });
  const fromEvent = (event) => {
    const r = pad.getBoundingClientRect();
    const clamp = (v) => Math.max(-1, Math.min(1, v));
    point = [clamp(((event.clientX - r.left) / r.width) * 2 - 1), clamp(1 - ((event.clientY - r.top) / r.height) * 2)];
    draw();
  };
  let dragging = false;
  pad.addEventListener("pointerdown", (e) => {
    dragging = true;
    pad.setPointerCapture(e.pointerId);
    fromEvent(e);
    sendPad();
  });
  pad.addEventListener("pointermove", (e) => {
    if (!dragging) return;
    fromEvent(e);
    throttledPad();
  });
  pad.addEventListener("pointerup", () => {
    dragging = false;
    sendPad();
  });
  const throttledPad = throttle(sendPad, 100);
  dominance.addEventListener("change", sendPad);
  $("pad-reset").addEventListener("click", () => {
    point = [0, 0];
    dominance.value = 0;
    dominance.dispatchEvent(new Event("input"));
    draw();
    sendPad();
  });
  draw();
}

function buildLaughter(types) {
  const box = $("laughter-buttons");
  const intensity = $("laughter-intensity");
  bindOutput(intensity, $("laughter-intensity-value"), 1);
  for (const t of types) {
    const title = `${t.family}, ${t.duration_s.toFixed(1)} s: ${t.notes}`;
    box.append(button(t.label, () => send({ laugh: t.type, intensity: Number(intensity.value) }), { data: { laughter: t.type }, title }));
  }
}

function buildIdle(toggles) {
  const box = $("idle-toggles");
  const inputs = [];
  let generation = 0;  // a later switch supersedes an earlier one's read-back
  const sendIdle = async () => {
    const settings = {};
    for (const { input, flags } of inputs) for (const flag of flags) settings[flag] = input.checked;
    send({ idle: settings });
    // Read back what the server holds (a server without the idle command keeps the character's setting).
    // A busy server may take a moment, so ask a few times before saying it did not take the switch.
    const mine = ++generation;
    const id = state.character;
    for (let attempt = 0; attempt < 6; attempt++) {
      await new Promise((resolve) => setTimeout(resolve, 300));
      if (mine !== generation || id !== state.character) return;
      try {
        const list = await api("GET", "/api/characters");
        if (mine !== generation || id !== state.character) return;
        const entry = (Array.isArray(list) ? list : []).find((e) => String(characterId(e)) === id);
        if (!entry) return;
        state.characters.set(id, entry);
        const held = entry.idle_parts;
        const taken = held && Object.entries(settings).every(([flag, on]) => !(flag in held) || held[flag] === on);
        if (taken) return;
        if (!held || attempt === 5) {
          setStatus(`this server cannot switch idle live: ${id} keeps idle ${entry.idle ? "on" : "off"}`);
          showIdle(entry);
          return;
        }
      } catch (error) {
        setStatus(error.message);
        return;
      }
    }
  };
  for (const toggle of toggles) {
    const label = document.createElement("label");
    const input = document.createElement("input");
    input.type = "checkbox";
    input.checked = true;
    input.dataset.idle = toggle.name;
    input.dataset.flags = JSON.stringify(toggle.flags);
    input.addEventListener("change", sendIdle);
    label.append(input, toggle.name);
    box.append(label);
    inputs.push({ input, flags: toggle.flags });
  }
}

/** Show a character's idle switches as the server reports them (``idle_parts``: each IdleSettings flag). */
function showIdle(info) {
  if (!info) return;
  const parts = info.idle_parts || {};
  document.querySelectorAll("#idle-toggles input").forEach((input) => {
    const flags = JSON.parse(input.dataset.flags);
    const on = flags.map((flag) => (flag in parts ? parts[flag] : Boolean(info.idle)));
    input.checked = on.every(Boolean);
    input.indeterminate = on.some(Boolean) && !input.checked;
  });
}

function buildActionUnits(controls) {
  const box = $("au-sliders");
  const sliders = [];
  const sendState = () => {
    const command = {};
    for (const s of sliders) command[s.dataset.au] = Number(s.value);
    send(command);
  };
  const throttledSend = throttle(sendState, 80);
  for (const au of controls.aus) {
    const row = document.createElement("div");
    row.className = "au";
    row.title = `${au.label} ${au.name}${au.lateral ? " (both sides)" : ""}${au.openfacs ? " - OpenFACS" : ""}`;
    const code = document.createElement("span");
    code.className = "code" + (au.openfacs ? " openfacs" : "");
    code.textContent = au.label;
    const track = document.createElement("div");
    track.className = "track";
    const input = document.createElement("input");
    input.type = "range";
    input.min = 0;
    input.max = controls.au_max;
    input.step = 0.1;
    input.value = 0;
    input.dataset.au = au.label;
    input.setAttribute("aria-label", `${au.label} ${au.name}`);
    const letters = document.createElement("div");
    letters.className = "letters";
    controls.intensity_letters.forEach((letter, i) => {
      // FACS letter i is intensity i + 1: mark it under that slider position (the thumb is 16 px wide)
      const span = document.createElement("span");
      span.textContent = letter;
      span.style.left = `calc(8px + (100% - 16px) * ${(i + 1) / controls.au_max})`;
      letters.append(span);
    });
    track.append(input, letters);
    const output = document.createElement("output");
    const show = () => {
      const v = Number(input.value);
      output.textContent = v === 0 ? "0" : intensityName(v, controls.intensity_letters);
      output.classList.toggle("on", v > 0);
    };
    input.addEventListener("input", () => {
      show();
      throttledSend();
    });
    input.addEventListener("change", sendState);
    show();
    row.append(code, track, output);
    box.append(row);
    sliders.push(input);
  }
  $("au-reset").addEventListener("click", () => {
    for (const s of sliders) {
      s.value = 0;
      s.dispatchEvent(new Event("input"));
    }
    sendState();
  });
}

/** "C" for 3, "C+0.4" style for fractional values (FACS letters A..E = 1..5). */
function intensityName(value, letters) {
  const whole = Math.round(value);
  if (Math.abs(value - whole) < 1e-6 && whole >= 1) return letters[whole - 1];
  return value.toFixed(1);
}

function throttle(fn, ms) {
  let timer = null;
  return () => {
    if (timer) return;
    timer = setTimeout(() => {
      timer = null;
      fn();
    }, ms);
  };
}

// Characters: list, pick, create, remove (HTTP API).
function characterId(entry) {
  return typeof entry === "string" ? entry : entry.id ?? entry.name;
}

async function refreshCharacters(preferred) {
  let list;
  try {
    list = await api("GET", "/api/characters");
  } catch (error) {
    setStatus(error.message);
    return [];
  }
  const entries = Array.isArray(list) ? list : list.characters || [];
  const ids = entries.map(characterId).filter((id) => id !== undefined && id !== null).map(String);
  state.characters = new Map(entries.map((entry) => [String(characterId(entry)), entry]));
  const picker = $("character-picker");
  picker.replaceChildren(...ids.map((id) => new Option(id, id)));
  const chosen = ids.includes(preferred) ? preferred : ids[0];
  if (chosen !== undefined) {
    picker.value = chosen;
    watch(chosen);
  } else {
    setStatus("no characters: create one");
  }
  return ids;
}

function buildCharacters(heads) {
  $("character-picker").addEventListener("change", (e) => watch(e.target.value));
  $("character-new-head").replaceChildren(...heads.map((h) => new Option(h, h)));
  $("character-create").addEventListener("click", async () => {
    const typed = $("character-new-name").value.trim();
    const id = typed || `character-${Date.now().toString(36).slice(-5)}`;
    try {
      const created = await api("POST", "/api/characters", { id, head: $("character-new-head").value });
      $("character-new-name").value = "";
      await refreshCharacters(created ? String(characterId(created)) : id);
    } catch (error) {
      setStatus(error.message);
    }
  });
  $("character-remove").addEventListener("click", async () => {
    const id = $("character-picker").value;
    if (!id) return;
    try {
      await api("DELETE", `/api/characters/${encodeURIComponent(id)}`);
      state.head && scene.remove(state.head.pivot);
      state.head = null;
      state.character = null;
      state.needsRender = true;
      await refreshCharacters();
    } catch (error) {
      setStatus(error.message);
    }
  });
}

function buildSpeech() {
  const text = $("say-text");
  const sound = $("say-sound");
  const say = () => {
    const words = text.value.trim();
    if (!words) {
      setStatus("type something to say");
      return;
    }
    state.speech.unlock(); // a click: the browser lets the page play sound from now on
    send({ say: words });
  };
  $("say-button").addEventListener("click", say);
  text.addEventListener("keydown", (event) => event.key === "Enter" && say());
  sound.addEventListener("change", () => {
    state.speech.enabled = sound.checked;
    if (sound.checked) state.speech.unlock();
    else state.speech.stop();
  });
  // browsers start audio only after a user gesture: the first click anywhere allows it
  document.addEventListener("pointerdown", () => state.speech.enabled && state.speech.unlock(), { once: true });
}

function buildClip(suffixes) {
  $("clip-file").accept = suffixes.join(",");
  $("clip-play").addEventListener("click", async () => {
    const file = $("clip-file").files[0];
    if (!file) {
      setStatus("choose a clip file first");
      return;
    }
    if (!state.character) return;
    try {
      const dot = file.name.lastIndexOf(".");
      const suffix = dot >= 0 ? file.name.slice(dot).toLowerCase() : "";
      const path = `/api/characters/${encodeURIComponent(state.character)}/clip?suffix=${encodeURIComponent(suffix)}`;
      await api("POST", path, await file.arrayBuffer(), "application/octet-stream");
      setStatus(`playing ${file.name}`);
    } catch (error) {
      setStatus(error.message);
    }
  });
}

async function fetchSound(url) {
  const response = await fetch(withToken(url), { headers: authHeaders() });
  if (!response.ok) throw new Error(`GET ${url}: ${response.status}`);
  return response.arrayBuffer();
}
state.speech = new SpeechPlayer(fetchSound);

async function main() {
  requestAnimationFrame(animate);
  try {
    state.controls = await api("GET", "/viewer/controls.json");
  } catch (error) {
    setStatus(error.message);
    return;
  }
  const controls = state.controls;
  buildCameras(controls.cameras);
  buildEmotions(controls);
  buildPad();
  buildLaughter(controls.laughter);
  buildIdle(controls.idle);
  buildActionUnits(controls);
  buildCharacters(controls.heads);
  buildClip(controls.clip_suffixes);
  buildSpeech();
  await refreshCharacters(state.character);
  document.body.dataset.ready = "1";
}

main();
