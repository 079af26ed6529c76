// Per-face singular values of the UV -> surface Jacobian, then area-weighted percentiles.
#include "texgrad/atlas/distortion.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

namespace texgrad {
namespace {

struct FaceValue {
  double value, weight;
};

double weightedPercentile(std::vector<FaceValue> values, double fraction) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end(),
            [](const FaceValue& a, const FaceValue& b) { return a.value < b.value; });
  double total = 0.0;
  for (const FaceValue& v : values) total += v.weight;
  double running = 0.0;
  for (const FaceValue& v : values) {
    running += v.weight;
    if (running >= fraction * total) return v.value;
  }
  return values.back().value;
}

}  // namespace

Distortion measureDistortion(const TexturedMesh& mesh) {
  double area3 = 0.0, areaUv = 0.0;
  for (size_t f = 0; f < mesh.faceCount(); ++f) {
    const auto& t = mesh.triangles[f];
    const auto& u = mesh.uvTriangles[f];
    area3 += 0.5 * (mesh.positions[t[1]] - mesh.positions[t[0]])
                       .cross(mesh.positions[t[2]] - mesh.positions[t[0]])
                       .norm();
    const Eigen::Vector2d e1 = mesh.uvs[u[1]] - mesh.uvs[u[0]], e2 = mesh.uvs[u[2]] - mesh.uvs[u[0]];
    areaUv += 0.5 * std::abs(e1.x() * e2.y() - e1.y() * e2.x());
  }
  if (!(area3 > 0.0) || !(areaUv > 0.0)) return {};
  const double s3 = 1.0 / std::sqrt(area3), suv = 1.0 / std::sqrt(areaUv);
  std::vector<FaceValue> conformal, authalic;
  for (size_t f = 0; f < mesh.faceCount(); ++f) {
    const auto& t = mesh.triangles[f];
    const auto& u = mesh.uvTriangles[f];
    Eigen::Matrix<double, 3, 2> p;
    p.col(0) = s3 * (mesh.positions[t[1]] - mesh.positions[t[0]]);
    p.col(1) = s3 * (mesh.positions[t[2]] - mesh.positions[t[0]]);
    Eigen::Matrix2d w;
    w.col(0) = suv * (mesh.uvs[u[1]] - mesh.uvs[u[0]]);
    w.col(1) = suv * (mesh.uvs[u[2]] - mesh.uvs[u[0]]);
    const double det = w.determinant();
    const double faceArea = 0.5 * p.col(0).cross(p.col(1)).norm();
    if (std::abs(det) < 1e-14 || faceArea < 1e-14) continue;
    const Eigen::Matrix<double, 3, 2> jacobian = p * w.inverse();
    const Eigen::Vector2d sigma = Eigen::JacobiSVD<Eigen::Matrix<double, 3, 2>>(jacobian).singularValues();
    if (!(sigma[1] > 0.0)) continue;
    conformal.push_back({std::log(sigma[0] / sigma[1]), faceArea});
    authalic.push_back({std::abs(std::log(sigma[0] * sigma[1])), faceArea});
  }
  return {weightedPercentile(conformal, 0.99), weightedPercentile(authalic, 0.99)};
}

}  // namespace texgrad
