// Benchmark: updates per second of the geodesic app (spot, 1024²), server side (solver steps)
// and as seen by the page (texture frames received, and uploaded and drawn on the model).
import { join } from "node:path";
import { openPage, sharedData, startServer, stopServer, waitForState } from "./harness.mjs";

const seconds = Number(process.env.TEXGRAD_BENCH_SECONDS || 4);  // at most, per click
const server = await startServer([join(sharedData, "spot", "spot_triangulated.obj"),
                                  "--app", "geodesic", "--max-fps", "1000",
                                  "--max-iterations", "100000"]);
try {
  const { browser, page } = await openPage(server.url);
  const size = page.viewportSize();
  // Several clicks: the solver settles (an update no longer changes the picture) within about
  // ten updates of each.
  const points = [[0.5, 0.5], [0.45, 0.4], [0.55, 0.6], [0.48, 0.55], [0.52, 0.45], [0.46, 0.6],
                  [0.54, 0.4], [0.5, 0.35], [0.5, 0.62], [0.47, 0.48]].map(
      ([fx, fy]) => [Math.round(size.width * fx), Math.round(size.height * fy)]);
  // The solver settles after a few dozen updates and then idles, so the rates are measured only
  // while it refines: from the second update after a click (the first one includes picking the
  // source) until the server reports it has stopped, or `seconds` per click, for each click.
  const request = (message) => page.evaluate((m) => window.texgrad.request(m), message);
  const counts = () => page.evaluate(() => [window.texgrad.stats.frames, window.texgrad.stats.shown]);
  let steps = 0, frames = 0, shown = 0, active = 0, lastStep = 0, lastFrame = 0;
  for (const point of points) {
    await page.mouse.click(...point);
    const s0 = await waitForState(page, (st) => st.iteration >= 2, 120000);
    const [f0, shown0] = await counts();
    const t0 = Date.now();
    let s1 = s0;
    while (Date.now() - t0 < seconds * 1000) {
      await new Promise((r) => setTimeout(r, 50));
      s1 = await request({ type: "state" });
      if (!s1.running) break;
    }
    const [f1, shown1] = await counts();
    active += (Date.now() - t0) / 1000;
    steps += s1.totalSteps - s0.totalSteps;
    frames += f1 - f0;
    shown += shown1 - shown0;
    lastStep = s1.lastStepSeconds;
    lastFrame = s1.lastFrameSeconds;
  }
  console.log(`geodesic spot 1024^2: server ${(steps / active).toFixed(2)} updates/s ` +
              `(last step ${(lastStep * 1000).toFixed(0)} ms, frame encoding ` +
              `${(lastFrame * 1000).toFixed(1)} ms), page ${(frames / active).toFixed(2)} ` +
              `updates/s received, ${(shown / active).toFixed(2)} shown, over ${steps} updates ` +
              `in ${active.toFixed(1)} s of refinement after ${points.length} clicks`);
  await browser.close();
} finally {
  await stopServer(server);
}
