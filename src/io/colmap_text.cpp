// COLMAP's text model (cameras.txt + images.txt) read into Camera values and written from them.
//
// cameras.txt: CAMERA_ID MODEL WIDTH HEIGHT PARAMS[] per line; images.txt: two lines per image,
// IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME (Hamilton quaternion and translation world ->
// camera) and the image's 2-D points (X Y POINT3D_ID triples, possibly none). '#' starts a
// comment line. Pixel coordinates as in Camera (origin at the top-left image corner).
#include <Eigen/Geometry>
#include <charconv>
#include <cmath>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <sstream>

#include "camera_formats.h"
#include "texgrad/core/error.h"
#include "texgrad/io/camera_writer.h"

namespace texgrad::cameras {
namespace {

/// How far a quaternion's norm may be from 1 before it is refused rather than normalised: files
/// written with 6 significant digits stay well inside, a misread column does not.
constexpr double kQuaternionNormTolerance = 1e-3;

/// The camera models texgrad applies, with their parameter counts (COLMAP's
/// src/colmap/sensor/models.h).
struct ModelSpec {
  std::string_view name;
  size_t parameters;
  DistortionModel distortion;
};
constexpr ModelSpec kModels[] = {{"SIMPLE_PINHOLE", 3, DistortionModel::None},
                                 {"PINHOLE", 4, DistortionModel::None},
                                 {"SIMPLE_RADIAL", 4, DistortionModel::SimpleRadial},
                                 {"RADIAL", 5, DistortionModel::Radial},
                                 {"OPENCV", 8, DistortionModel::OpenCV}};
/// COLMAP's other models: known, but their lenses are not modelled by LensDistortion.
constexpr std::string_view kOtherColmapModels[] = {"OPENCV_FISHEYE",
                                                   "FULL_OPENCV",
                                                   "FOV",
                                                   "SIMPLE_RADIAL_FISHEYE",
                                                   "RADIAL_FISHEYE",
                                                   "THIN_PRISM_FISHEYE",
                                                   "RAD_TAN_THIN_PRISM_FISHEYE"};

/// One line of a text file with its 1-based number.
struct Line {
  std::string_view text;
  size_t number = 0;
};

/// Iterates over the lines of a text (LF or CRLF).
class LineReader {
 public:
  explicit LineReader(std::string_view text) : text_(text) {}
  /// The next line, or nothing at the end of the text.
  std::optional<Line> next() {
    if (pos_ >= text_.size()) return std::nullopt;
    size_t end = text_.find('\n', pos_);
    if (end == std::string_view::npos) end = text_.size();
    std::string_view line = text_.substr(pos_, end - pos_);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    pos_ = end + 1;
    return Line{line, ++number_};
  }

