// End-to-end smoke test: stitch app in headless Chromium. A generated composite on builtin:sphere
// (left half of the image from one source, right half from a brighter one) is shown, then the
// stitched result; the page's toggle switches between them, and a lock stroke under the cursor
// re-solves so that the texture there is the composite again (server probes, exact).
// TEXGRAD_E2E_STITCH=bob runs it on the shared multiview_bob composite instead (slower; the
// docs screenshot).
import { mkdirSync, writeFileSync } from "node:fs";
import { join } from "node:path";
import { deflateSync } from "node:zlib";
import { check, openPage, repo, sharedData, startServer, stopServer, waitForState } from "./harness.mjs";

const outDir = process.env.TEXGRAD_E2E_OUT || join(repo, "build", "e2e");
mkdirSync(outDir, { recursive: true });

/// Minimal 8-bit RGB PNG writer (no filter, one zlib stream).
function writePng(path, width, height, rgb) {
  const crcTable = Array.from({ length: 256 }, (_, n) => {
    let c = n;
    for (let k = 0; k < 8; ++k) c = c & 1 ? 0xedb88320 ^ (c >>> 1) : c >>> 1;
    return c >>> 0;
  });
  const crc = (bytes) => {
    let c = 0xffffffff;
    for (const b of bytes) c = crcTable[(c ^ b) & 0xff] ^ (c >>> 8);
    return (c ^ 0xffffffff) >>> 0;
  };
  const chunk = (type, data) => {
    const out = Buffer.alloc(12 + data.length);
    out.writeUInt32BE(data.length, 0);
    out.write(type, 4, "ascii");
    data.copy(out, 8);
    out.writeUInt32BE(crc(out.subarray(4, 8 + data.length)), 8 + data.length);
    return out;
  };
  const header = Buffer.alloc(13);
  header.writeUInt32BE(width, 0);
  header.writeUInt32BE(height, 4);
  header.set([8, 2, 0, 0, 0], 8);  // 8 bits, RGB
  const raw = Buffer.alloc((3 * width + 1) * height);
  for (let y = 0; y < height; ++y)
    for (let i = 0; i < 3 * width; ++i) raw[y * (3 * width + 1) + 1 + i] = rgb[3 * width * y + i];
  writeFileSync(path, Buffer.concat([
    Buffer.from([0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a]), chunk("IHDR", header),
    chunk("IDAT", deflateSync(raw)), chunk("IEND", Buffer.alloc(0))]));
}

/// Composite and segment mask: the right half of the image is 60 levels brighter.
function generatedInputs(size = 256) {
  const composite = new Uint8Array(3 * size * size), segments = new Uint8Array(3 * size * size);
  for (let y = 0; y < size; ++y)
    for (let x = 0; x < size; ++x) {
      const right = x >= size / 2, i = 3 * (y * size + x);
      const shade = 90 + 40 * Math.sin(x / 9) * Math.cos(y / 13);
      composite.set([shade + (right ? 60 : 0), shade * 0.8 + (right ? 60 : 0), 70], i);
      segments.set(right ? [255, 0, 0] : [0, 0, 255], i);
    }
  const c = join(outDir, "stitch-composite.png"), s = join(outDir, "stitch-segments.png");
  writePng(c, size, size, composite);
  writePng(s, size, size, segments);
  return ["builtin:sphere", "--composite", c, "--segments", s];
}

export async function run() {
  const bob = process.env.TEXGRAD_E2E_STITCH === "bob";
  const args = bob
    ? [join(sharedData, "bob", "bob_tri.obj"), "--composite",
       join(sharedData, "multiview_bob", "texels.png"), "--segments",
       join(sharedData, "multiview_bob", "mask.png")]
    : generatedInputs();
  const server = await startServer([...args, "--app", "stitch"]);
  let browser;
  try {
    const opened = await openPage(server.url);
    browser = opened.browser;
    const { page, errors } = opened;
    check(await page.isVisible("#stitch-controls"), "the stitch controls are shown");
    const solved = await waitForState(page, (s) => s.totalSteps >= 1 && !s.running, 120000);
    check(solved.error === "" && solved.residual < 1e-2,
          `stitched in ${solved.lastStepSeconds.toFixed(2)} s, residual ${solved.residual.toExponential(2)}`);
    await page.waitForFunction(() => /solved in/.test(document.getElementById("stats").textContent),
                               null, { timeout: 10000 });
    check(true, "the status line shows the solve time");

    // A point on the model near the canvas centre (bob has a hole there); its value in either
    // texture (probes read the shown one).
    const box = await page.locator("#view canvas").boundingBox();
    let cx, cy, hit = null;
    for (const [dx, dy] of [[0, 0], [0, 0.15], [0, -0.15], [0.15, 0], [-0.15, 0], [0, 0.3]]) {
      [cx, cy] = [box.x + box.width * (0.5 + dx), box.y + box.height * (0.5 + dy)];
      hit = await page.evaluate(([x, y]) => window.texgrad.pick(x, y), [cx, cy]);
      if (hit) break;
    }
    check(hit !== null, `the model is under the cursor (face ${hit && hit.face})`);
    const probe = () => page.evaluate(
        (p) => window.texgrad.request({ type: "probe", points: [p] }).then((r) => r.values[0]), hit);
    const settle = (after) => waitForState(page, (s) => s.totalSteps > after && !s.running, 120000);
    const stitchedValue = await probe();
    let steps = (await waitForState(page, () => true)).totalSteps;
    await page.click("#toggle");
    await settle(steps);
    const compositeValue = await probe();
    await page.waitForTimeout(300);
    await page.screenshot({ path: join(outDir, "viewer-stitch-composite.png") });
    check(await page.textContent("#toggle") === "Show stitched", "the toggle shows the composite");
    check(Math.abs(stitchedValue - compositeValue) > 1e-3,
          `stitching changed the texture under the centre (${compositeValue.toFixed(4)} -> ` +
          `${stitchedValue.toFixed(4)})`);

    // A short lock stroke through the centre: re-solve, the stitched result shown, and the texels
    // under the stroke equal to the composite exactly.
    steps = (await waitForState(page, () => true)).totalSteps;
    await page.mouse.move(cx, cy);
    await page.mouse.down();
    await page.mouse.move(cx + 4, cy, { steps: 2 });
    await page.mouse.up();
    await settle(steps);
    await page.waitForFunction(() => /solved in/.test(document.getElementById("stats").textContent),
                               null, { timeout: 30000 });
    check(await page.textContent("#toggle") === "Show composite", "the page shows the stitched result");
    const locked = await probe();
    check(locked === compositeValue, `locked texels keep the composite value exactly (${locked})`);
    await page.waitForTimeout(300);
    await page.screenshot({ path: join(outDir, "viewer-stitch.png") });
    check(errors.length === 0, `no page errors ${errors.join("; ")}`);
  } finally {
    if (browser) await browser.close();
    await stopServer(server);
  }
}

if (import.meta.url === `file://${process.argv[1]}`) {
  run().then(() => console.log("stitch e2e: passed"),
             (e) => { console.error(e); process.exit(1); });
}
