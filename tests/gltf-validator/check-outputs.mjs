// CTest GltfOutputsValidate: texgrad's glTF write-back is self-contained. A .gltf and a .glb
// written from Avocado (external images), moved to another folder, validate with the Khronos
// glTF validator (no errors); so does BoomBox's write-back, whose source lacks its
// occlusion/roughness/metallic image: the write warns once naming it (not under --quiet) and the
// copy leaves that texture out. The unmoved BoomBox source must fail validation (the missing
// file is reported), which shows the check sees a dangling URI. A two-material asset (two
// primitives, two base-colour images, gltf_write_pages) validates, and so do its .gltf and .glb
// write-backs replacing both images at once, after the move; so do the CLI's .gltf and .glb
// write-backs of that asset with a material on every primitive (`texgrad filter`: its two
// base-colour images are two texture pages, each replaced by its filtered page).
// Environment: TEXGRAD_CLI, TEXGRAD_WRITE_PAGES, TEXGRAD_SHARED_DATA, TEXGRAD_VALIDATOR_OUT (a
// scratch folder).
import { spawnSync } from "node:child_process";
import fs from "node:fs";
import path from "node:path";
import validator from "gltf-validator";

const cli = process.env.TEXGRAD_CLI;
const writePages = process.env.TEXGRAD_WRITE_PAGES;
const data = process.env.TEXGRAD_SHARED_DATA;
const scratch = process.env.TEXGRAD_VALIDATOR_OUT;
let failures = 0;

function check(condition, message) {
  if (!condition) {
    console.error("FAIL: " + message);
    failures += 1;
  }
}

/// Runs texgrad in `cwd`; returns its exit status and stderr.
function texgrad(args, cwd) {
  const run = spawnSync(cli, args, { cwd, encoding: "utf8" });
  return { status: run.status, err: run.stderr };
}

/// The validator's report for `file`; external resources resolve from the file's own folder.
async function validate(file) {
  const bytes = new Uint8Array(fs.readFileSync(file));
  return validator.validateBytes(bytes, {
    uri: path.basename(file),
    maxIssues: 0,
    externalResourceFunction: (uri) =>
      new Promise((resolve, reject) => {
        const resource = path.resolve(path.dirname(file), decodeURIComponent(uri));
        fs.readFile(resource, (error, content) => (error ? reject(error) : resolve(content)));
      }),
  });
}

/// Moves `file` into `folder` and expects it to validate without errors.
async function expectValidAfterMove(file, folder) {
  fs.mkdirSync(folder, { recursive: true });
  const target = path.join(folder, path.basename(file));
  fs.renameSync(file, target);
  const report = await validate(target);
  const errors = report.issues.messages.filter((m) => m.severity === 0);
  for (const e of errors) console.error(`  ${target}: ${e.code} ${e.pointer ?? ""} ${e.message}`);
  check(report.issues.numErrors === 0,
        `${target} has ${report.issues.numErrors} validation errors after the move`);
  console.log(`${target}: ${report.issues.numErrors} errors, ${report.issues.numWarnings} ` +
              `warnings, ${report.info?.resources?.length ?? 0} resources`);
}

fs.rmSync(scratch, { recursive: true, force: true });
const written = path.join(scratch, "written");
// Deeper than `written`, so a path relative to the source folder cannot resolve from both.
const moved = path.join(scratch, "moved", "to", "another", "folder");
fs.mkdirSync(written, { recursive: true });

const avocado = path.join(data, "Avocado/glTF/Avocado.gltf");
for (const name of ["avocado.gltf", "avocado.glb"]) {
  const run = texgrad(["dilate", avocado, "--radius", "1", "--quiet", "-o", name], written);
  check(run.status === 0 && run.err === "", `dilate to ${name}: status ${run.status}: ${run.err}`);
  if (run.status === 0) await expectValidAfterMove(path.join(written, name), moved);
}

const boomBox = path.join(data, "BoomBox/glTF/BoomBox.gltf");
const missing = "BoomBox_occlusionRoughnessMetallic.png";
const source = await validate(boomBox);
check(source.issues.numErrors > 0, `the BoomBox source (missing ${missing}) validates: the check is blind`);
const quiet = texgrad(["dilate", boomBox, "--radius", "1", "--quiet", "-o", "quiet.gltf"], written);
check(quiet.status === 0 && quiet.err === "", `--quiet BoomBox: status ${quiet.status}: ${quiet.err}`);
const box = texgrad(["dilate", boomBox, "--radius", "1", "-o", "boombox.gltf"], written);
const warnings = box.err.split("\n").filter((line) => line.includes("warning"));
check(box.status === 0, `BoomBox write-back: status ${box.status}: ${box.err}`);
check(warnings.length === 1 && warnings[0].includes(missing),
      `expected one warning naming ${missing}, got: ${box.err}`);
if (box.status === 0) await expectValidAfterMove(path.join(written, "boombox.gltf"), moved);

const pagesDir = path.join(scratch, "pages");
const pages = spawnSync(writePages, [pagesDir], { encoding: "utf8" });
check(pages.status === 0 && pages.stdout.startsWith("2 base-colour images replaced"),
      `gltf_write_pages: status ${pages.status}: ${pages.stdout}${pages.stderr}`);
if (pages.status === 0) {
  const fixture = await validate(path.join(pagesDir, "source", "two.gltf"));
  check(fixture.issues.numErrors === 0,
        `the two-material source has ${fixture.issues.numErrors} validation errors`);
  for (const name of ["pages.gltf", "pages.glb"])
    await expectValidAfterMove(path.join(pagesDir, name), path.join(moved, "pages"));
  const every = path.join(pagesDir, "source", "every.gltf");
  for (const name of ["cli-pages.gltf", "cli-pages.glb"]) {
    const run = texgrad(["filter", every, "--beta", "0.3", "--quiet", "-o", name], written);
    check(run.status === 0 && run.err === "", `filter to ${name}: status ${run.status}: ${run.err}`);
    if (run.status === 0) await expectValidAfterMove(path.join(written, name), moved);
  }
}

if (failures > 0) {
  console.error(`${failures} check(s) failed`);
  process.exit(1);
}
console.log("all glTF outputs validate after the move");
