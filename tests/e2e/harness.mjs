// End-to-end test plumbing: starts `texgrad view`, drives Debian's Chromium (headless, software
// WebGL) through playwright-core from viewer/node_modules, and collects page-side helpers.
import { spawn } from "node:child_process";
import { createRequire } from "node:module";
import { dirname, join, resolve } from "node:path";
import { fileURLToPath } from "node:url";

const here = dirname(fileURLToPath(import.meta.url));
export const repo = resolve(here, "..", "..");
const require = createRequire(join(repo, "viewer", "package.json"));
const { chromium } = require("playwright-core");

export const cli = process.env.TEXGRAD_CLI || join(repo, "build", "release", "texgrad");
export const sharedData = process.env.TEXGRAD_SHARED_DATA || resolve(repo, "..", "shared", "data");
export const chromiumPath = process.env.CHROMIUM || "/usr/bin/chromium";

/// Starts `texgrad view ARGS --port 0` and resolves with { url, process } once it prints its URL.
export function startServer(args, { timeoutMs = 120000 } = {}) {
  const webRoot = process.env.TEXGRAD_WEB_ROOT ? ["--web-root", process.env.TEXGRAD_WEB_ROOT] : [];
  const child = spawn(cli, ["view", ...args, "--port", "0", ...webRoot],
                      { stdio: ["ignore", "pipe", "pipe"] });
  let stderr = "";
  child.stderr.on("data", (d) => { stderr += d; });
  return new Promise((resolvePromise, reject) => {
    const timer = setTimeout(() => {
      child.kill("SIGTERM");
      reject(new Error(`texgrad view did not print its URL in time:\n${stderr}`));
    }, timeoutMs);
    let stdout = "";
    child.stdout.on("data", (d) => {
      stdout += d;
      const m = stdout.match(/open (http:\/\/\S+)/);
      if (m) {
        clearTimeout(timer);
        resolvePromise({ url: m[1], process: child, stdout: () => stdout, stderr: () => stderr });
      }
    });
    child.on("exit", (code) => {
      clearTimeout(timer);
      reject(new Error(`texgrad view exited with ${code}:\n${stderr}`));
    });
  });
}

/// Stops a server started by startServer and waits for it to exit.
export function stopServer(server) {
  return new Promise((resolvePromise) => {
    if (server.process.exitCode !== null) return resolvePromise(server.process.exitCode);
    server.process.removeAllListeners("exit");
    server.process.on("exit", (code) => resolvePromise(code));
    server.process.kill("SIGTERM");
  });
}

/// Chromium flags for software WebGL in a container (--disable-dev-shm-usage: containers, CI
/// among them, often have a 64 MB /dev/shm).
export const chromiumFlags = ["--no-sandbox", "--use-angle=swiftshader",
                              "--enable-unsafe-swiftshader", "--ignore-gpu-blocklist",
                              "--disable-dev-shm-usage"];

/// Launches headless Chromium with software WebGL and opens the viewer page.
export async function openPage(url, { width = 900, height = 700 } = {}) {
  const browser = await chromium.launch({
    executablePath: chromiumPath,
    headless: true,
    args: chromiumFlags,
  });
  const page = await browser.newPage({ viewport: { width, height } });
  const errors = [];
  page.on("pageerror", (e) => errors.push(String(e)));
  page.on("crash", () => console.error("  the page crashed"));
  page.on("console", (m) => { if (m.type() === "error") errors.push(m.text()); });
  await page.goto(url);
  await page.waitForFunction(() => window.texgrad && window.texgrad.ready, null,
                             { timeout: 60000 });
  return { browser, page, errors };
}

/// Waits until `predicate(state)` holds for the server state, polling every 100 ms.
export async function waitForState(page, predicate, timeoutMs = 60000) {
  const start = Date.now();
  for (;;) {
    const state = await page.evaluate(() => window.texgrad.request({ type: "state" }));
    if (predicate(state)) return state;
    if (Date.now() - start > timeoutMs)
      throw new Error(`timed out waiting for server state; last: ${JSON.stringify(state)}`);
    await new Promise((r) => setTimeout(r, 100));
  }
}

/// Waits until `fn(arg)`, evaluated in the page every 100 ms, returns a truthy value and returns
/// it; on time-out throws with `what` and the page's frame statistics. Uses only page.evaluate,
/// so it also drives devtools.mjs's bare page.
export async function waitForPage(page, fn, timeoutMs, what, arg = null) {
  const start = Date.now();
  for (;;) {
    const value = await page.evaluate(fn, arg);
    if (value) return value;
    if (Date.now() - start > timeoutMs) {
      const seen = await page.evaluate(() => ({ frames: window.texgrad.stats.frames,
                                                last: window.texgrad.stats.last,
                                                server: window.texgrad.stats.serverState }));
      throw new Error(`timed out waiting for ${what}; page: ${JSON.stringify(seen)}`);
    }
    await new Promise((r) => setTimeout(r, 100));
  }
}

/// RGBA of the rendered canvas at CSS pixel (x, y) (the renderer keeps its drawing buffer).
export function canvasPixel(page, x, y) {
  return page.evaluate(([px, py]) => {
    const canvas = document.querySelector("#view canvas");
    const scratch = document.createElement("canvas");
    scratch.width = canvas.width;
    scratch.height = canvas.height;
    const ctx = scratch.getContext("2d");
    ctx.drawImage(canvas, 0, 0);
    const s = canvas.width / canvas.clientWidth;
    return Array.from(ctx.getImageData(Math.round(px * s), Math.round(py * s), 1, 1).data);
  }, [x, y]);
}

/// Deterministic pseudo-random surface points (face, bary) over the mesh.
export function surfaceSamples(faces, count, seed = 1) {
  let s = seed >>> 0;
  const next = () => ((s = (Math.imul(s, 1664525) + 1013904223) >>> 0) / 4294967296);
  const points = [];
  for (let i = 0; i < count; ++i) {
    let a = next(), b = next();
    if (a + b > 1) { a = 1 - a; b = 1 - b; }
    points.push({ face: Math.floor(next() * faces), bary: [1 - a - b, a, b] });
  }
  return points;
}

export const distance3 = (p, q) => Math.hypot(p[0] - q[0], p[1] - q[1], p[2] - q[2]);

/// Spearman rank correlation of two equally long arrays.
export function spearman(x, y) {
  const rank = (v) => {
    const order = v.map((value, i) => [value, i]).sort((p, q) => p[0] - q[0]);
    const r = new Array(v.length);
    order.forEach(([, i], k) => { r[i] = k; });
    return r;
  };
  const rx = rank(x), ry = rank(y), n = x.length;
  let d2 = 0;
  for (let i = 0; i < n; ++i) d2 += (rx[i] - ry[i]) ** 2;
  return 1 - (6 * d2) / (n * (n * n - 1));
}

export function check(condition, message) {
  if (!condition) throw new Error(`check failed: ${message}`);
  console.log(`  ok: ${message}`);
}
