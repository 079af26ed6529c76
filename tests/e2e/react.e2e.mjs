// End-to-end smoke test: reaction-diffusion app on spot in headless Chromium. The page's Pause,
// Step and Start buttons drive the time stepper; the page receives a frame per step and shows the
// iteration and residual.
import { mkdirSync } from "node:fs";
import { join } from "node:path";
import { check, openPage, repo, sharedData, startServer, stopServer, waitForState } from "./harness.mjs";

const outDir = process.env.TEXGRAD_E2E_OUT || join(repo, "build", "e2e");
mkdirSync(outDir, { recursive: true });

export async function run() {
  const server = await startServer([join(sharedData, "spot", "spot_triangulated.obj"),
                                    "--app", "react", "--max-iterations", "100000"]);
  let browser;
  try {
    const opened = await openPage(server.url);
    browser = opened.browser;
    const { page, errors } = opened;
    check(await page.isVisible("#react-controls"), "the react controls are shown");
    await waitForState(page, (s) => s.iteration >= 3, 120000);
    await page.click("#pause");
    const paused = await waitForState(page, (s) => s.paused && !s.running, 60000);
    const frames = await page.evaluate(() => window.texgrad.stats.frames);
    await page.click("#step");
    const stepped = await waitForState(
        page, (s) => s.totalSteps === paused.totalSteps + 1 && !s.running, 60000);
    check(stepped.iteration === paused.iteration + 1,
          `Step advances one iteration (${paused.iteration} -> ${stepped.iteration})`);
    await page.waitForFunction((n) => window.texgrad.stats.frames > n, frames, { timeout: 30000 });
    check(true, "the page received the stepped frame");
    check(stepped.residual >= 0 && stepped.residual < 1,
          `residual ${stepped.residual.toExponential(2)} is shown`);
    await page.waitForFunction(() => /iteration \d+/.test(document.getElementById("stats").textContent),
                               null, { timeout: 10000 });
    await page.click("#start");
    await waitForState(page, (s) => s.iteration >= stepped.iteration + 3, 120000);
    check(true, "Start runs on");
    await page.waitForTimeout(300);
    await page.screenshot({ path: join(outDir, "viewer-react.png") });
    check(errors.length === 0, `no page errors ${errors.join("; ")}`);
  } finally {
    if (browser) await browser.close();
    await stopServer(server);
  }
}

if (import.meta.url === `file://${process.argv[1]}`) {
  run().then(() => console.log("react e2e: passed"),
             (e) => { console.error(e); process.exit(1); });
}
