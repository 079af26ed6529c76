// Benchmark: updates per second of the geodesic app (spot, 1024²), server side (solver steps)
// and as seen by the page (texture frames received, and uploaded and drawn on the model).
import { join } from "node:path";
import { openPage, sharedData, startServer, stopServer, waitForState } from "./harness.mjs";

const seconds = Number(process.env.TEXGRAD_BENCH_SECONDS || 6);
const server = await startServer([join(sharedData, "spot", "spot_triangulated.obj"),
                                  "--app", "geodesic", "--max-fps", "1000",
                                  "--max-iterations", "100000"]);
try {
  const { browser, page } = await openPage(server.url);
  const size = page.viewportSize();
  const points = [[0.5, 0.5], [0.45, 0.4], [0.55, 0.6]].map(
      ([fx, fy]) => [Math.round(size.width * fx), Math.round(size.height * fy)]);
  await page.mouse.click(...points[0]);
  await waitForState(page, (st) => st.iteration >= 2, 120000);  // skip the source set-up step
  const s0 = await page.evaluate(() => window.texgrad.request({ type: "state" }));
  const counts = () => page.evaluate(() => [window.texgrad.stats.frames, window.texgrad.stats.shown]);
  const [f0, shown0] = await counts();
  const t0 = Date.now();
  await page.waitForTimeout(seconds * 1000);
  const s1 = await page.evaluate(() => window.texgrad.request({ type: "state" }));
  const [f1, shown1] = await counts();
  const elapsed = (Date.now() - t0) / 1000;
  const serverRate = (s1.totalSteps - s0.totalSteps) / elapsed;
  const pageRate = (f1 - f0) / elapsed, shownRate = (shown1 - shown0) / elapsed;
  console.log(`geodesic spot 1024^2: server ${serverRate.toFixed(2)} updates/s ` +
              `(last step ${(s1.lastStepSeconds * 1000).toFixed(0)} ms, frame encoding ` +
              `${(s1.lastFrameSeconds * 1000).toFixed(1)} ms), page ${pageRate.toFixed(2)} ` +
              `updates/s received, ${shownRate.toFixed(2)} shown`);
  await browser.close();
} finally {
  await stopServer(server);
}
