// Which faces of the model the page draws (main.js): a pure function of the decoded mesh, so
// tests/e2e/visible-side.test.mjs checks it under node without a browser.
import * as THREE from "three";

/// The faces to draw: only the outer ones (front or back, by the winding) when the surface is
/// closed and consistently oriented, since its inner sides can never be seen from outside; both
/// otherwise (open surfaces, mirrored or inconsistent winding, degenerate faces). Culling saves
/// a software renderer (SwiftShader) about a fifth of each frame on spot.
export function visibleSide(mesh) {
  const { faces, triangles, positions } = mesh;
  const vertices = positions.length / 3;
  const directed = new Set();  // directed edges, as from * vertices + to
  let volume = 0;
  for (let f = 0; f < faces; ++f) {
    const corner = [triangles[3 * f], triangles[3 * f + 1], triangles[3 * f + 2]];
    if (corner[0] === corner[1] || corner[1] === corner[2] || corner[2] === corner[0])
      return THREE.DoubleSide;
    for (let k = 0; k < 3; ++k) {
      const key = corner[k] * vertices + corner[(k + 1) % 3];
      if (directed.has(key)) return THREE.DoubleSide;  // two faces wound the same way
      directed.add(key);
    }
    const [a, b, c] = corner.map((v) => new THREE.Vector3().fromArray(positions, 3 * v));
    volume += a.dot(b.cross(c));  // 6 x the signed volume of the tetrahedron (origin, a, b, c)
  }
  for (const key of directed) {
    const from = Math.floor(key / vertices), to = key % vertices;
    if (!directed.has(to * vertices + from)) return THREE.DoubleSide;  // an open edge
  }
  if (volume === 0) return THREE.DoubleSide;
  return volume > 0 ? THREE.FrontSide : THREE.BackSide;
}
