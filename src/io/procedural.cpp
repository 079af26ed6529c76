// Procedural textured meshes (the built-in sample, the CLI's builtin: meshes and the test
// fixtures) and the sample texture. Every mesh is built from quad-grid charts: 3-D vertices are
// welded through exact integer keys, UVs are per chart, and charts sit apart with gutters.
#include "texgrad/io/procedural.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <map>
#include <numbers>
#include <string>

#include "texgrad/core/error.h"

namespace texgrad::procedural {
namespace {

/// UV distance from the atlas border to the charts, and half the gutter between two charts
/// (gutter 0.06: four texels at 64 x 64, where the smallest sample texture is written).
constexpr double kMargin = 0.03;
/// Radius of the cylinder: circumference 1, so arc length along the cut equals height.
constexpr double kCylinderRadius = 0.5 / std::numbers::pi;
/// Sine of the cones' half angle: 1/2 unrolls each cone to a half disc.
constexpr double kConeSine = 0.5;
/// Torus radii (centre circle and tube) and its grid: charts around the centre circle and tube.
constexpr double kTorusMajor = 1.0;
constexpr double kTorusMinor = 0.4;
constexpr int kTorusSegments = 3;      ///< charts around the centre circle
constexpr int kTorusQuadsAround = 22;  ///< quads per chart along the centre circle
constexpr int kTorusQuadsTube = 16;    ///< quads per chart along half the tube

/// Exact identity of a welded 3-D vertex (lattice coordinates chosen by each builder).
using VertexKey = std::array<int, 3>;

/// Axis-aligned rectangle of the atlas holding one chart.
struct UvRect {
  Eigen::Vector2d lo, hi;
  /// Point at fractions (a, b) of the rectangle's width and height.
  Eigen::Vector2d at(double a, double b) const {
    return {lo.x() + a * (hi.x() - lo.x()), lo.y() + b * (hi.y() - lo.y())};
  }
};

/// Cell (column, row) of a columns x rows atlas, shrunk by kMargin on every side.
UvRect atlasCell(int column, int row, int columns, int rows) {
  const double w = 1.0 / columns, h = 1.0 / rows;
  return {{column * w + kMargin, row * h + kMargin},
          {(column + 1) * w - kMargin, (row + 1) * h - kMargin}};
}

/// Accumulates charts into a TexturedMesh, welding vertices with equal keys.
class MeshBuilder {
 public:
  /// Adds an nu x nv quad grid as one chart. Grid point (i, j), 0 <= i <= nu, 0 <= j <= nv, is
  /// the 3-D vertex key(i, j) at position(i, j) (evaluated once per key) with UV uv(i, j).
  /// Quads are split along their (i, j)-(i+1, j+1) diagonal, corners in increasing-i-then-j
  /// order: counter-clockwise in UV when u grows with i and v with j, and facing along
  /// dP/di x dP/dj in 3-D.
  void addGridChart(int nu, int nv, const std::function<VertexKey(int, int)>& key,
                    const std::function<Eigen::Vector3d(int, int)>& position,
                    const std::function<Eigen::Vector2d(int, int)>& uv) {
    const auto uvBase = static_cast<int32_t>(mesh_.uvs.size());
    std::vector<int32_t> vertexOfPoint;
    for (int j = 0; j <= nv; ++j)
      for (int i = 0; i <= nu; ++i) {
        const auto [it, added] =
            vertexOfKey_.try_emplace(key(i, j), static_cast<int32_t>(mesh_.positions.size()));
        if (added) mesh_.positions.push_back(position(i, j));
        vertexOfPoint.push_back(it->second);
        mesh_.uvs.push_back(uv(i, j));
      }
    auto point = [&](int i, int j) { return j * (nu + 1) + i; };
    auto addTriangle = [&](int a, int b, int c) {
      mesh_.triangles.push_back({vertexOfPoint[static_cast<size_t>(a)],
                                 vertexOfPoint[static_cast<size_t>(b)],
                                 vertexOfPoint[static_cast<size_t>(c)]});
      mesh_.uvTriangles.push_back({uvBase + a, uvBase + b, uvBase + c});
    };
    for (int j = 0; j < nv; ++j)
      for (int i = 0; i < nu; ++i) {
        addTriangle(point(i, j), point(i + 1, j), point(i + 1, j + 1));
        addTriangle(point(i, j), point(i + 1, j + 1), point(i, j + 1));
      }
  }

