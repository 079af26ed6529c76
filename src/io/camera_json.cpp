// texgrad's camera JSON (docs/photos.md) read into Camera values and written from them:
// {"cameras": [{"file", "width", "height", "K", "R", "C" or "t", "distortion"?}, ...]}, with the
// conventions of Camera (R world -> camera, pixel origin at the image's top-left corner).
#include <nlohmann/json.hpp>

#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <sstream>

#include "camera_formats.h"
#include "texgrad/core/error.h"
#include "texgrad/core/json_depth.h"
#include "texgrad/io/camera_writer.h"

namespace texgrad::cameras {
namespace {

using Json = nlohmann::json;

/// Deepest nesting a camera JSON needs is 5 (file, cameras, camera, K, row); the rest is headroom.
constexpr int kMaxJsonDepth = 16;

/// The distortion model names of the JSON and the coefficients each uses.
struct JsonModel {
  std::string_view name;
  DistortionModel model;
  std::vector<std::string_view> coefficients;
};
const std::vector<JsonModel>& jsonModels() {
  static const std::vector<JsonModel> models = {
      {"none", DistortionModel::None, {}},
      {"simple_radial", DistortionModel::SimpleRadial, {"k1"}},
      {"radial", DistortionModel::Radial, {"k1", "k2"}},
      {"opencv", DistortionModel::OpenCV, {"k1", "k2", "p1", "p2"}}};
  return models;
}

/// Messages: "<file>: <element>: <problem>".
class Where {
 public:
  Where(const std::filesystem::path& file, std::string element)
      : file_(file), element_(std::move(element)) {}
  Where operator[](size_t index) const {
    return {file_, element_ + "[" + std::to_string(index) + "]"};
  }
  Where operator/(std::string_view key) const { return {file_, element_ + "." + std::string(key)}; }
  [[noreturn]] void fail(const std::string& problem) const {
    throw InvalidInputError(file_.string() + ": " + element_ + ": " + problem);
  }
  [[noreturn]] void unsupported(const std::string& problem) const {
    throw UnsupportedError(file_.string() + ": " + element_ + ": " + problem);
  }