 private:
  std::string_view text_;
  size_t pos_ = 0, number_ = 0;
};

bool isBlank(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f';
}

std::string_view trim(std::string_view text) {
  while (!text.empty() && isBlank(text.front())) text.remove_prefix(1);
  while (!text.empty() && isBlank(text.back())) text.remove_suffix(1);
  return text;
}

/// The whitespace-separated words of a line; with `limit`, the last word is the rest of the line
/// (trimmed), so that image names may hold spaces.
std::vector<std::string_view> words(std::string_view line,
                                    size_t limit = std::numeric_limits<size_t>::max()) {
  std::vector<std::string_view> out;
  line = trim(line);
  while (!line.empty()) {
    if (out.size() + 1 == limit) {
      out.push_back(line);
      break;
    }
    size_t end = 0;
    while (end < line.size() && !isBlank(line[end])) ++end;
    out.push_back(line.substr(0, end));
    line = trim(line.substr(end));
  }
  return out;
}

/// True for lines that carry no data: blank or '#' comments.
bool skipped(std::string_view line) {
  line = trim(line);
  return line.empty() || line.front() == '#';
}

/// "<file> line <n>: " for messages.
std::string at(const std::filesystem::path& file, size_t line) {
  return file.string() + " line " + std::to_string(line) + ": ";
}

double number(std::string_view word, const std::string& where, std::string_view field) {
  double value = 0;
  const auto [end, ec] = std::from_chars(word.data(), word.data() + word.size(), value);
  const bool whole = end == word.data() + word.size();
  const bool parsed = ec == std::errc() && whole;
  if (!parsed || !std::isfinite(value))
    throw InvalidInputError(where + std::string(field) + " is '" + std::string(word) + "', " +
                            (parsed ? "which is not finite"
                             : ec == std::errc::result_out_of_range && whole
                                 ? "which is out of range"
                                 : "which is not a number") +
                            "; fix the line or re-export the model");
  return value;
}

/// A non-negative integer that fits `max` (ids, image sizes).
uint64_t integer(std::string_view word, const std::string& where, std::string_view field,
                 uint64_t max) {
  uint64_t value = 0;
  const auto [end, ec] = std::from_chars(word.data(), word.data() + word.size(), value);
  if (ec != std::errc() || end != word.data() + word.size() || value > max)
    throw InvalidInputError(where + std::string(field) + " is '" + std::string(word) +
                            "', which is not an integer from 0 to " + std::to_string(max) +
                            "; fix the line or re-export the model");
  return value;
}

/// Intrinsics of one COLMAP camera: a Camera without name and pose.
using Intrinsics = Camera;

const ModelSpec& modelSpec(std::string_view name, const std::string& where) {
  for (const ModelSpec& spec : kModels)
    if (spec.name == name) return spec;
  const std::string supported = "SIMPLE_PINHOLE, PINHOLE, SIMPLE_RADIAL, RADIAL and OPENCV";
  for (std::string_view other : kOtherColmapModels)
    if (other == name)
      throw UnsupportedError(where + "camera model " + std::string(name) +
                             " is not supported (texgrad applies " + supported +
                             "); undistort the photos first (colmap image_undistorter writes "
                             "PINHOLE cameras)");
  throw InvalidInputError(where + "unknown camera model '" + std::string(name) +
                          "'; COLMAP's text model names one of " + supported +
                          " (or another COLMAP model)");
}

/// The intrinsics of a cameras.txt line (already split into words).
Intrinsics parseCameraLine(const std::vector<std::string_view>& w, const std::string& where) {
  if (w.size() < 4)
    throw InvalidInputError(where + "expected CAMERA_ID MODEL WIDTH HEIGHT PARAMS[], found " +
                            std::to_string(w.size()) + " words; fix the line");
  const ModelSpec& spec = modelSpec(w[1], where);
  if (w.size() != 4 + spec.parameters)
    throw InvalidInputError(where + "camera model " + std::string(spec.name) + " has " +
                            std::to_string(spec.parameters) + " parameters, the line gives " +
                            std::to_string(w.size() - 4) + "; fix the line");
  constexpr uint64_t kMaxSize = std::numeric_limits<int>::max();
  Intrinsics c;
  c.width = static_cast<int>(integer(w[2], where, "WIDTH", kMaxSize));
  c.height = static_cast<int>(integer(w[3], where, "HEIGHT", kMaxSize));
  if (c.width == 0 || c.height == 0)
    throw InvalidInputError(where + "the image size is " + std::to_string(c.width) + " x " +
                            std::to_string(c.height) + "; it must be positive");
  std::vector<double> p;
  for (size_t k = 0; k < spec.parameters; ++k)
    p.push_back(number(w[4 + k], where, "parameter " + std::to_string(k + 1)));
  const bool oneFocal = spec.name != "PINHOLE" && spec.name != "OPENCV";
  const size_t principal = oneFocal ? 1 : 2;  // index of cx
  c.fx = p[0];
  c.fy = oneFocal ? p[0] : p[1];
  c.cx = p[principal];
  c.cy = p[principal + 1];
  if (!(c.fx > 0 && c.fy > 0))
    throw InvalidInputError(where + "the focal length must be positive; fix the line");
  c.distortion.model = spec.distortion;
  const size_t first = principal + 2;  // first distortion parameter
  if (spec.parameters > first) c.distortion.k1 = p[first];
  if (spec.distortion == DistortionModel::Radial || spec.distortion == DistortionModel::OpenCV)
    c.distortion.k2 = p[first + 1];
  if (spec.distortion == DistortionModel::OpenCV) {
    c.distortion.p1 = p[first + 2];
    c.distortion.p2 = p[first + 3];
  }
  return c;
}

std::map<uint64_t, Intrinsics> readCamerasTxt(const std::filesystem::path& file) {
  const std::string text = readWholeFile(file);
  std::map<uint64_t, Intrinsics> out;
  LineReader lines(text);
  while (const std::optional<Line> line = lines.next()) {
    if (skipped(line->text)) continue;
    const std::string where = at(file, line->number);
    const std::vector<std::string_view> w = words(line->text);
    const uint64_t id = integer(w[0], where, "CAMERA_ID", std::numeric_limits<uint32_t>::max());
    Intrinsics camera = parseCameraLine(w, where);
    if (!out.emplace(id, camera).second)
      throw InvalidInputError(where + "camera " + std::to_string(id) +
                              " is defined twice; give each camera its own id");
  }
  return out;
}

/// Checks the line after an image line: X Y POINT3D_ID triples (or nothing). A file written
/// with one line per image fails here instead of losing every other image.
void checkPointsLine(const Line& line, const std::filesystem::path& file, std::string_view name) {
  const std::vector<std::string_view> w = words(line.text);
  bool numbers = w.size() % 3 == 0;
  for (size_t k = 0; numbers && k < w.size(); ++k) {
    double value = 0;
    const auto [end, ec] = std::from_chars(w[k].data(), w[k].data() + w[k].size(), value);
    numbers = ec == std::errc() && end == w[k].data() + w[k].size();
  }
  if (!numbers)
    throw InvalidInputError(at(file, line.number) + "expected the 2-D points of image '" +
                            std::string(name) +
                            "' (X Y POINT3D_ID triples, or an empty line): images.txt holds two "
                            "lines per image; fix the file or re-export the model");
}

/// The pose of an images.txt line: R and t world -> camera from QW QX QY QZ TX TY TZ.
void parsePose(const std::vector<std::string_view>& w, const std::string& where, Camera& camera) {
  const char* fields[] = {"QW", "QX", "QY", "QZ", "TX", "TY", "TZ"};
  double v[7];
  for (size_t k = 0; k < 7; ++k) v[k] = number(w[1 + k], where, fields[k]);
  const Eigen::Quaterniond q(v[0], v[1], v[2], v[3]);  // Hamilton, as COLMAP (Eigen)
  if (!(std::abs(q.norm() - 1) <= kQuaternionNormTolerance))
    throw InvalidInputError(where + "the quaternion QW QX QY QZ has norm " +
                            formatNumber(q.norm()) +
                            ", not 1; check the column order (IMAGE_ID "
                            "QW QX QY QZ TX TY TZ CAMERA_ID NAME)");
  camera.R = q.normalized().toRotationMatrix();
  camera.t = {v[4], v[5], v[6]};
}

}  // namespace

std::vector<Camera> readColmapText(const std::filesystem::path& camerasTxt,
                                   const std::filesystem::path& imagesTxt) {
  const std::map<uint64_t, Intrinsics> intrinsics = readCamerasTxt(camerasTxt);
  const std::string text = readWholeFile(imagesTxt);
  std::vector<Camera> out;
  std::set<uint64_t> imageIds;
  std::map<std::string, size_t> names;  // name -> line
  LineReader lines(text);
  constexpr size_t kImageWords = 10;
  while (const std::optional<Line> line = lines.next()) {
    if (skipped(line->text)) continue;
    const std::string where = at(imagesTxt, line->number);
    const std::vector<std::string_view> w = words(line->text, kImageWords);
    if (w.size() != kImageWords)
      throw InvalidInputError(where +
                              "expected IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME, "
                              "found " +
                              std::to_string(w.size()) + " words; fix the line");
    const uint64_t id = integer(w[0], where, "IMAGE_ID", std::numeric_limits<uint32_t>::max());
    if (!imageIds.insert(id).second)
      throw InvalidInputError(where + "image id " + std::to_string(id) +
                              " is used twice; give each image its own id");
    const uint64_t cameraId =
        integer(w[8], where, "CAMERA_ID", std::numeric_limits<uint32_t>::max());
    const auto found = intrinsics.find(cameraId);
    if (found == intrinsics.end())
      throw InvalidInputError(where + "image '" + std::string(w[9]) + "' refers to camera " +
                              std::to_string(cameraId) + ", which " + camerasTxt.string() +
                              " does not define; export cameras.txt and images.txt together");
    if (const std::string problem = nameProblem(w[9]); !problem.empty())
      throw InvalidInputError(where + problem + "; rename the photo");
    const auto [previous, fresh] = names.emplace(std::string(w[9]), line->number);
    if (!fresh)
      throw InvalidInputError(where + "image '" + std::string(w[9]) +
                              "' is listed twice (also on line " +
                              std::to_string(previous->second) + "); keep one entry per photo");
    Camera camera = found->second;
    camera.name = std::string(w[9]);
    parsePose(w, where, camera);
    out.push_back(std::move(camera));
    if (const std::optional<Line> points = lines.next())
      checkPointsLine(*points, imagesTxt, out.back().name);
  }
  return out;
}

namespace {

/// The COLMAP model line (MODEL WIDTH HEIGHT PARAMS[]) of a camera.
std::string modelLine(const Camera& c) {
  const LensDistortion& d = c.distortion;
  const bool oneFocal = c.fx == c.fy;
  std::vector<double> p;
  std::string model;
  if (d.model == DistortionModel::None) {
    model = "PINHOLE";
    p = {c.fx, c.fy, c.cx, c.cy};
  } else if (d.model == DistortionModel::SimpleRadial && oneFocal) {
    model = "SIMPLE_RADIAL";
    p = {c.fx, c.cx, c.cy, d.k1};
  } else if (d.model == DistortionModel::Radial && oneFocal) {
    model = "RADIAL";
    p = {c.fx, c.cx, c.cy, d.k1, d.k2};
  } else {  // OpenCV, or a radial model with two focal lengths: the same projection
    const bool tangential = d.model == DistortionModel::OpenCV;
    model = "OPENCV";
    p = {c.fx,
         c.fy,
         c.cx,
         c.cy,
         d.k1,
         d.model == DistortionModel::SimpleRadial ? 0.0 : d.k2,
         tangential ? d.p1 : 0.0,
         tangential ? d.p2 : 0.0};
  }
  std::string line = model + " " + std::to_string(c.width) + " " + std::to_string(c.height);
  for (double value : p) line += " " + formatNumber(value);
  return line;
}

}  // namespace

}  // namespace texgrad::cameras