  TexturedMesh take() { return std::move(mesh_); }

 private:
  TexturedMesh mesh_;
  std::map<VertexKey, int32_t> vertexOfKey_;
};

void requireAtLeast(const char* what, int value, int minimum) {
  if (value < minimum)
    throw InvalidInputError(std::string("procedural mesh: ") + what + " must be at least " +
                            std::to_string(minimum) + " (got " + std::to_string(value) + ")");
}

/// For each face of an n-lattice cube, the lattice axes that grow with u and v: u x v is the
/// outward normal. Face f lies on axis f / 2, on its + side when f is even.
constexpr std::array<std::array<int, 2>, 6> kCubeFaceUvAxes{
    {{1, 2}, {2, 1}, {2, 0}, {0, 2}, {0, 1}, {1, 0}}};

/// UV of grid point (i, j) of an n x n chart of cube face f.
using CubeFaceUv = std::function<Eigen::Vector2d(int f, int i, int j)>;

/// The surface of the lattice cube [0, n]^3 as six charts; `position` maps a lattice point to 3-D
/// and `uv` places each face's grid.
TexturedMesh latticeCube(int n, const std::function<Eigen::Vector3d(const VertexKey&)>& position,
                         const CubeFaceUv& uv) {
  MeshBuilder builder;
  for (int f = 0; f < 6; ++f) {
    const int axis = f / 2;
    const bool plus = f % 2 == 0;
    const int au = kCubeFaceUvAxes[static_cast<size_t>(f)][0];
    const int av = kCubeFaceUvAxes[static_cast<size_t>(f)][1];
    auto key = [&](int i, int j) {
      VertexKey k{};
      k[static_cast<size_t>(axis)] = plus ? n : 0;
      k[static_cast<size_t>(au)] = i;
      k[static_cast<size_t>(av)] = j;
      return k;
    };
    builder.addGridChart(
        n, n, key, [&](int i, int j) { return position(key(i, j)); },
        [&](int i, int j) { return uv(f, i, j); });
  }
  return builder.take();
}

/// Face f's chart in the 3 x 2 atlas of `cube` and `cubeSphere`.
Eigen::Vector2d atlasCubeUv(int n, int f, int i, int j) {
  return atlasCell(f % 3, f / 3, 3, 2).at(double(i) / n, double(j) / n);
}

/// A fixed pseudo-random number in [-1, 1] for key k (SplitMix64 finaliser).
double hashToUnit(uint64_t k) {
  k += 0x9e3779b97f4a7c15ull;
  k = (k ^ (k >> 30)) * 0xbf58476d1ce4e5b9ull;
  k = (k ^ (k >> 27)) * 0x94d049bb133111ebull;
  k ^= k >> 31;
  return 2.0 * static_cast<double>(k >> 11) / static_cast<double>(1ull << 53) - 1.0;
}

/// Point of the torus at angle theta around the centre circle and phi around the tube.
Eigen::Vector3d torusPoint(double theta, double phi) {
  const double ring = kTorusMajor + kTorusMinor * std::cos(phi);
  return {ring * std::cos(theta), ring * std::sin(theta), kTorusMinor * std::sin(phi)};
}

}  // namespace

TexturedMesh square(double su, double sv, double u0, double v0) {
  TexturedMesh mesh;
  for (const auto& [x, y] :
       std::array<std::array<double, 2>, 4>{{{0, 0}, {1, 0}, {1, 1}, {0, 1}}}) {
    mesh.positions.emplace_back(x, y, 0.0);
    mesh.uvs.emplace_back(u0 + su * x, v0 + sv * y);
  }
  // A mirrored UV map (su * sv < 0) reverses the corner order so UV triangles stay
  // counter-clockwise.
  const bool mirrored = su * sv < 0;
  const std::array<Triangle, 2> faces = mirrored ? std::array<Triangle, 2>{{{0, 2, 1}, {0, 3, 2}}}
                                                 : std::array<Triangle, 2>{{{0, 1, 2}, {0, 2, 3}}};
  for (const Triangle& t : faces) {
    mesh.triangles.push_back(t);
    mesh.uvTriangles.push_back(t);
  }
  return mesh;
}

TexturedMesh twoChartSquare(int n) {
  requireAtLeast("the seam edge count", n, 1);
  // Each half is 0.5 x 1 in 3-D, gridded with square quads where n allows, and mapped
  // isometrically (one scale for both halves) into its half of the atlas.
  const int across = std::max(1, (n + 1) / 2);
  const double scale = 1.0 - 4.0 * kMargin;  // the 1-high half fits 0.5 - 2 margins wide
  MeshBuilder builder;
  for (int side = 0; side < 2; ++side) {
    const double uStart = 0.25 + 0.5 * side - 0.25 * scale;
    const double vStart = 0.5 - 0.5 * scale;
    auto x = [&](int i) { return 0.5 * side + 0.5 * i / across; };
    auto y = [&](int j) { return double(j) / n; };
    builder.addGridChart(
        across, n,
        [&](int i, int j) {
          return VertexKey{side * across + i, j, 0};
        },
        [&](int i, int j) { return Eigen::Vector3d(x(i), y(j), 0.0); },
        [&](int i, int j) {
          return Eigen::Vector2d(uStart + scale * (x(i) - 0.5 * side), vStart + scale * y(j));
        });
  }
  return builder.take();
}

TexturedMesh cube(int subdivisions) {
  requireAtLeast("cube subdivisions", subdivisions, 1);
  const double n = subdivisions;
  return latticeCube(
      subdivisions,
      [n](const VertexKey& k) {
        return Eigen::Vector3d(k[0] / n - 0.5, k[1] / n - 0.5, k[2] / n - 0.5);
      },
      [subdivisions](int f, int i, int j) { return atlasCubeUv(subdivisions, f, i, j); });
}

TexturedMesh alignedCube(int subdivisions, double jitter) {
  requireAtLeast("cube subdivisions", subdivisions, 1);
  if (kAlignedCubeChartTexels % subdivisions != 0)
    throw InvalidInputError("procedural mesh: aligned cube subdivisions must divide " +
                            std::to_string(kAlignedCubeChartTexels) + " (got " +
                            std::to_string(subdivisions) + ")");
  if (!(std::abs(jitter) < 1.0))
    throw InvalidInputError("procedural mesh: aligned cube jitter must be below one texel");
  // Chart origins in texel-centre coordinates: 21-texel gutters, all inside the 256^2 image.
  constexpr std::array<int, 3> kColumn{8, 93, 178};
  constexpr std::array<int, 2> kRow{24, 152};
  const int step = kAlignedCubeChartTexels / subdivisions;
  const double n = subdivisions;
  return latticeCube(
      subdivisions,
      [n](const VertexKey& k) {
        return Eigen::Vector3d(k[0] / n - 0.5, k[1] / n - 0.5, k[2] / n - 0.5);
      },
      [&](int f, int i, int j) {
        const auto key =
            static_cast<uint64_t>((f * (subdivisions + 1) + j) * (subdivisions + 1) + i);
        const Eigen::Vector2d texel(
            kColumn[static_cast<size_t>(f % 3)] + step * i + jitter * hashToUnit(2 * key),
            kRow[static_cast<size_t>(f / 3)] + step * j + jitter * hashToUnit(2 * key + 1));
        return Eigen::Vector2d((texel.x() + 0.5) / kAlignedCubeResolution,
                               (texel.y() + 0.5) / kAlignedCubeResolution);
      });
}

TexturedMesh cylinder(int around, int along) {
  requireAtLeast("cylinder segments around", around, 3);
  requireAtLeast("cylinder segments along", along, 1);
  // Unrolled, the cylinder is the unit square (circumference 1, height 1): map it isometrically.
  const UvRect rect = atlasCell(0, 0, 1, 1);
  MeshBuilder builder;
  builder.addGridChart(
      around, along,
      [&](int i, int j) {
        return VertexKey{i % around, j, 0};
      },
      [&](int i, int j) {
        const double angle = 2.0 * std::numbers::pi * i / around;
        return Eigen::Vector3d(kCylinderRadius * std::cos(angle), kCylinderRadius * std::sin(angle),
                               double(j) / along);
      },
      [&](int i, int j) { return rect.at(double(i) / around, double(j) / along); });
  return builder.take();
}

TexturedMesh cubeSphere(int subdivisions) {
  requireAtLeast("sphere subdivisions", subdivisions, 1);
  const double n = subdivisions;
  return latticeCube(
      subdivisions,
      [n](const VertexKey& k) {
        return Eigen::Vector3d(2.0 * k[0] / n - 1.0, 2.0 * k[1] / n - 1.0, 2.0 * k[2] / n - 1.0)
            .normalized();
      },
      [subdivisions](int f, int i, int j) { return atlasCubeUv(subdivisions, f, i, j); });
}

TexturedMesh twoCones(int around, int rings) {
  requireAtLeast("cone segments around", around, 3);
  requireAtLeast("cone rings", rings, 1);
  // Each cone is cut along its generator at angle 0 and unrolled isometrically about the apex:
  // generator i at angle i * beta, beta the apex angle of one facet, so every face (planar,
  // spanned by two generators) keeps its shape. Cone 0 opens towards +z, cone 1 towards -z.
  const double halfAngle = std::asin(kConeSine);
  const double beta = 2.0 * std::asin(kConeSine * std::sin(std::numbers::pi / around));
  // UV radius of a sector (slant 1): two half discs (around * beta < pi) stacked in v.
  const double uvRadius = 0.5 - 2.0 * kMargin;
  TexturedMesh mesh;
  mesh.positions.emplace_back(0.0, 0.0, 0.0);  // the shared apex
  for (int cone = 0; cone < 2; ++cone) {
    const double up = cone == 0 ? 1.0 : -1.0;
    const auto first = static_cast<int32_t>(mesh.positions.size());
    for (int k = 1; k <= rings; ++k)
      for (int i = 0; i < around; ++i) {
        const double theta = 2.0 * std::numbers::pi * i / around, s = double(k) / rings;
        mesh.positions.emplace_back(s * kConeSine * std::cos(theta),
                                    s * kConeSine * std::sin(theta), up * s * std::cos(halfAngle));
      }
    auto vertex = [&](int k, int i) { return k == 0 ? 0 : first + (k - 1) * around + i % around; };
    const Eigen::Vector2d apexUv(0.5, kMargin + cone * (uvRadius + 2.0 * kMargin));
    const auto uvFirst = static_cast<int32_t>(mesh.uvs.size());
    mesh.uvs.push_back(apexUv);
    for (int k = 1; k <= rings; ++k)
      for (int i = 0; i <= around; ++i) {
        const double angle = i * beta, r = uvRadius * k / rings;
        mesh.uvs.push_back(apexUv + r * Eigen::Vector2d(std::cos(angle), std::sin(angle)));
      }
    auto uv = [&](int k, int i) {
      return k == 0 ? uvFirst : uvFirst + 1 + (k - 1) * (around + 1) + i;
    };
    auto add = [&](std::array<std::array<int, 2>, 3> corners) {
      mesh.triangles.push_back({vertex(corners[0][0], corners[0][1]),
                                vertex(corners[1][0], corners[1][1]),
                                vertex(corners[2][0], corners[2][1])});
      mesh.uvTriangles.push_back({uv(corners[0][0], corners[0][1]),
                                  uv(corners[1][0], corners[1][1]),
                                  uv(corners[2][0], corners[2][1])});
    };
    for (int i = 0; i < around; ++i) add({{{0, 0}, {1, i}, {1, i + 1}}});
    for (int k = 1; k < rings; ++k)
      for (int i = 0; i < around; ++i) {
        add({{{k, i}, {k + 1, i}, {k + 1, i + 1}}});
        add({{{k, i}, {k + 1, i + 1}, {k, i + 1}}});
      }
  }
  return mesh;
}

TexturedMesh sampleTorus() {
  // 3 segments around the centre circle x 2 halves of the tube (outer, inner) = 6 charts. Each
  // chart maps (theta, phi) linearly, with theta scaled by its half's mean ring radius so the
  // map is as close to isometric as a rectangle allows. Atlas: one row per segment, outer
  // chart left, inner chart right (the two widths sum to the same in every row).
  const int quadsAround = kTorusSegments * kTorusQuadsAround;
  const int quadsTube = 2 * kTorusQuadsTube;
  const double pi = std::numbers::pi;
  const double meanOffset = kTorusMinor * 2.0 / pi;  // mean of r cos(phi) over a tube half
  const std::array<double, 2> ringRadius{kTorusMajor + meanOffset, kTorusMajor - meanOffset};
  const double thetaSpan = 2.0 * pi / kTorusSegments, phiSpan = pi;
  const double rowWidth = thetaSpan * (ringRadius[0] + ringRadius[1]);
  const double chartHeight = phiSpan * kTorusMinor;
  const double scale =
      std::min((1.0 - 4.0 * kMargin) / rowWidth,
               (1.0 - 2.0 * kTorusSegments * kMargin) / (kTorusSegments * chartHeight));

  MeshBuilder builder;
  for (int segment = 0; segment < kTorusSegments; ++segment)
    for (int half = 0; half < 2; ++half) {
      const int iStart = segment * kTorusQuadsAround;
      const int jStart = -kTorusQuadsTube / 2 + half * kTorusQuadsTube;  // outer half: phi ~ 0
      const double u0 = kMargin + half * (thetaSpan * ringRadius[0] * scale + 2.0 * kMargin);
      const double v0 = (2 * segment + 1) * kMargin + segment * chartHeight * scale;
      auto theta = [&](int i) { return 2.0 * pi * (iStart + i) / quadsAround; };
      auto phi = [&](int j) { return 2.0 * pi * (jStart + j) / quadsTube; };
      builder.addGridChart(
          kTorusQuadsAround, kTorusQuadsTube,
          [&](int i, int j) {
            return VertexKey{(iStart + i) % quadsAround, (jStart + j + quadsTube) % quadsTube, 0};
          },
          [&](int i, int j) { return torusPoint(theta(i), phi(j)); },
          [&](int i, int j) {
            return Eigen::Vector2d(
                u0 + scale * ringRadius[static_cast<size_t>(half)] * (theta(i) - theta(0)),
                v0 + scale * kTorusMinor * (phi(j) - phi(0)));
          });
    }
  return builder.take();
}

Image sampleTexture(int width, int height) {
  requireAtLeast("texture width", width, 1);
  requireAtLeast("texture height", height, 1);
  // An 8 x 8 checker over a hue gradient, with an upright "F" in every cell: the F is
  // asymmetric under every flip and rotation, so a wrong v-flip or a mirrored chart shows.
  constexpr int kCells = 8;
  constexpr float kLevels = 255.0f;  // values sit exactly on 8-bit levels: lossless as PNG
  auto inBox = [](double x, double y, double x0, double x1, double y0, double y1) {
    return x >= x0 && x < x1 && y >= y0 && y < y1;
  };
  Image image(width, height, 3, PixelFormat::UInt8);
  for (int j = 0; j < height; ++j)
    for (int i = 0; i < width; ++i) {
      const double u = (i + 0.5) / width, v = (j + 0.5) / height;
      const double cu = u * kCells, cv = v * kCells;
      const double x = cu - std::floor(cu), y = cv - std::floor(cv);  // position in the cell
      const bool dark = (static_cast<int>(cu) + static_cast<int>(cv)) % 2 == 1;
      const bool glyph = inBox(x, y, 0.30, 0.42, 0.18, 0.82) ||  // stem
                         inBox(x, y, 0.30, 0.72, 0.70, 0.82) ||  // top bar
                         inBox(x, y, 0.30, 0.62, 0.44, 0.55);    // middle bar
      std::array<double, 3> rgb{0.15 + 0.8 * u, 0.15 + 0.7 * v,
                                0.55 + 0.4 * std::sin(2.0 * std::numbers::pi * (u + 0.5 * v))};
      const double shade = glyph ? 0.15 : (dark ? 0.7 : 1.0);
      for (int c = 0; c < 3; ++c) {
        const double value = std::clamp(rgb[static_cast<size_t>(c)] * shade, 0.0, 1.0);
        image.at(i, j, c) = std::round(static_cast<float>(value) * kLevels) / kLevels;
      }
    }
  return image;
}

}  // namespace texgrad::procedural
