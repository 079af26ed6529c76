// End-to-end: filter app on spot in headless Chromium. Drags a smoothing brush stroke over the
// model and checks, from server-side probes at surface points, that the texture changed near the
// stroke and nowhere far from it.
import { mkdirSync } from "node:fs";
import { join } from "node:path";
import { check, distance3, openPage, repo, sharedData, startServer, stopServer, surfaceSamples,
         waitForState } from "./harness.mjs";

const outDir = process.env.TEXGRAD_E2E_OUT || join(repo, "build", "e2e");
mkdirSync(outDir, { recursive: true });

/// Luminance at surface points, in requests of at most 100 points.
async function probe(page, points) {
  const values = [];
  for (let i = 0; i < points.length; i += 100) {
    const reply = await page.evaluate((p) => window.texgrad.request({ type: "probe", points: p }),
                                      points.slice(i, i + 100));
    if (reply.type !== "probe") throw new Error(`probe failed: ${JSON.stringify(reply)}`);
    values.push(...reply.values);
  }
  return values;
}

export async function run() {
  const server = await startServer([join(sharedData, "spot", "spot_triangulated.obj"),
                                    "--app", "filter"]);
  let browser;
  try {
    const opened = await openPage(server.url);
    browser = opened.browser;
    const { page, errors } = opened;
    await waitForState(page, (s) => !s.running, 60000);
    const faces = await page.evaluate(() => window.texgrad.faces);
    const diameter = await page.evaluate(() => window.texgrad.diameter);
    const samples = surfaceSamples(faces, 400, 7);

    // A short stroke across the middle of the view: strong smoothing brush.
    const size = page.viewportSize();
    const radius = 0.04;
    await page.evaluate((r) => {
      document.getElementById("radius").value = String(r);
      document.getElementById("strength").value = "1";
      document.querySelector("input[name=mode][value=smooth]").checked = true;
    }, radius);
    const y = Math.round(size.height * 0.5);
    const xs = [0.46, 0.48, 0.5, 0.52, 0.54].map((f) => Math.round(size.width * f));
    const stroke = [], strokeHits = [];
    for (const x of xs) {
      const hit = await page.evaluate(([px, py]) => window.texgrad.pick(px, py), [x, y]);
      check(hit !== null, `stroke point (${x}, ${y}) lies on the model`);
      strokeHits.push(hit);
      stroke.push(await page.evaluate((h) => window.texgrad.surfacePoint(h.face, h.bary), hit));
    }
    const strokeBefore = await probe(page, strokeHits);
    const before = await probe(page, samples);
    await page.mouse.move(xs[0], y);
    await page.mouse.down();
    for (const x of xs.slice(1)) {
      await page.waitForTimeout(60);
      await page.mouse.move(x, y, { steps: 3 });
    }
    await page.waitForTimeout(60);
    await page.mouse.up();
    await page.waitForTimeout(200);
    const state = await waitForState(page, (s) => !s.running && s.iteration > 0, 90000);
    console.log(`  server: ${state.iteration} steps after the stroke, residual ` +
                `${state.residual.toExponential(2)}, ${state.updatesPerSecond.toFixed(1)} updates/s`);
    await page.screenshot({ path: join(outDir, "viewer-filter.png") });
    const after = await probe(page, samples);

    // Distance of every sample to the stroke (3-D, model units; radius is a fraction of the
    // bounding-box diagonal, the page's diameter is the bounding sphere's).
    const points = [];
    for (const s of samples) points.push(await page.evaluate((h) => window.texgrad.surfacePoint(h.face, h.bary), s));
    const brushRadius = radius * diameter;
    let near = 0, nearChanged = 0, farChanged = 0, far = 0, maxFarChange = 0;
    for (let i = 0; i < samples.length; ++i) {
      if (before[i] === null || after[i] === null) continue;
      const d = Math.min(...stroke.map((q) => distance3(points[i], q)));
      const change = Math.abs(after[i] - before[i]);
      if (d < 0.5 * brushRadius) {
        ++near;
        if (change > 1 / 255) ++nearChanged;
      } else if (d > 2.5 * brushRadius) {
        ++far;
        maxFarChange = Math.max(maxFarChange, change);
        if (change > 1.5 / 255) ++farChanged;
      }
    }
    console.log(`  ${near} samples near the stroke, ${far} far from it`);
    check(far > 100, "enough samples far from the stroke");
    check(farChanged === 0, `texture unchanged far from the stroke (max change ${(maxFarChange * 255).toFixed(2)}/255)`);
    // Near the stroke: the texture under the stroke itself changed.
    const strokeAfter = await probe(page, strokeHits);
    const changedOnStroke = strokeAfter.filter((v, i) => Math.abs(v - strokeBefore[i]) > 1 / 255).length;
    check(changedOnStroke >= 3, `${changedOnStroke} of ${strokeHits.length} points under the stroke changed`);
    console.log(`  ${nearChanged} of ${near} random samples near the stroke changed`);
    check(errors.length === 0, `no page errors ${errors.join("; ")}`);
  } finally {
    if (browser) await browser.close();
    await stopServer(server);
  }
}

if (import.meta.url === `file://${process.argv[1]}`) {
  run().then(() => console.log("filter e2e: passed"),
             (e) => { console.error(e); process.exit(1); });
}