 private:
  const std::filesystem::path& file_;
  std::string element_;
};

/// A JSON value for a message: short scalars as written, anything else by its type.
std::string describe(const Json& value) {
  constexpr size_t kLongest = 40;
  if (value.is_primitive()) {
    const std::string text = value.dump();
    if (text.size() <= kLongest) return text;
  }
  return std::string("a") + (value.is_array() || value.is_object() ? "n " : " ") +
         value.type_name();
}

double number(const Json& value, const Where& where) {
  if (!value.is_number()) where.fail("expected a number, found " + describe(value));
  const double x = value.get<double>();
  if (!std::isfinite(x)) where.fail("the number is not finite");
  return x;
}

int size(const Json& value, const Where& where) {
  if (!value.is_number_integer() || value.get<int64_t>() <= 0 ||
      value.get<int64_t>() > std::numeric_limits<int>::max())
    where.fail("expected a positive whole number of pixels, found " + describe(value));
  return static_cast<int>(value.get<int64_t>());
}

template <int Rows, int Cols>
Eigen::Matrix<double, Rows, Cols> matrix(const Json& value, const Where& where) {
  const std::string shape =
      Cols == 1 ? "an array of " + std::to_string(Rows) + " numbers"
                : std::to_string(Rows) + " rows of " + std::to_string(Cols) + " numbers";
  if (!value.is_array() || value.size() != Rows) where.fail("expected " + shape);
  Eigen::Matrix<double, Rows, Cols> out;
  for (size_t i = 0; i < Rows; ++i) {
    if constexpr (Cols == 1) {
      out(static_cast<Eigen::Index>(i)) = number(value[i], where[i]);
    } else {
      const Json& row = value[i];
      if (!row.is_array() || row.size() != Cols) where[i].fail("expected " + shape);
      for (size_t j = 0; j < Cols; ++j)
        out(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) =
            number(row[j], where[i][j]);
    }
  }
  return out;
}

/// Throws unless `object` is an object whose keys are all `allowed`.
void requireKeys(const Json& object, const Where& where,
                 std::initializer_list<std::string_view> allowed) {
  if (!object.is_object()) where.fail("expected an object, found " + describe(object));
  for (const auto& item : object.items()) {
    bool known = false;
    for (std::string_view key : allowed) known = known || key == item.key();
    if (!known) {
      std::string list;
      for (std::string_view key : allowed) list += (list.empty() ? "" : ", ") + std::string(key);
      where.fail("unknown key \"" + item.key() + "\" (the keys are " + list + ")");
    }
  }
}

const Json& required(const Json& object, std::string_view key, const Where& where) {
  const auto found = object.find(key);
  if (found == object.end()) where.fail("\"" + std::string(key) + "\" is missing");
  return *found;
}

void readIntrinsics(const Json& entry, const Where& where, Camera& camera) {
  camera.width = size(required(entry, "width", where), where / "width");
  camera.height = size(required(entry, "height", where), where / "height");
  const Where atK = where / "K";
  const Eigen::Matrix3d K = matrix<3, 3>(required(entry, "K", where), atK);
  if (K(0, 1) != 0) atK.unsupported("a skewed K (K[0][1] != 0) is not supported");
  if (K(1, 0) != 0 || K(2, 0) != 0 || K(2, 1) != 0 || K(2, 2) != 1)
    atK.fail("expected [[fx, 0, cx], [0, fy, cy], [0, 0, 1]]");
  if (!(K(0, 0) > 0 && K(1, 1) > 0)) atK.fail("the focal lengths fx and fy must be positive");
  camera.fx = K(0, 0);
  camera.fy = K(1, 1);
  camera.cx = K(0, 2);
  camera.cy = K(1, 2);
}

void readPose(const Json& entry, const Where& where, Camera& camera) {
  camera.R = matrix<3, 3>(required(entry, "R", where), where / "R");
  if (!isRotation(camera.R))
    (where / "R")
        .fail("not a rotation (rows orthonormal to " + formatNumber(kRotationTolerance) +
              ", determinant +1); give R world -> camera");
  const bool hasC = entry.contains("C"), hasT = entry.contains("t");
  if (hasC && hasT) where.fail("give the camera centre \"C\" or the translation \"t\", not both");
  if (!hasC && !hasT) where.fail("the camera centre \"C\" (or the translation \"t\") is missing");
  if (hasT) {
    camera.t = matrix<3, 1>(entry["t"], where / "t");
  } else {
    const Eigen::Vector3d C = matrix<3, 1>(entry["C"], where / "C");
    camera.t = -camera.R * C;
    if (!camera.t.allFinite()) (where / "C").fail("the centre is too far out to compute t = -R C");
  }
}

LensDistortion readDistortion(const Json& value, const Where& where) {
  const Json& name = required(value, "model", where);
  const JsonModel* model = nullptr;
  for (const JsonModel& m : jsonModels())
    if (name.is_string() && name.get<std::string>() == m.name) model = &m;
  if (model == nullptr)
    (where / "model")
        .fail("unknown distortion model " + describe(name) +
              " (the models are none, simple_radial, radial, opencv)");
  LensDistortion d;
  d.model = model->model;
  double* slots[] = {&d.k1, &d.k2, &d.p1, &d.p2};
  const std::string_view names[] = {"k1", "k2", "p1", "p2"};
  for (const auto& item : value.items()) {
    if (item.key() == "model") continue;
    bool used = false;
    for (std::string_view c : model->coefficients) used = used || c == item.key();
    if (!used)
      where.fail("\"" + item.key() + "\" is not a coefficient of the " + std::string(model->name) +
                 " model");
  }
  for (size_t k = 0; k < 4; ++k)
    for (std::string_view c : model->coefficients)
      if (c == names[k]) *slots[k] = number(required(value, c, where), where / c);
  return d;
}

Camera readEntry(const Json& entry, const Where& where) {
  requireKeys(entry, where, {"file", "width", "height", "K", "R", "C", "t", "distortion"});
  Camera camera;
  const Json& file = required(entry, "file", where);
  if (!file.is_string())
    (where / "file").fail("expected the photo's file name, found " + describe(file));
  camera.name = file.get<std::string>();
  if (const std::string problem = nameProblem(camera.name); !problem.empty())
    (where / "file").fail(problem);
  readIntrinsics(entry, where, camera);
  readPose(entry, where, camera);
  if (entry.contains("distortion"))
    camera.distortion = readDistortion(entry["distortion"], where / "distortion");
  return camera;
}

}  // namespace

std::vector<Camera> readCameraJson(const std::filesystem::path& path) {
  const std::string text = readWholeFile(path);
  if (jsonNestsDeeperThan(text, kMaxJsonDepth))
    throw InvalidInputError(path.string() + ": JSON nested deeper than " +
                            std::to_string(kMaxJsonDepth) +
                            " levels; this is not a camera file (docs/photos.md)");
  Json root;
  try {
    root = Json::parse(text);
  } catch (const Json::exception& e) {  // a syntax error, or a number out of double's range
    std::string why = e.what();  // "[json.exception.parse_error.101] parse error at line ..."
    const size_t bracket = why.find("] ");
    if (bracket != std::string::npos) why.erase(0, bracket + 2);
    throw InvalidInputError(path.string() + ": not valid JSON (" + why + ")");
  }
  const Where top(path, "top level");
  requireKeys(root, top, {"cameras"});
  const Json& list = required(root, "cameras", top);
  const Where at(path, "cameras");
  if (!list.is_array()) at.fail("expected an array of cameras");
  std::vector<Camera> out;
  std::map<std::string, size_t> names;
  for (size_t i = 0; i < list.size(); ++i) {
    out.push_back(readEntry(list[i], at[i]));
    const auto [previous, fresh] = names.emplace(out.back().name, i);
    if (!fresh)
      (at[i] / "file")
          .fail("photo '" + out.back().name + "' is listed twice (also cameras[" +
                std::to_string(previous->second) + "]); keep one entry per photo");
  }
  return out;
}

namespace {

std::string row(std::initializer_list<double> values) {
  std::string out = "[";
  for (double v : values) out += (out.size() > 1 ? ", " : "") + formatNumber(v);
  return out + "]";
}

/// A name as a JSON string; throws InvalidInputError unless it is UTF-8 (JSON text is).
std::string jsonString(const std::string& name, const std::string& where) {
  try {
    return Json(name).dump();
  } catch (const Json::type_error&) {
    throw InvalidInputError(where + "the image name is not UTF-8 text; rename the photo");
  }
}

/// One camera as a JSON object, indented for a list.
std::string entryText(const Camera& c, const std::string& where) {
  const Eigen::Matrix3d& R = c.R;
  std::ostringstream out;
  out << "    {\n"
      << "      \"file\": " << jsonString(c.name, where) << ",\n"
      << "      \"width\": " << c.width << ",\n"
      << "      \"height\": " << c.height << ",\n"
      << "      \"K\": [" << row({c.fx, 0, c.cx}) << ", " << row({0, c.fy, c.cy}) << ", "
      << row({0, 0, 1}) << "],\n"
      << "      \"R\": [" << row({R(0, 0), R(0, 1), R(0, 2)}) << ", "
      << row({R(1, 0), R(1, 1), R(1, 2)}) << ", " << row({R(2, 0), R(2, 1), R(2, 2)}) << "],\n"
      << "      \"t\": " << row({c.t.x(), c.t.y(), c.t.z()});
  if (c.distortion.model != DistortionModel::None) {
    const LensDistortion& d = c.distortion;
    const double values[] = {d.k1, d.k2, d.p1, d.p2};
    for (const JsonModel& m : jsonModels()) {
      if (m.model != d.model) continue;
      out << ",\n      \"distortion\": {\"model\": \"" << m.name << "\"";
      for (size_t k = 0; k < m.coefficients.size(); ++k)
        out << ", \"" << m.coefficients[k] << "\": " << formatNumber(values[k]);
      out << "}";
    }
  }
  out << "\n    }";
  return out.str();
}

}  // namespace

}  // namespace texgrad::cameras

namespace texgrad {

void writeCameraJson(const std::filesystem::path& path, const std::vector<Camera>& cameras) {
  std::string text = "{\n  \"cameras\": [";
  for (size_t i = 0; i < cameras.size(); ++i) {
    const std::string where = path.string() + ": camera " + std::to_string(i) + ": ";
    cameras::checkWritable(cameras[i], where);
    text += (i == 0 ? "\n" : ",\n") + cameras::entryText(cameras[i], where);
  }
  text += "\n  ]\n}\n";
  cameras::writeTextFile(path, text);
}

}  // namespace texgrad
