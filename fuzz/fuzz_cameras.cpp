// Fuzz target for the camera file readers (readCameraFile): the first byte picks the format (modulo
// 3: 0 texgrad's camera JSON; 1 COLMAP's text model, cameras.txt then images.txt after a line
// "#--images--"; 2 an OpenMVS .mvs scene). A JSON or COLMAP file the reader accepts must be
// written by the matching writer and read back to the same cameras (.mvs has no writer).
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>

#include "fuzz_input.h"
#include "texgrad/core/error.h"
#include "texgrad/io/camera_reader.h"
#include "texgrad/io/camera_writer.h"

namespace {

using texgrad::Camera;

/// How far a rotation may move through COLMAP's quaternion and back (a few ulp of entries <= 1).
constexpr double kQuaternionRoundTrip = 1e-12;

/// Aborts (a finding) unless `b` is `a` read back: exactly, except R through a quaternion.
void requireSame(const std::vector<Camera>& a, const std::vector<Camera>& b, bool quaternion) {
  if (a.size() != b.size()) std::abort();
  for (size_t i = 0; i < a.size(); ++i) {
    const Camera &x = a[i], &y = b[i];
    const bool same = x.name == y.name && x.width == y.width && x.height == y.height &&
                      x.fx == y.fx && x.fy == y.fy && x.cx == y.cx && x.cy == y.cy && x.t == y.t &&
                      x.distortion.model == y.distortion.model &&
                      x.distortion.k1 == y.distortion.k1 && x.distortion.k2 == y.distortion.k2 &&
                      x.distortion.p1 == y.distortion.p1 && x.distortion.p2 == y.distortion.p2;
    const double rotation = (x.R - y.R).cwiseAbs().maxCoeff();
    if (!same || !(rotation <= (quaternion ? kQuaternionRoundTrip : 0.0))) std::abort();
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace texgrad;
  if (size < 1) return 0;
  enum Format { Json, Colmap, OpenMvs };
  const auto format = static_cast<Format>(data[0] % 3);
  std::string_view text = fuzz::asText(data + 1, size - 1);
  std::filesystem::path path;
  if (format == Colmap) {
    const std::string_view separator = "\n#--images--\n";
    const size_t split = text.find(separator);
    fuzz::writeScratch(
        "images.txt", split == std::string_view::npos ? "" : text.substr(split + separator.size()));
    path = fuzz::writeScratch("cameras.txt", text.substr(0, split));
  } else {
    path = fuzz::writeScratch(format == Json ? "fuzz.json" : "fuzz.mvs", text);
  }
  std::vector<Camera> cameras;
  try {
    cameras = readCameraFile(path);
  } catch (const Error&) {
    return 0;  // a typed refusal with a message is the expected outcome for a malformed file
  }
  // Accepted: the writer must take it and the reader must give it back.
  if (format == Colmap) {
    writeColmapText(fuzz::scratch() / "written", cameras);
    requireSame(cameras, readCameraFile(fuzz::scratch() / "written"), true);
  } else if (format == Json) {
    writeCameraJson(fuzz::scratch() / "written.json", cameras);
    requireSame(cameras, readCameraFile(fuzz::scratch() / "written.json"), false);
  }
  return 0;
}
