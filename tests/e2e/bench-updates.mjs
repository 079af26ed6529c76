// Benchmark: updates per second of the geodesic app (spot, 1024²), server side (solver steps)
// and as seen by the page (texture frames received, and uploaded and drawn on the model).
import { readdirSync, readFileSync } from "node:fs";
import { join } from "node:path";
import { openBarePage } from "./devtools.mjs";
import { openPage, sharedData, startServer, stopServer, waitForPage, waitForState }
  from "./harness.mjs";

// --playwright: drive the page through playwright as the end-to-end tests do, for comparison
// (playwright's Network domain copies every frame to the driver: devtools.mjs).
const viaPlaywright = process.argv.includes("--playwright");

// CPU time (ms) so far of texgrad and of each kind of Chromium process (browser, gpu-process,
// renderer, utility), read from /proc; empty where there is no /proc.
function cpuByProcess(serverPid) {
  const tick = 1000 / 100;  // USER_HZ is 100 on Linux
  const sums = {};
  let pids = [];
  try { pids = readdirSync("/proc").filter((d) => /^\d+$/.test(d)); } catch { return sums; }
  for (const pid of pids) {
    try {
      // Chromium rewrites its helpers' command lines into one space-separated string.
      const cmd = readFileSync(`/proc/${pid}/cmdline`, "latin1").replace(/\0/g, " ");
      let kind = null;
      if (Number(pid) === serverPid) kind = "texgrad";
      else if (/^\S*chrom/.test(cmd)) {
        const type = cmd.match(/--type=(\S+)/), sub = cmd.match(/--utility-sub-type=(\S+)/);
        kind = sub ? sub[1].split(".")[0] : type ? type[1] : "browser";
      }
      if (!kind) continue;
      const fields = readFileSync(`/proc/${pid}/stat`, "latin1").split(") ")[1].split(" ");
      sums[kind] = (sums[kind] || 0) + (Number(fields[11]) + Number(fields[12])) * tick;
    } catch { /* the process ended */ }
  }
  return sums;
}

const server = await startServer([join(sharedData, "spot", "spot_triangulated.obj"),
                                  "--app", "geodesic", "--max-fps", "1000",
                                  "--max-iterations", "100000"]);
let page = null, close = null;
try {
  if (viaPlaywright) {
    const opened = await openPage(server.url);
    page = opened.page;
    close = () => opened.browser.close();
  } else {
    ({ page } = await openBarePage(server.url));
    close = () => page.close();
  }
  const size = page.viewportSize();
  // The solver settles (an update no longer changes the 16-bit picture) within about ten updates
  // of a click and then idles, so the rates are measured over the refinement after each of
  // several clicks, from the page's arrival time of every frame: from the first frame of a click
  // (it includes picking the source) to its last, steps by the frames' iteration numbers (the
  // server may send only the latest of several steps), frames received and frames drawn.
  const points = [[0.5, 0.5], [0.45, 0.4], [0.55, 0.6], [0.48, 0.55], [0.52, 0.45], [0.46, 0.6],
                  [0.54, 0.4], [0.5, 0.35], [0.5, 0.62], [0.47, 0.48]].map(
      ([fx, fy]) => [Math.round(size.width * fx), Math.round(size.height * fy)]);
  await page.evaluate(() => {
    const stats = window.texgrad.stats;
    const previous = stats.onFrame;
    window.frameLog = [];
    stats.onFrame = (header) => {
      window.frameLog.push({ t: performance.now(), iteration: header.iteration,
                             shown: stats.shown });
      if (previous) previous(header);
    };
  });
  let steps = 0, frames = 0, shown = 0, active = 0, lastStep = 0, lastFrame = 0, counted = 0;
  const cpu = {};
  let cpuSteps = 0;
  for (const point of points) {
    const idle = await waitForState(page, (st) => !st.running, 120000);
    await page.evaluate(() => { window.frameLog = []; });
    const cpuBefore = cpuByProcess(server.process.pid);
    await page.mouse.click(...point);
    const done = await waitForState(
        page, (st) => st.totalSteps > idle.totalSteps && !st.running, 120000);
    await waitForPage(page, (n) => window.frameLog.some((f) => f.iteration >= n), 30000,
                      "the page to receive the click's last frame", done.iteration);
    const cpuAfter = cpuByProcess(server.process.pid);
    for (const [kind, ms] of Object.entries(cpuAfter))
      cpu[kind] = (cpu[kind] || 0) + ms - (cpuBefore[kind] || 0);
    cpuSteps += done.totalSteps - idle.totalSteps;
    const log = await page.evaluate(() => window.frameLog.filter((f) => f.iteration >= 1));
    if (log.length < 2) continue;  // settled at once: nothing to time
    const first = log[0], last = log[log.length - 1];
    active += (last.t - first.t) / 1000;
    steps += last.iteration - first.iteration;
    frames += log.length - 1;
    shown += last.shown - first.shown;
    lastStep = done.lastStepSeconds;
    lastFrame = done.lastFrameSeconds;
    counted += 1;
  }
  const driver = viaPlaywright ? "playwright" : "bare DevTools";
  console.log(`geodesic spot 1024^2 (${driver}): ` +
              `server ${(steps / active).toFixed(2)} updates/s ` +
              `(last step ${(lastStep * 1000).toFixed(0)} ms, frame encoding ` +
              `${(lastFrame * 1000).toFixed(1)} ms), page ${(frames / active).toFixed(2)} ` +
              `updates/s received, ${(shown / active).toFixed(2)} shown, over ${steps} updates ` +
              `in ${active.toFixed(1)} s of refinement after ${counted} of ${points.length} clicks`);
  const perStep = Object.entries(cpu).filter(([, ms]) => ms > 0).sort((a, b) => b[1] - a[1])
      .map(([kind, ms]) => `${kind} ${(ms / cpuSteps).toFixed(1)}`).join(", ");
  if (perStep) console.log(`CPU ms per update (click to settled, ${cpuSteps} updates): ${perStep}`);
} finally {
  if (close) await close();
  await stopServer(server);
}