namespace texgrad {

void writeColmapText(const std::filesystem::path& folder, const std::vector<Camera>& cameras) {
  std::ostringstream camerasTxt, imagesTxt;
  camerasTxt << "# Camera list with one line of data per camera:\n"
             << "#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]\n"
             << "# Number of cameras: " << cameras.size() << "\n";
  imagesTxt << "# Image list with two lines of data per image:\n"
            << "#   IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME\n"
            << "#   POINTS2D[] as (X, Y, POINT3D_ID)\n"
            << "# Number of images: " << cameras.size() << ", mean observations per image: 0\n";
  for (size_t i = 0; i < cameras.size(); ++i) {
    const Camera& c = cameras[i];
    cameras::checkWritable(c, folder.string() + ": camera " + std::to_string(i) + ": ");
    const size_t id = i + 1;
    camerasTxt << id << " " << cameras::modelLine(c) << "\n";
    const Eigen::Quaterniond q(c.R);
    imagesTxt << id;
    for (double value : {q.w(), q.x(), q.y(), q.z(), c.t.x(), c.t.y(), c.t.z()})
      imagesTxt << " " << cameras::formatNumber(value);
    imagesTxt << " " << id << " " << c.name << "\n\n";
  }
  std::error_code ec;
  std::filesystem::create_directories(folder, ec);
  if (ec) throw IoError("cannot create " + folder.string() + ": " + ec.message());
  cameras::writeTextFile(folder / "cameras.txt", camerasTxt.str());
  cameras::writeTextFile(folder / "images.txt", imagesTxt.str());
  cameras::writeTextFile(
      folder / "points3D.txt",
      "# 3D point list with one line of data per point:\n"
      "#   POINT3D_ID, X, Y, Z, R, G, B, ERROR, TRACK[] as (IMAGE_ID, POINT2D_IDX)\n"
      "# Number of points: 0, mean track length: 0\n");
}

}  // namespace texgrad
