// Unit test of the page's face culling choice (viewer/src/visible_side.js), under node: closed and
// consistently wound surfaces draw their outer side only; anything else draws both sides.
import assert from "node:assert/strict";
import { createRequire } from "node:module";
import { join } from "node:path";
import { repo } from "./harness.mjs";
import { visibleSide } from "../../viewer/src/visible_side.js";

const THREE = createRequire(join(repo, "viewer", "package.json"))("three");

// A tetrahedron with outward (counter-clockwise seen from outside) faces.
const positions = new Float32Array([0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1]);
const outward = [0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3];
const mesh = (triangles) => ({ faces: triangles.length / 3, triangles: new Uint32Array(triangles),
                               positions });
const flip = (triangles) => triangles.map((v, i) => triangles[i - (i % 3) + 2 - (i % 3)]);

const cases = [
  ["closed, outward", mesh(outward), THREE.FrontSide],
  ["closed, inward (every face flipped)", mesh(flip(outward)), THREE.BackSide],
  ["open (one face missing)", mesh(outward.slice(0, 9)), THREE.DoubleSide],
  ["inconsistent (one face flipped)",
   mesh([...flip(outward.slice(0, 3)), ...outward.slice(3)]), THREE.DoubleSide],
  ["degenerate face", mesh([...outward, 0, 0, 1]), THREE.DoubleSide],
];
for (const [name, input, expected] of cases) {
  assert.equal(visibleSide(input), expected, name);
  console.log(`ok  ${name}`);
}
