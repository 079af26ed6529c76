// Page of `texgrad view`: loads the mesh from the server, shows the solver's texture frames on it,
// and turns clicks and brush strokes into protocol messages (include/texgrad/viewer/protocol.h).
import * as THREE from "three";
import { OrbitControls } from "three/addons/controls/OrbitControls.js";
import { decodeFrame, decodeMesh } from "./protocol.js";
import { surfaceMaterial } from "./material.js";
import { visibleSide } from "./visible_side.js";

const token = new URLSearchParams(location.search).get("token") || "";
const withToken = (path) => (token ? `${path}?token=${encodeURIComponent(token)}` : path);
const $ = (id) => document.getElementById(id);

// The server answers every message exactly once, echoing its "id"; replies without an id (the
// greeting, errors about unreadable messages) are only shown.
class Connection {
  constructor(url, onFrame) {
    this.pending = new Map();
    this.nextId = 1;
    this.ws = new WebSocket(url);
    this.ws.binaryType = "arraybuffer";
    this.opened = new Promise((resolve, reject) => {
      this.ws.onopen = resolve;
      this.ws.onerror = reject;
    });
    this.ws.onmessage = (event) => {
      if (typeof event.data !== "string") return onFrame(event.data);
      const reply = JSON.parse(event.data);
      if (reply.type === "error") showMessage(reply.message);
      const resolve = this.pending.get(reply.id);
      if (resolve) {
        this.pending.delete(reply.id);
        resolve(reply);
      }
    };
    this.ws.onclose = () => showMessage("connection to the server closed");
  }
  /// Sends a message object (an id is added) and resolves with its reply.
  request(message) {
    const id = this.nextId++;
    return new Promise((resolve) => {
      this.pending.set(id, resolve);
      this.ws.send(JSON.stringify({ ...message, id }));
    });
  }
  /// Sends raw text (tests of malformed input) and resolves with the next error or reply.
  sendRaw(text) {
    return new Promise((resolve) => {
      const previous = this.ws.onmessage;
      this.ws.onmessage = (event) => {
        if (typeof event.data !== "string") return previous(event);
        this.ws.onmessage = previous;
        resolve(JSON.parse(event.data));
      };
      this.ws.send(text);
    });
  }
}

function showMessage(text) {
  $("message").textContent = text;
}

function buildGeometry(mesh) {
  const { faces, triangles, positions, uvs } = mesh;
  // Smooth normals from the welded positions, then one vertex per corner (faceIndex = mesh face).
  const vertexNormals = new Float32Array(positions.length);
  const a = new THREE.Vector3(), b = new THREE.Vector3(), c = new THREE.Vector3();
  for (let f = 0; f < faces; ++f) {
    const [i, j, k] = [triangles[3 * f], triangles[3 * f + 1], triangles[3 * f + 2]];
    a.fromArray(positions, 3 * i);
    b.fromArray(positions, 3 * j).sub(a);
    c.fromArray(positions, 3 * k).sub(a);
    b.cross(c);
    for (const v of [i, j, k])
      for (let d = 0; d < 3; ++d) vertexNormals[3 * v + d] += b.getComponent(d);
  }
  const pos = new Float32Array(9 * faces), nor = new Float32Array(9 * faces);
  for (let corner = 0; corner < 3 * faces; ++corner) {
    const v = triangles[corner];
    for (let d = 0; d < 3; ++d) {
      pos[3 * corner + d] = positions[3 * v + d];
      nor[3 * corner + d] = vertexNormals[3 * v + d];
    }
  }
  const geometry = new THREE.BufferGeometry();
  geometry.setAttribute("position", new THREE.BufferAttribute(pos, 3));
  geometry.setAttribute("normal", new THREE.BufferAttribute(nor, 3));
  geometry.setAttribute("uv", new THREE.BufferAttribute(uvs, 2));
  geometry.normalizeNormals();
  geometry.computeBoundingSphere();
  return geometry;
}

/// Whether WebGL runs without a GPU (the renderer's name where the browser tells it).
function softwareRenderer() {
  const gl = document.createElement("canvas").getContext("webgl2");
  if (!gl) return false;
  const info = gl.getExtension("WEBGL_debug_renderer_info");
  const name = String(gl.getParameter(info ? info.UNMASKED_RENDERER_WEBGL : gl.RENDERER));
  gl.getExtension("WEBGL_lose_context")?.loseContext();
  return /swiftshader|llvmpipe|softpipe|software/i.test(name);
}

