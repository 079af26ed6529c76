// Helpers shared by the camera file readers and writers (private to the io module).
#include "camera_formats.h"

#include <Eigen/LU>
#include <array>
#include <charconv>
#include <cmath>
#include <fstream>
#include <iterator>

#include "texgrad/core/error.h"
#include "texgrad/io/atomic_file.h"

namespace texgrad::cameras {

std::string readWholeFile(const std::filesystem::path& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw IoError("cannot open " + path.string() + ": it is a folder, not a camera file");
  std::ifstream in(path, std::ios::binary);
  if (!in)
    throw IoError("cannot open " + path.string() + ": " +
                  (std::filesystem::exists(path, ec) ? "unreadable file" : "no such file") +
                  "; check the path and permissions");
  std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  if (in.bad()) throw IoError("cannot read " + path.string() + "; check the disk");
  return text;
}

void writeTextFile(const std::filesystem::path& path, const std::string& text) {
  writeAtomically(path, [&](const std::filesystem::path& temporary) {
    std::ofstream out(temporary, std::ios::binary);
    out << text;
    out.close();
    if (!out) throw IoError("cannot write " + path.string() + "; check the disk and permissions");
  });
}

bool isRotation(const Eigen::Matrix3d& R) {
  if (!R.allFinite()) return false;
  const double offIdentity =
      (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  return offIdentity <= kRotationTolerance && R.determinant() > 0;
}

std::string formatNumber(double value) {
  std::array<char, 32> buffer{};  // the shortest round-trip form of a double has <= 24 chars
  const auto [end, ec] = std::to_chars(buffer.data(), buffer.data() + buffer.size(), value);
  return std::string(buffer.data(), ec == std::errc() ? end : buffer.data());
}

std::string nameProblem(std::string_view name) {
  if (name.empty()) return "the image name is empty";
  for (char c : name)
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f)
      return "the image name holds a control character (a line break or tab?)";
  if (name.front() == ' ' || name.back() == ' ')
    return "the image name starts or ends with a blank";
  return "";
}

void checkWritable(const Camera& camera, const std::string& where) {
  if (const std::string problem = nameProblem(camera.name); !problem.empty())
    throw InvalidInputError(where + problem);
  if (camera.width <= 0 || camera.height <= 0)
    throw InvalidInputError(where + "the image size must be positive");
  const LensDistortion& d = camera.distortion;
  const bool finite = std::isfinite(camera.fx) && std::isfinite(camera.fy) &&
                      std::isfinite(camera.cx) && std::isfinite(camera.cy) &&
                      camera.t.allFinite() && std::isfinite(d.k1) && std::isfinite(d.k2) &&
                      std::isfinite(d.p1) && std::isfinite(d.p2);
  if (!finite) throw InvalidInputError(where + "a number is not finite");
  if (!(camera.fx > 0 && camera.fy > 0))
    throw InvalidInputError(where + "the focal lengths must be positive");
  if (!isRotation(camera.R)) throw InvalidInputError(where + "R is not a rotation");
}

}  // namespace texgrad::cameras
