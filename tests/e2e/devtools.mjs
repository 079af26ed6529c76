// A bare DevTools-protocol page for the viewer benchmark: headless Chromium driven through the
// Runtime and Input domains only. Playwright enables the Network domain on every page, and with it
// Chromium copies each WebSocket frame the page receives, base64-encoded, to the driver; for the
// geodesic app's 2 MB texture frames that took about a core of the benchmark's 2 (Chromium's
// browser process and node). A user's browser pays nothing of the kind, so the benchmark does not
// either. Needs node's WebSocket client (node 20: --experimental-websocket).
import { spawn } from "node:child_process";
import { mkdtempSync, rmSync } from "node:fs";
import { tmpdir } from "node:os";
import { join } from "node:path";
import { chromiumFlags, chromiumPath } from "./harness.mjs";

/// Starts headless Chromium with software WebGL (harness.chromiumFlags), opens `url` in a
/// width x height viewport and resolves, once the viewer page is ready, with a page object
/// offering evaluate(fn, arg), mouse.click(x, y), viewportSize() and close().
export async function openBarePage(url, { width = 900, height = 700, timeoutMs = 60000 } = {}) {
  if (typeof WebSocket === "undefined")
    throw new Error("this node has no WebSocket client: run it with --experimental-websocket");
  const profile = mkdtempSync(join(tmpdir(), "texgrad-chromium-"));
  const browser = spawn(chromiumPath, [
    "--headless", ...chromiumFlags, "--no-first-run", "--remote-debugging-port=0",
    `--user-data-dir=${profile}`, "about:blank"],
                        { stdio: ["ignore", "ignore", "pipe"], detached: true });
  const exited = new Promise((r) => browser.on("exit", r));
  let cdp = null;
  const closeBrowser = async () => {
    if (cdp) await Promise.race([cdp.send("Browser.close", {}).catch(() => {}),
                                 new Promise((r) => setTimeout(r, 5000))]);
    // Its own process group (detached): the helper processes go with it.
    const signal = (name) => { try { process.kill(-browser.pid, name); } catch { /* gone */ } };
    const killer = setTimeout(() => signal("SIGKILL"), 5000);
    signal("SIGTERM");
    if (browser.exitCode === null && browser.signalCode === null) await exited;
    clearTimeout(killer);
    if (cdp) cdp.close();
    // Chromium's helper processes may still be writing to the profile for a moment.
    try {
      rmSync(profile, { recursive: true, force: true, maxRetries: 20, retryDelay: 100 });
    } catch (e) {
      console.error(`could not remove the browser profile ${profile}: ${e.message}`);
    }
  };
  try {
    const endpoint = await devtoolsEndpoint(browser, timeoutMs);
    cdp = await connect(endpoint);
    const { targetId } = await cdp.send("Target.createTarget", { url: "about:blank" });
    const { sessionId } = await cdp.send("Target.attachToTarget", { targetId, flatten: true });
    const send = (method, params = {}) => cdp.send(method, params, sessionId);
    await send("Emulation.setDeviceMetricsOverride",
               { width, height, deviceScaleFactor: 1, mobile: false });
    await send("Page.navigate", { url });
    const page = barePage(send, { width, height }, closeBrowser);
    const start = Date.now();
    while (!(await page.evaluate(() => Boolean(window.texgrad && window.texgrad.ready)))) {
      if (Date.now() - start > timeoutMs) throw new Error("the viewer page did not get ready");
      await new Promise((r) => setTimeout(r, 100));
    }
    return { page };
  } catch (e) {
    await closeBrowser();
    throw e;
  }
}

/// The browser-wide DevTools WebSocket address Chromium prints on stderr.
function devtoolsEndpoint(browser, timeoutMs) {
  return new Promise((resolvePromise, reject) => {
    let stderr = "";
    const timer = setTimeout(() => reject(new Error(`Chromium did not start:\n${stderr}`)),
                             timeoutMs);
    browser.stderr.on("data", (d) => {
      stderr += d;
      const m = stderr.match(/DevTools listening on (ws:\/\/\S+)/);
      if (m) {
        clearTimeout(timer);
        resolvePromise(m[1]);
      }
    });
    browser.on("exit", (code) => {
      clearTimeout(timer);
      reject(new Error(`Chromium exited with ${code}:\n${stderr}`));
    });
  });
}

/// A protocol connection: send(method, params, sessionId) resolves with the command's result.
function connect(endpoint) {
  const ws = new WebSocket(endpoint);
  const pending = new Map();
  let nextId = 1;
  ws.onmessage = (event) => {
    const message = JSON.parse(event.data);
    const waiter = pending.get(message.id);
    if (!waiter) return;  // events: none are enabled
    pending.delete(message.id);
    if (message.error) waiter.reject(new Error(`${waiter.method}: ${message.error.message}`));
    else waiter.resolve(message.result);
  };
  return new Promise((resolvePromise, reject) => {
    ws.onerror = () => reject(new Error(`cannot connect to ${endpoint}`));
    ws.onopen = () => resolvePromise({
      send(method, params, sessionId) {
        const id = nextId++;
        ws.send(JSON.stringify({ id, method, params, ...(sessionId ? { sessionId } : {}) }));
        return new Promise((resolve, rejectCommand) => {
          pending.set(id, { resolve, reject: rejectCommand, method });
        });
      },
      close() { ws.close(); },
    });
  });
}

/// The subset of playwright's Page the benchmark and harness.waitForState use.
function barePage(send, size, close) {
  const mouse = (type, x, y, extra = {}) =>
    send("Input.dispatchMouseEvent", { type, x, y, button: "left", ...extra });
  return {
    async evaluate(fn, arg = null) {
      const { result, exceptionDetails } = await send("Runtime.evaluate", {
        expression: `(${fn})(${JSON.stringify(arg)})`, awaitPromise: true, returnByValue: true });
      if (exceptionDetails)
        throw new Error(`in the page: ${exceptionDetails.exception?.description}`);
      return result.value;
    },
    mouse: {
      async click(x, y) {
        await mouse("mouseMoved", x, y, { button: "none" });
        await mouse("mousePressed", x, y, { buttons: 1, clickCount: 1 });
        await mouse("mouseReleased", x, y, { buttons: 0, clickCount: 1 });
      },
    },
    viewportSize: () => ({ ...size }),
    close,
  };
}
