// End-to-end: geodesic app on spot (1024²) in headless Chromium. Clicks the model, waits for the
// solver's frames, then checks from the server's probes that the distance is 0 at the source and
// grows with the distance from it, and from the rendered pixels that the source shows distance 0.
import { mkdirSync } from "node:fs";
import { join } from "node:path";
import { canvasPixel, check, distance3, openPage, repo, sharedData, spearman, startServer,
         stopServer, surfaceSamples, waitForPage, waitForState } from "./harness.mjs";

const outDir = process.env.TEXGRAD_E2E_OUT || join(repo, "build", "e2e");
mkdirSync(outDir, { recursive: true });

/// Server-side values at surface points, in requests of at most 100 points.
async function probe(page, points) {
  const values = [];
  for (let i = 0; i < points.length; i += 100) {
    const reply = await page.evaluate((p) => window.texgrad.request({ type: "probe", points: p }),
                                      points.slice(i, i + 100));
    check(reply.type === "probe", `probe answered (${JSON.stringify(reply).slice(0, 200)})`);
    values.push(...reply.values);
  }
  return values;
}

export async function run() {
  const server = await startServer([join(sharedData, "spot", "spot_triangulated.obj"),
                                    "--app", "geodesic", "--max-iterations", "200"]);
  let browser;
  try {
    const opened = await openPage(server.url);
    browser = opened.browser;
    const { page, errors } = opened;
    const size = page.viewportSize();
    const click = { x: Math.round(size.width * 0.5), y: Math.round(size.height * 0.5) };
    const aimed = await page.evaluate(([x, y]) => window.texgrad.pick(x, y), [click.x, click.y]);
    check(aimed !== null, "the model is under the centre of the view");
    // The server idles before the click (no source yet): every step counted after it is the
    // click's.
    const idle = await waitForState(page, (s) => !s.running, 30000);
    await page.mouse.click(click.x, click.y);
    const source = await waitForPage(page, () => window.texgrad.stats.lastSource, 10000,
                                     "the click to set a source");
    check(source.face >= 0, `the click set a source (face ${source.face})`);
    const state = await waitForState(
        page, (s) => s.totalSteps > idle.totalSteps && !s.running && s.iteration > 0, 90000);
    const settled = await waitForPage(page, (seq) => { const h = window.texgrad.stats.last;
                                                       return h && h.sequence >= seq ? h : null; },
                                      30000, "the page to receive the settled frame",
                                      state.sequence);
    check(state.totalSteps - idle.totalSteps >= 2 && settled.iteration === state.iteration,
          `the page shows the settled frame (iteration ${settled.iteration} of ` +
          `${state.totalSteps - idle.totalSteps} steps after the click)`);
    console.log(`  server: ${state.iteration} steps, residual ${state.residual.toExponential(2)}, ` +
                `${state.updatesPerSecond.toFixed(1)} updates/s`);

    // Server state: distance at the source and at samples over the surface.
    const samples = surfaceSamples(await page.evaluate(() => window.texgrad.faces), 200);
    const values = await probe(page, [source, ...samples]);
    const maxDistance = Math.max(...values.filter((v) => v !== null));
    check(Math.abs(values[0]) < 0.01 * maxDistance,
          `distance at the source ${values[0].toPrecision(3)} is ~0 (max ${maxDistance.toPrecision(3)})`);
    const sourcePoint = await page.evaluate((s) => window.texgrad.surfacePoint(s.face, s.bary), source);
    const euclid = [], geo = [];
    for (let i = 0; i < samples.length; ++i) {
      const v = values[i + 1];
      if (v === null) continue;
      const p = await page.evaluate((s) => window.texgrad.surfacePoint(s.face, s.bary), samples[i]);
      euclid.push(distance3(p, sourcePoint));
      geo.push(v);
    }
    check(geo.length > 150, `${geo.length} of ${samples.length} probes have a value`);
    const rho = spearman(euclid, geo);
    check(rho > 0.85, `distance grows away from the source (Spearman ${rho.toFixed(3)} vs 3-D distance)`);
    const shorter = geo.filter((g, i) => g < 0.9 * euclid[i] - 0.02 * maxDistance).length;
    check(shorter <= geo.length * 0.02, `geodesic >= ~3-D distance (${shorter} exceptions)`);

    // Screenshot: the source pixel shows the colour of distance 0 (red), far pixels do not.
    await page.waitForTimeout(300);
    await page.screenshot({ path: join(outDir, "viewer-geodesic.png") });
    const shown = await page.evaluate((s) => window.texgrad.project(s.face, s.bary), source);
    const at = await canvasPixel(page, shown.x, shown.y + 2);
    check(at[0] > 1.5 * at[2] && at[0] > 100, `pixel at the source is red (rgba ${at})`);
    let far = null, farDistance = -1;
    for (let i = 0; i < samples.length; ++i) {
      const v = values[i + 1];
      if (v === null || v < 0.6 * maxDistance) continue;
      const screen = await page.evaluate((s) => window.texgrad.project(s.face, s.bary), samples[i]);
      const hit = await page.evaluate(([x, y]) => window.texgrad.pick(x, y), [screen.x, screen.y]);
      if (!hit || hit.face !== samples[i].face) continue;  // hidden behind other faces
      if (v > farDistance) { farDistance = v; far = screen; }
    }
    if (far) {
      const px = await canvasPixel(page, far.x, far.y);
      check(px[2] > px[0], `a visible far point (distance ${farDistance.toPrecision(3)}) is blue (rgba ${px})`);
    }
    check(errors.length === 0, `no page errors ${errors.join("; ")}`);
  } finally {
    if (browser) await browser.close();
    await stopServer(server);
  }
}

if (import.meta.url === `file://${process.argv[1]}`) {
  run().then(() => console.log("geodesic e2e: passed"),
             (e) => { console.error(e); process.exit(1); });
}
