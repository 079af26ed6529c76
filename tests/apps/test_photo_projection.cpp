// Photo projection (issue 29): projected positions against an independent projection, occlusion
// and back faces, and a synthetic capture of spot stitched back to its true texture.
#include <gtest/gtest.h>

#include <Eigen/LU>

#include "photo_renderer.h"
#include "photo_scene.h"
#include "test_paths.h"
#include "texgrad/apps/photo_projection.h"
#include "texgrad/apps/stitch.h"
#include "texgrad/io/image_io.h"
#include "texgrad/io/mesh_reader.h"

namespace texgrad {
namespace {

TexturedMesh spot() {
  return readMesh(test::sharedData() / "spot/spot_triangulated.obj");
}

/// A photo whose pixels hold their own COLMAP pixel coordinates (x, y, 0): projecting it gives
/// every texel's projected position.
Image pixelCoordinatePhoto(int width, int height) {
  Image photo(width, height, 3, PixelFormat::Float);
  for (int j = 0; j < height; ++j)
    for (int i = 0; i < width; ++i) {
      photo.at(i, j, 0) = static_cast<float>(i + 0.5);
      photo.at(i, j, 1) = static_cast<float>(height - j - 0.5);  // texel row j from the bottom
    }
  return photo;
}

/// Per unknown whose texel centre lies in a UV triangle: its 3-D point, found from the mesh's
/// UVs directly (not through the texel basis); NaN rows for the others.
Eigen::MatrixX3d centrePoints(const TexelDomain& domain) {
  const TexturedMesh& mesh = domain.mesh();
  const TexelGrid& grid = domain.grid();
  Eigen::MatrixX3d points =
      Eigen::MatrixX3d::Constant(grid.unknownCount(), 3, std::numeric_limits<double>::quiet_NaN());
  for (size_t f = 0; f < mesh.triangles.size(); ++f) {
    Eigen::Vector2d c[3];
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector2d& uv = mesh.uvs[static_cast<size_t>(mesh.uvTriangles[f][k])];
      c[k] = {uv.x() * grid.imageWidth - 0.5 - grid.x0, uv.y() * grid.imageHeight - 0.5 - grid.y0};
    }
    Eigen::Matrix2d e;
    e << c[1] - c[0], c[2] - c[0];
    if (std::abs(e.determinant()) < 1e-12) continue;
    const Eigen::Matrix2d inverse = e.inverse();
    for (int y = std::max(0, static_cast<int>(std::min({c[0].y(), c[1].y(), c[2].y()})));
         y <= std::min(grid.ny - 1, static_cast<int>(std::max({c[0].y(), c[1].y(), c[2].y()})) + 1);
         ++y)
      for (int x = std::max(0, static_cast<int>(std::min({c[0].x(), c[1].x(), c[2].x()})));
           x <=
           std::min(grid.nx - 1, static_cast<int>(std::max({c[0].x(), c[1].x(), c[2].x()})) + 1);
           ++x) {
        const int32_t u = grid.unknownOfTexel[static_cast<size_t>(grid.texelIndex(x, y))];
        if (u < 0 || !std::isnan(points(u, 0))) continue;
        const Eigen::Vector2d st = inverse * (Eigen::Vector2d(x, y) - c[0]);
        if (st.minCoeff() < 1e-6 || st.sum() > 1.0 - 1e-6) continue;  // strictly inside only
        const auto& t = mesh.triangles[f];
        points.row(u) = ((1.0 - st.sum()) * mesh.positions[static_cast<size_t>(t[0])] +
                         st.x() * mesh.positions[static_cast<size_t>(t[1])] +
                         st.y() * mesh.positions[static_cast<size_t>(t[2])])
                            .transpose();
      }
  }
  return points;
}

/// Largest distance between the projected position the projector samples and the independent
/// projection of the texel's surface point, over seen texels at least 2 pixels inside the photo;
/// `compared` receives how many texels were compared.
double worstPositionError(const TexelDomain& domain, const Camera& camera, int& compared) {
  const PhotoProjector projector(domain);
  const PhotoProjection view =
      projector.project(camera, pixelCoordinatePhoto(camera.width, camera.height));
  const Eigen::MatrixX3d points = centrePoints(domain);
  const Eigen::MatrixXd sampled = gatherTexels(domain.grid(), view.partial);
  const Eigen::MatrixXd confidence = gatherTexels(domain.grid(), view.confidence);
  double worst = 0.0;
  compared = 0;
  for (int u = 0; u < domain.unknowns(); ++u) {
    const int texel = domain.grid().texelOfUnknown[static_cast<size_t>(u)];
    if (!(confidence(u, 0) > 0.0) || std::isnan(points(u, 0)) ||
        !domain.grid().inImage(texel % domain.grid().nx, texel / domain.grid().nx))
      continue;
    const Eigen::Vector2d expected = test::projectIndependently(camera, points.row(u).transpose());
    if (expected.minCoeff() < 2.0 || expected.x() > camera.width - 2.0 ||
        expected.y() > camera.height - 2.0)
      continue;
    worst = std::max(worst, (sampled.row(u).head<2>().transpose() - expected).norm());
    ++compared;
  }
  return worst;
}

TEST(PhotoProjection, ProjectedPositionMatchesIndependentProjection) {
  const TexelDomain domain(spot(), 256, 256);
  const test::Capture capture = test::captureAround(domain.mesh(), 2, 320, 240);
  for (const Camera& camera : capture.cameras) {  // view 1 has radial distortion
    int compared = 0;
    const double worst = worstPositionError(domain, camera, compared);
    EXPECT_GT(compared, 2000) << camera.name;
    EXPECT_LT(worst, 0.05) << camera.name << ": projected position off by " << worst << " px";
  }
}

/// A square [x0, x1] x [-1, 1] at height z, facing +z (or -z), with its UVs in [u0, u1] x
/// [0.05, 0.95], added to `mesh`.
void addSquare(TexturedMesh& mesh, double x0, double x1, double z, bool facingUp, double u0,
               double u1) {
  const auto base = static_cast<int32_t>(mesh.positions.size());
  mesh.positions.insert(mesh.positions.end(), {{x0, -1, z}, {x1, -1, z}, {x1, 1, z}, {x0, 1, z}});
  mesh.uvs.insert(mesh.uvs.end(), {{u0, 0.05}, {u1, 0.05}, {u1, 0.95}, {u0, 0.95}});
  const Triangle a{base, base + 1, base + 2}, b{base, base + 2, base + 3};
  const Triangle af{base, base + 2, base + 1}, bf{base, base + 3, base + 2};
  mesh.triangles.push_back(facingUp ? a : af);
  mesh.triangles.push_back(facingUp ? b : bf);
  mesh.uvTriangles.push_back(facingUp ? a : af);
  mesh.uvTriangles.push_back(facingUp ? b : bf);
}

TEST(PhotoProjection, HiddenAndBackFacingTexelsGetZeroConfidence) {
  // Back square z = 0, x in [-1, 1]; front square z = 1, x in [-1, 0]; a square facing away.
  // From (0, 0, 4) the front square hides exactly the back square's x < 0 half.
  TexturedMesh mesh;
  addSquare(mesh, -1.0, 1.0, 0.0, true, 0.02, 0.32);
  addSquare(mesh, -1.0, 0.0, 1.0, true, 0.36, 0.64);
  addSquare(mesh, 1.2, 2.0, 0.0, false, 0.68, 0.98);
  const TexelDomain domain(std::move(mesh), 256, 128);
  const Camera camera = test::lookAtCamera("top.png", {0.0, 0.0, 4.0}, Eigen::Vector3d::Zero(),
                                           Eigen::Vector3d::UnitY(), 400, 300, 250.0);
  const PhotoProjector projector(domain);
  const PhotoProjection view = projector.project(camera, Image(400, 300, 3));
  const Eigen::MatrixXd confidence = gatherTexels(domain.grid(), view.confidence);
  constexpr double kMargin = 0.05;  // model units, about 3 texels of the back square
  int hidden = 0, visible = 0, away = 0;
  for (int u = 0; u < domain.unknowns(); ++u) {
    const Eigen::Vector3d p = projector.points().position.row(u).transpose();
    const double c = confidence(u, 0);
    if (p.x() > 1.1) {
      EXPECT_EQ(c, 0.0) << "back-facing texel at " << p.transpose();
      ++away;
    } else if (p.z() < 0.5 && p.x() < -kMargin) {
      EXPECT_EQ(c, 0.0) << "hidden texel at " << p.transpose();
      ++hidden;
    } else if (p.x() > kMargin || p.z() > 0.5) {
      EXPECT_GT(c, 0.0) << "visible texel at " << p.transpose();
      ++visible;
    }
  }
  EXPECT_GT(hidden, 1000);
  EXPECT_GT(visible, 2000);
  EXPECT_GT(away, 500);
}

TEST(PhotoProjection, MaskBlackRemovesTexelsWhiteKeepsThem) {
  TexturedMesh mesh;
  addSquare(mesh, -1.0, 1.0, 0.0, true, 0.05, 0.95);
  const TexelDomain domain(std::move(mesh), 128, 128);
  const Camera camera = test::lookAtCamera("top.png", {0.0, 0.0, 4.0}, Eigen::Vector3d::Zero(),
                                           Eigen::Vector3d::UnitY(), 400, 300, 250.0);
  Image mask(400, 300, 1);
  for (int j = 0; j < 300; ++j)
    for (int i = 200; i < 400; ++i) mask.at(i, j) = 1.0f;  // right half usable
  const PhotoProjector projector(domain);
  const Image photo(400, 300, 3);
  const Eigen::MatrixXd whole =
      gatherTexels(domain.grid(), projector.project(camera, photo).confidence);
  const Eigen::MatrixXd masked =
      gatherTexels(domain.grid(), projector.project(camera, photo, &mask).confidence);
  int removed = 0, kept = 0;
  for (int u = 0; u < domain.unknowns(); ++u) {
    const double x =
        test::projectIndependently(camera, projector.points().position.row(u).transpose()).x();
    if (x < 199.0) {
      EXPECT_EQ(masked(u, 0), 0.0);
      removed += whole(u, 0) > 0.0;
    } else if (x > 201.0) {
      EXPECT_EQ(masked(u, 0), whole(u, 0));
      kept += whole(u, 0) > 0.0;
    }
  }
  EXPECT_GT(removed, 1000);
  EXPECT_GT(kept, 1000);
}

TEST(PhotoProjection, SyntheticCaptureStitchesToTheTrueTextureSlow) {
  // Truth: spot's texture at the atlas resolution, band-limited (box filter, then two tent
  // passes); eight views of 320 x 320 pixels, every other one with radial distortion.
  const TexelDomain domain(spot(), 256, 256);
  const Image truth = test::tentBlur(
      test::boxDownsample(readImage(test::sharedData() / "spot/spot_texture.png"), 256, 256), 2);
  const test::Capture capture = test::captureAround(domain.mesh(), 8, 320, 320);
  const PhotoProjector projector(domain);
  std::vector<Image> partials, confidences;
  BestViewComposite best;
  for (size_t k = 0; k < capture.cameras.size(); ++k) {
    const Image photo =
        test::renderPhoto(domain.mesh(), truth, capture.cameras[k], capture.looks[k]);
    PhotoProjection view = projector.project(capture.cameras[k], photo);
    EXPECT_GT(view.seenTexels, 1000) << capture.cameras[k].name;
    best.add(view, static_cast<int>(k));
    partials.push_back(std::move(view.partial));
    confidences.push_back(std::move(view.confidence));
  }
  const StitchResult stitched = stitchPartials(domain, partials, confidences, {});
  const double stitchedError = test::fittedRms(domain, stitched.image, truth, best.confidence);
  const double compositeError = test::fittedRms(domain, best.composite, truth, best.confidence);
  const double stitchedJump =
      test::regionBoundaryJump(domain, stitched.image, truth, best.segments);
  const double compositeJump =
      test::regionBoundaryJump(domain, best.composite, truth, best.segments);
  std::cout << "fitted RMS: stitched " << stitchedError << ", best-view composite "
            << compositeError << "; region-boundary jump: stitched " << stitchedJump
            << ", composite " << compositeJump << "\n";
  EXPECT_LE(stitchedError, compositeError / 3.0);
  EXPECT_LE(stitchedJump, compositeJump / 10.0);
}

}  // namespace
}  // namespace texgrad
