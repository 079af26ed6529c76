// Camera fixtures shared by the camera file tests: cameras of every distortion model in general
// poses, and their comparison to the round-trip tolerance.
#pragma once

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <random>
#include <string>
#include <vector>

#include "texgrad/io/camera.h"

namespace texgrad::test {

/// Cameras of every distortion model, in general poses.
inline std::vector<Camera> randomCameras(uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(-1, 1);
  std::vector<Camera> cameras;
  const DistortionModel models[] = {DistortionModel::None, DistortionModel::SimpleRadial,
                                    DistortionModel::Radial, DistortionModel::OpenCV};
  for (int i = 0; i < 8; ++i) {
    Camera c;
    c.name = "photo_" + std::to_string(i) + ".png";
    c.width = 1000 + 7 * i;
    c.height = 700 + 3 * i;
    c.fx = 800 + 100 * unit(rng);
    const DistortionModel model = models[i % 4];
    // The radial models share one focal length (SIMPLE_RADIAL and RADIAL have one).
    const bool radial = model == DistortionModel::SimpleRadial || model == DistortionModel::Radial;
    c.fy = radial ? c.fx : 800 + 100 * unit(rng);
    c.cx = c.width / 2.0 + 10 * unit(rng);
    c.cy = c.height / 2.0 + 10 * unit(rng);
    c.R = Eigen::AngleAxisd(3 * unit(rng),
                            Eigen::Vector3d(unit(rng), unit(rng), unit(rng)).normalized())
              .toRotationMatrix();
    c.t = 10 * Eigen::Vector3d(unit(rng), unit(rng), unit(rng));
    c.distortion.model = model;
    if (model != DistortionModel::None) c.distortion.k1 = 0.1 * unit(rng);
    if (model == DistortionModel::Radial || model == DistortionModel::OpenCV)
      c.distortion.k2 = 0.05 * unit(rng);
    if (model == DistortionModel::OpenCV) {
      c.distortion.p1 = 0.01 * unit(rng);
      c.distortion.p2 = 0.01 * unit(rng);
    }
    cameras.push_back(c);
  }
  return cameras;
}

/// Largest difference a writer -> reader round trip may leave in any camera value.
inline constexpr double kRoundTrip = 1e-12;

/// Expects the same cameras, each value to kRoundTrip.
inline void expectSameCameras(const std::vector<Camera>& got, const std::vector<Camera>& want) {
  ASSERT_EQ(got.size(), want.size());
  for (size_t i = 0; i < want.size(); ++i) {
    SCOPED_TRACE("camera " + std::to_string(i));
    const Camera &a = got[i], &b = want[i];
    EXPECT_EQ(a.name, b.name);
    EXPECT_EQ(a.width, b.width);
    EXPECT_EQ(a.height, b.height);
    EXPECT_NEAR(a.fx, b.fx, kRoundTrip);
    EXPECT_NEAR(a.fy, b.fy, kRoundTrip);
    EXPECT_NEAR(a.cx, b.cx, kRoundTrip);
    EXPECT_NEAR(a.cy, b.cy, kRoundTrip);
    EXPECT_LT((a.R - b.R).cwiseAbs().maxCoeff(), kRoundTrip);
    EXPECT_LT((a.t - b.t).cwiseAbs().maxCoeff(), kRoundTrip);
    EXPECT_EQ(a.distortion.model, b.distortion.model);
    EXPECT_NEAR(a.distortion.k1, b.distortion.k1, kRoundTrip);
    EXPECT_NEAR(a.distortion.k2, b.distortion.k2, kRoundTrip);
    EXPECT_NEAR(a.distortion.p1, b.distortion.p1, kRoundTrip);
    EXPECT_NEAR(a.distortion.p2, b.distortion.p2, kRoundTrip);
  }
}

}  // namespace texgrad::test
