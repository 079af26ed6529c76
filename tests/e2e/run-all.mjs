// Runs every viewer end-to-end test in sequence; exit status 1 if any fails.
// Usage: node tests/e2e/run-all.mjs (TEXGRAD_CLI, TEXGRAD_SHARED_DATA, CHROMIUM override paths).
import { run as geodesic } from "./geodesic.e2e.mjs";
import { run as filter } from "./filter.e2e.mjs";
import { run as react } from "./react.e2e.mjs";
import { run as stitch } from "./stitch.e2e.mjs";

let failed = 0;
const tests = [["geodesic", geodesic], ["filter", filter], ["react", react], ["stitch", stitch]];
for (const [name, test] of tests) {
  const start = Date.now();
  console.log(`== viewer e2e: ${name}`);
  try {
    await test();
    console.log(`== ${name}: passed (${((Date.now() - start) / 1000).toFixed(1)} s)`);
  } catch (error) {
    ++failed;
    console.error(`== ${name}: FAILED\n${error.stack || error}`);
  }
}
process.exit(failed ? 1 : 0);
