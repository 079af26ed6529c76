// Procedural textured meshes built in code: the built-in sample and the unit-test fixtures.
#pragma once

#include "texgrad/io/image.h"
#include "texgrad/io/textured_mesh.h"

namespace texgrad::procedural {

/// Unit square [0,1]^2 in the plane z = 0 as two triangles, UV = (x * su + u0, y * sv + v0).
TexturedMesh square(double su = 1.0, double sv = 1.0, double u0 = 0.0, double v0 = 0.0);
/// A flat square split into two charts along x = 0.5, packed side by side in UV with a gutter:
/// one seam of `n` edges.
TexturedMesh twoChartSquare(int n = 4);
/// Unit cube with one chart per face (6 charts, 12 seams edges per side), packed in a 3x2 atlas.
TexturedMesh cube(int subdivisions = 4);
/// Texture size at which alignedCube's UVs lie on texel centres.
inline constexpr int kAlignedCubeResolution = 256;
/// Texels per side of each alignedCube chart at kAlignedCubeResolution.
inline constexpr int kAlignedCubeChartTexels = 64;
/// Unit cube as six 64 x 64-texel charts of a 256 x 256 texture (3 x 2 atlas): at that size every
/// UV is a texel centre, so chart edges run on lattice lines; each UV is then moved by a fixed
/// pseudo-random offset of at most `jitter` texels per coordinate. `subdivisions` divides 64.
TexturedMesh alignedCube(int subdivisions = 4, double jitter = 0.0);
/// Open cylinder (radius 1/(2π), height 1) cut along one generator: one chart, one seam.
TexturedMesh cylinder(int around = 32, int along = 16);
/// Unit sphere as a projected cube: 6 charts in a 3x2 atlas with gutters (the geodesic fixture).
TexturedMesh cubeSphere(int subdivisions = 16);
/// Two cones (half angle 30 degrees, slant 1, `around` facets, `rings` rings) joined only at
/// their common apex, a non-manifold vertex (index 0): cone 0 opens towards +z, cone 1 towards
/// -z. Each is one chart, cut along one generator (one seam) and unrolled isometrically to a
/// half disc about its apex, so the geodesic distance from the apex is |p| on both cones.
TexturedMesh twoCones(int around = 32, int rings = 8);
/// Torus with several charts and gutters: the built-in sample for the demo command.
TexturedMesh sampleTorus();
/// A colourful procedural texture for the sample (asymmetric so flips and seams show).
Image sampleTexture(int width, int height);

}  // namespace texgrad::procedural