async function main() {
  const info = await (await fetch(withToken("/api/info"))).json();
  const mesh = decodeMesh(await (await fetch(withToken("/api/mesh"))).arrayBuffer());
  $("app-name").textContent = info.app;
  $(`${info.app}-controls`).classList.remove("hidden");

  // Multisampling costs a software renderer (no GPU: SwiftShader, llvmpipe) a large part of each
  // frame, so it is only asked of hardware.
  const renderer = new THREE.WebGLRenderer({ antialias: !softwareRenderer(),
                                             preserveDrawingBuffer: true });
  renderer.setPixelRatio(window.devicePixelRatio);
  renderer.setSize(window.innerWidth, window.innerHeight);
  $("view").appendChild(renderer.domElement);
  const scene = new THREE.Scene();
  scene.background = new THREE.Color(0x202428);
  const geometry = buildGeometry(mesh);
  const sphere = geometry.boundingSphere;
  const camera = new THREE.PerspectiveCamera(40, window.innerWidth / window.innerHeight,
                                             sphere.radius / 100, sphere.radius * 100);
  camera.position.copy(sphere.center).add(new THREE.Vector3(0, 0, sphere.radius * 2.8));
  const controls = new OrbitControls(camera, renderer.domElement);
  controls.target.copy(sphere.center);
  controls.update();
  controls.addEventListener("change", () => requestRender());

  const surface = surfaceMaterial(info.width, info.height, 2 * sphere.radius, visibleSide(mesh));
  surface.setLockTint(info.app === "stitch");
  const model = new THREE.Mesh(geometry, surface.material);
  scene.add(model);

  // Frames arrive faster than they can be shown at times: keep only the latest and upload it on
  // the next animation frame. An animation frame is asked for only when something changed (a
  // frame, the camera, the size, a setting), so an idle page leaves the CPU to the solver.
  const stats = { frames: 0, shown: 0, frameTimes: [], shownTimes: [], last: null,
                  serverState: null, lastSource: null };
  let latest = null, renderScheduled = false;
  const forget = (times, now) => {
    while (times.length && times[0] < now - 1000) times.shift();
  };
  const recent = (times, now) => {
    times.push(now);
    forget(times, now);
  };
  const draw = () => {
    renderScheduled = false;
    if (latest) {
      if (surface.show(latest)) {
        stats.shown += 1;
        recent(stats.shownTimes, performance.now());
      }
      latest = null;
    }
    renderer.render(scene, camera);
  };
  const requestRender = () => {
    if (renderScheduled) return;
    renderScheduled = true;
    requestAnimationFrame(draw);
  };
  const onFrame = (buffer) => {
    latest = decodeFrame(buffer);
    stats.frames += 1;
    stats.last = latest.header;
    stats.lastTexels = latest.texels;
    if (stats.onFrame) stats.onFrame(latest.header);
    recent(stats.frameTimes, performance.now());
    requestRender();
  };
  const connection = new Connection(
      `${location.protocol === "https:" ? "wss" : "ws"}://${location.host}${withToken("/ws")}`,
      onFrame);
  await connection.opened;

  // Picking: face index and barycentric coordinates of the surface point under a pixel.
  const raycaster = new THREE.Raycaster();
  const triangle = new THREE.Triangle();
  const bary = new THREE.Vector3();
  const pick = (clientX, clientY) => {
    const rect = renderer.domElement.getBoundingClientRect();
    const ndc = new THREE.Vector2(((clientX - rect.left) / rect.width) * 2 - 1,
                                  -((clientY - rect.top) / rect.height) * 2 + 1);
    raycaster.setFromCamera(ndc, camera);
    const hit = raycaster.intersectObject(model, false)[0];
    if (!hit) return null;
    const p = geometry.attributes.position;
    const f = hit.faceIndex;
    triangle.a.fromBufferAttribute(p, 3 * f);
    triangle.b.fromBufferAttribute(p, 3 * f + 1);
    triangle.c.fromBufferAttribute(p, 3 * f + 2);
    triangle.getBarycoord(hit.point, bary);
    const w = [bary.x, bary.y, bary.z].map((x) => Math.min(1, Math.max(0, x)));
    const sum = w[0] + w[1] + w[2];
    return { face: f, bary: w.map((x) => x / sum) };
  };

  const lockMode = () => document.querySelector("input[name=lock-mode]:checked").value;
  const brush = () => (info.app === "stitch"
    ? { radius: Number($("lock-radius").value), strength: 1, mode: lockMode() }
    : { radius: Number($("radius").value), strength: Number($("strength").value),
        mode: document.querySelector("input[name=mode]:checked").value });
  // Stitch: which texture the server shows and whether a solve is under way. The worker answers
  // requests only between solves, so the page times re-solves itself: from the first change
  // (brush, reset) to the first frame stepped after the last change was applied.
  const stitch = { stitched: true, solving: info.app === "stitch", pending: 0, applied: 0,
                   after: 0, started: performance.now(), seconds: null, residual: null };
  const setShown = (stitched) => {
    stitch.stitched = stitched;
    $("toggle").textContent = stitched ? "Show composite" : "Show stitched";
  };
  const stitchChange = (message) => {
    if (!stitch.solving) {
      stitch.started = performance.now();
      stitch.applied = 0;
    }
    stitch.solving = true;
    stitch.pending += 1;
    setShown(true);
    return connection.request(message).then((reply) => {
      stitch.pending -= 1;
      stitch.after = stats.last ? stats.last.sequence : 0;
      if (reply.type !== "error") stitch.applied += 1;
      // Only refused changes (e.g. a radius out of range): nothing is solved.
      if (stitch.pending === 0 && stitch.applied === 0) stitch.solving = false;
      return reply;
    });
  };
  stats.onFrame = (header) => {
    if (info.app !== "stitch" || !stitch.solving || stitch.pending > 0) return;
    if (header.iteration < 1 || header.sequence <= stitch.after) return;
    stitch.solving = false;
    stitch.residual = header.residual;
    if (stitch.after > 0) stitch.seconds = (performance.now() - stitch.started) / 1000;
  };
  let painting = false, lastDab = 0, down = null;
  const dabInterval = 50;  // ms between brush dabs while dragging
  const dab = (event) => {
    const hit = pick(event.clientX, event.clientY);
    if (!hit) return;
    lastDab = performance.now();
    const message = { type: "brush", ...hit, ...brush() };
    if (info.app === "stitch") stitchChange(message);
    else connection.request(message);
  };
  const paints = (event) => event.button === 0 &&
      (info.app === "filter" || (info.app === "stitch" && lockMode() !== "off"));
  renderer.domElement.addEventListener("pointerdown", (event) => {
    down = { x: event.clientX, y: event.clientY };
    if (paints(event) && pick(event.clientX, event.clientY)) {
      painting = true;
      controls.enabled = false;
      dab(event);
    }
  });
  renderer.domElement.addEventListener("pointermove", (event) => {
    if (painting && performance.now() - lastDab >= dabInterval) dab(event);
  });
  window.addEventListener("pointerup", (event) => {
    if (painting) {
      painting = false;
      controls.enabled = true;
    } else if (info.app === "geodesic" && down && event.button === 0 &&
               Math.hypot(event.clientX - down.x, event.clientY - down.y) < 4) {
      const hit = pick(event.clientX, event.clientY);
      if (hit) {
        stats.lastSource = hit;
        connection.request({ type: "source", ...hit, add: event.shiftKey });
      }
    }
    down = null;
  });

  const bindSlider = (id, format, onChange) => {
    const update = () => { $(`${id}-value`).textContent = format(Number($(id).value)); };
    $(id).addEventListener("input", () => { update(); if (onChange) onChange(); });
    update();
  };
  const sendParameters = () => connection.request({
    type: "params", alpha: 10 ** Number($("alpha").value), beta: Number($("beta").value) });
  bindSlider("alpha", (v) => (10 ** v).toExponential(1), sendParameters);
  bindSlider("beta", (v) => v.toFixed(2), sendParameters);
  bindSlider("radius", (v) => v.toFixed(3));
  bindSlider("strength", (v) => v.toFixed(2));
  bindSlider("lock-radius", (v) => v.toFixed(3));
  $("toggle").addEventListener("click", () => {
    setShown(!stitch.stitched);
    connection.request({ type: "show", texture: stitch.stitched ? "stitched" : "composite" });
  });
  bindSlider("iso", (v) => v.toFixed(3), () => {
    surface.setIsoSpacing(Number($("iso").value));
    requestRender();
  });
  surface.setIsoSpacing(Number($("iso").value));
  for (const action of ["start", "pause", "step", "reset"])
    $(action).addEventListener("click", () => {
      if (info.app === "stitch" && action === "reset") stitchChange({ type: "run", action });
      else connection.request({ type: "run", action });
    });
  $("save").addEventListener("click", async () => {
    const reply = await connection.request({ type: "save" });
    if (reply.type === "saved") showMessage(`saved ${reply.path}`);
  });

  // Updates per second shown on the model (frames received: stats.frameTimes).
  const pageRate = () => {
    forget(stats.shownTimes, performance.now());
    return stats.shownTimes.length;
  };
  const receivedRate = () => {
    forget(stats.frameTimes, performance.now());
    return stats.frameTimes.length;
  };
  // Replacing a text, even by the same one, makes the browser paint the panel again.
  const setText = (id, text) => {
    if ($(id).textContent !== text) $(id).textContent = text;
  };
  let stateAsked = false;
  const showStitchStatus = () => {
    const state = stitch.solving
      ? `solving... ${((performance.now() - stitch.started) / 1000).toFixed(1)} s`
      : `solved${stitch.seconds === null ? "" : ` in ${stitch.seconds.toFixed(2)} s`}`;
    setText("stats", `${state}\n` +
        (stitch.residual === null ? "" : `residual ${stitch.residual.toExponential(2)}\n`) +
        `showing ${stitch.stitched ? "stitched" : "composite"}`);
  };
  setInterval(async () => {
    if (info.app === "stitch") showStitchStatus();
    if (stateAsked) return;  // the server answers after the running solve
    stateAsked = true;
    stats.serverState = await connection.request({ type: "state" });
    stateAsked = false;
    const s = stats.serverState, h = stats.last;
    if (info.app === "stitch") {
      // The first step is the initial solve: the server timed it.
      if (s.totalSteps === 1 && stitch.seconds === null) stitch.seconds = s.lastStepSeconds;
      if (s.error) showMessage(s.error);
      return showStitchStatus();
    }
    setText("stats",
        `updates/s page ${pageRate()} (received ${receivedRate()})  ` +
        `server ${s.updatesPerSecond.toFixed(1)}\n` +
        `iteration ${s.iteration}  ${s.running ? "running" : s.paused ? "paused" : "settled"}\n` +
        `residual ${s.residual.toExponential(2)}\n` +
        (h && h.format === 2 ? `max distance ${h.scale.toPrecision(4)}\n` : ""));
  }, 500);

  window.addEventListener("resize", () => {
    camera.aspect = window.innerWidth / window.innerHeight;
    camera.updateProjectionMatrix();
    renderer.setSize(window.innerWidth, window.innerHeight);
    requestRender();
  });
  requestRender();

  // Hooks for the end-to-end tests (tests/e2e): picking, raw requests and counters.
  window.texgrad = {
    info,
    stats,
    pick,
    pageRate,
    request: (message) => connection.request(message),
    sendRaw: (text) => connection.sendRaw(text),
    faces: mesh.faces,
    surfacePoint: (face, baryIn) => {
      const p = geometry.attributes.position, v = new THREE.Vector3(), q = new THREE.Vector3();
      for (let k = 0; k < 3; ++k) q.addScaledVector(v.fromBufferAttribute(p, 3 * face + k), baryIn[k]);
      return q.toArray();
    },
    diameter: 2 * sphere.radius,
    project: (face, baryIn) => {
      const p = geometry.attributes.position, v = new THREE.Vector3(), q = new THREE.Vector3();
      for (let k = 0; k < 3; ++k) q.addScaledVector(v.fromBufferAttribute(p, 3 * face + k), baryIn[k]);
      q.project(camera);
      const rect = renderer.domElement.getBoundingClientRect();
      return { x: rect.left + (q.x + 1) / 2 * rect.width, y: rect.top + (1 - q.y) / 2 * rect.height };
    },
    ready: true,
  };
}

main().catch((error) => showMessage(String(error)));
