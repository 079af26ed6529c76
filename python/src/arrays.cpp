// Conversions between numpy arrays and the library's images, matrices and sparse matrices, and
// the solver keywords shared by every app.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>

#include "bindings.h"
#include "texgrad/core/error.h"

namespace texgrad::python {
namespace {

/// Largest image side accepted (an Image indexes with int).
constexpr py::ssize_t kMaxImageSide = 1 << 20;

/// "(2, 3, 4)": the shape of `a` as Python prints it.
std::string shapeText(const py::array& a) {
  std::string text = "(";
  for (py::ssize_t d = 0; d < a.ndim(); ++d) {
    if (d > 0) text += ", ";
    text += std::to_string(a.shape(d));
  }
  return text + (a.ndim() == 1 ? ",)" : ")");
}

/// `handle` as a numpy array (array-likes converted); TypeError naming `name` if it is none.
py::array asArray(const py::handle& handle, const std::string& name) {
  if (handle.is_none()) throw py::type_error(name + " must be an array, got None");
  py::array a = py::array::ensure(handle);
  if (!a) {
    PyErr_Clear();
    throw py::type_error(name + " must be an array (numpy or array-like)");
  }
  return a;
}

SampleType sampleTypeOf(const py::array& a, const std::string& name) {
  const py::dtype type = a.dtype();
  const bool native = type.attr("isnative").cast<bool>();
  const char kind = type.kind();
  const py::ssize_t size = type.itemsize();
  if (native && kind == 'u' && size == 1) return SampleType::UInt8;
  if (native && kind == 'u' && size == 2) return SampleType::UInt16;
  if (native && kind == 'f' && size == 4) return SampleType::Float32;
  if (native && kind == 'f' && size == 8) return SampleType::Float64;
  throw py::type_error(name + " has dtype " + textOf(type) +
                       "; texgrad takes uint8, uint16, float32 or float64 images");
}

/// Normalised float value of one sample: integers to [0, 1] as readImage decodes them
/// (v * (1 / max) in float, which differs from v / max in the last bit for some v).
template <typename T>
float sampleValue(T v) {
  if constexpr (std::is_integral_v<T>)
    return static_cast<float>(v) * (1.0f / static_cast<float>(std::numeric_limits<T>::max()));
  else
    return static_cast<float>(v);
}

template <typename T>
void readSamples(const py::array& a, Image& image, const std::string& name) {
  const auto* base = static_cast<const char*>(a.data());
  const py::ssize_t rowStride = a.strides(0), columnStride = a.strides(1);
  const py::ssize_t channelStride = a.ndim() == 3 ? a.strides(2) : 0;
  for (int r = 0; r < image.height; ++r) {
    const int j = image.height - 1 - r;  // numpy row 0 is the top, texel row 0 the bottom
    for (int i = 0; i < image.width; ++i) {
      const char* texel = base + r * rowStride + i * columnStride;
      for (int c = 0; c < image.channels; ++c) {
        T raw;
        std::memcpy(&raw, texel + c * channelStride, sizeof raw);
        const float value = sampleValue(raw);
        if (!std::isfinite(value))
          throw InvalidInputError(name + " holds a non-finite value at row " + std::to_string(r) +
                                  ", column " + std::to_string(i) + ", channel " +
                                  std::to_string(c));
        image.at(i, j, c) = value;
      }
    }
  }
}

/// Stored value of a float sample in type T (the quantisation of writeImage for integers).
template <typename T>
T storedValue(float v) {
  if constexpr (std::is_integral_v<T>) {
    constexpr float levels = static_cast<float>(std::numeric_limits<T>::max());
    const float clamped = std::isnan(v) ? 0.0f : std::clamp(v, 0.0f, 1.0f);
    return static_cast<T>(std::lround(clamped * levels));
  } else {
    return static_cast<T>(v);
  }
}

template <typename T>
py::array writeSamples(const Image& image, bool planar) {
  const auto h = static_cast<py::ssize_t>(image.height), w = static_cast<py::ssize_t>(image.width);
  py::array_t<T> out = planar ? py::array_t<T>({h, w})
                              : py::array_t<T>({h, w, static_cast<py::ssize_t>(image.channels)});
  T* data = out.mutable_data();
  const size_t rowSize = static_cast<size_t>(image.width) * static_cast<size_t>(image.channels);
  for (int r = 0; r < image.height; ++r) {
    const float* source = image.pixels.data() + static_cast<size_t>(image.height - 1 - r) * rowSize;
    T* target = data + static_cast<size_t>(r) * rowSize;
    for (size_t k = 0; k < rowSize; ++k) target[k] = storedValue<T>(source[k]);
  }
  return out;
}

}  // namespace

ImageArgument imageFromArray(const py::handle& handle, const std::string& name) {
  const py::array a = asArray(handle, name);
  if (a.ndim() != 2 && a.ndim() != 3)
    throw InvalidInputError(name + " must be an H x W or H x W x C image, got shape " +
                            shapeText(a));
  const py::ssize_t channels = a.ndim() == 3 ? a.shape(2) : 1;
  if (channels < 1 || channels > 4)
    throw InvalidInputError(name + " must have 1 to 4 channels, got shape " + shapeText(a));
  if (a.shape(0) == 0 || a.shape(1) == 0)
    throw InvalidInputError(name + " is empty (shape " + shapeText(a) + ")");
  if (a.shape(0) > kMaxImageSide || a.shape(1) > kMaxImageSide)
    throw InvalidInputError(name + " is too large (shape " + shapeText(a) + ")");
  ImageArgument result;
  result.sampleType = sampleTypeOf(a, name);
  result.planar = a.ndim() == 2;
  const PixelFormat formats[] = {PixelFormat::UInt8, PixelFormat::UInt16, PixelFormat::Float,
                                 PixelFormat::Float};
  result.image = Image(static_cast<int>(a.shape(1)), static_cast<int>(a.shape(0)),
                       static_cast<int>(channels), formats[static_cast<int>(result.sampleType)]);
  switch (result.sampleType) {
    case SampleType::UInt8:
      readSamples<uint8_t>(a, result.image, name);
      break;
    case SampleType::UInt16:
      readSamples<uint16_t>(a, result.image, name);
      break;
    case SampleType::Float32:
      readSamples<float>(a, result.image, name);
      break;
    case SampleType::Float64:
      readSamples<double>(a, result.image, name);
      break;
  }
  return result;
}

py::array arrayFromImage(Image&& image, SampleType type, bool planar) {
  const Image owned = std::move(image);
  planar = planar && owned.channels == 1;
  switch (type) {
    case SampleType::UInt8:
      return writeSamples<uint8_t>(owned, planar);
    case SampleType::UInt16:
      return writeSamples<uint16_t>(owned, planar);
    case SampleType::Float32:
      return writeSamples<float>(owned, planar);
    case SampleType::Float64:
      break;
  }
  return writeSamples<double>(owned, planar);
}

SampleType sampleTypeFrom(const py::object& dtype, SampleType fallback) {
  if (dtype.is_none()) return fallback;
  const py::dtype type = py::dtype::from_args(dtype);
  const py::array probe(type, std::vector<py::ssize_t>{0});
  return sampleTypeOf(probe, "dtype");
}

Eigen::MatrixXd matrixFromArray(const py::handle& handle, const std::string& name,
                                Eigen::Index cols) {
  const py::array raw = asArray(handle, name);
  if (raw.dtype().kind() != 'f' && raw.dtype().kind() != 'u' && raw.dtype().kind() != 'i')
    throw py::type_error(name + " has dtype " + textOf(raw.dtype()) + "; numbers are needed");
  const auto a = py::array_t<double, py::array::forcecast>::ensure(raw);
  if (a.ndim() == 1 && (cols < 0 || cols == 1)) {
    Eigen::MatrixXd m(a.shape(0), 1);
    const auto view = a.unchecked<1>();
    for (py::ssize_t r = 0; r < a.shape(0); ++r) m(r, 0) = view(r);
    if (!m.allFinite()) throw InvalidInputError(name + " holds a non-finite value");
    return m;
  }
  if (a.ndim() != 2 || (cols >= 0 && a.shape(1) != cols))
    throw InvalidInputError(name + " must be a 2-D array" +
                            (cols >= 0 ? " with " + std::to_string(cols) + " columns" : "") +
                            ", got shape " + shapeText(a));
  Eigen::MatrixXd m(a.shape(0), a.shape(1));
  const auto view = a.unchecked<2>();
  for (py::ssize_t r = 0; r < a.shape(0); ++r)
    for (py::ssize_t c = 0; c < a.shape(1); ++c) m(r, c) = view(r, c);
  if (!m.allFinite()) throw InvalidInputError(name + " holds a non-finite value");
  return m;
}

py::array_t<double> arrayFromMatrix(const Eigen::MatrixXd& m) {
  py::array_t<double> out({static_cast<py::ssize_t>(m.rows()), static_cast<py::ssize_t>(m.cols())});
  auto view = out.mutable_unchecked<2>();
  for (Eigen::Index r = 0; r < m.rows(); ++r)
    for (Eigen::Index c = 0; c < m.cols(); ++c) view(r, c) = m(r, c);
  return out;
}

py::tuple csrTuple(const Eigen::SparseMatrix<double>& m) {
  Eigen::SparseMatrix<double, Eigen::RowMajor, int> rows = m;
  rows.makeCompressed();
  const auto nnz = static_cast<py::ssize_t>(rows.nonZeros());
  py::array_t<double> data(nnz);
  py::array_t<int32_t> indices(nnz);
  py::array_t<int32_t> indptr(static_cast<py::ssize_t>(rows.rows()) + 1);
  std::copy_n(rows.valuePtr(), nnz, data.mutable_data());
  std::copy_n(rows.innerIndexPtr(), nnz, indices.mutable_data());
  std::copy_n(rows.outerIndexPtr(), rows.rows() + 1, indptr.mutable_data());
  return py::make_tuple(data, indices, indptr, py::make_tuple(rows.rows(), rows.cols()));
}

namespace {

/// `value` as T; TypeError naming the keyword if it is not one.
template <typename T>
T keywordValue(const py::handle& value, const std::string& name, const char* expected) {
  try {
    return value.cast<T>();
  } catch (const py::cast_error&) {
    throw py::type_error(name + " must be " + expected + ", got " + textOf(py::type::of(value)));
  }
}

}  // namespace

void applySolverKeywords(const py::dict& keywords, SolverSettings& s) {
  for (const auto& [key, value] : keywords) {
    const std::string name = textOf(key);
    if (value.is_none()) continue;
    if (name == "solver")
      s.kind = parseSolverKind(keywordValue<std::string>(value, name, "a string"));
    else if (name == "precision")
      s.singlePrecision = parseSinglePrecision(keywordValue<std::string>(value, name, "a string"));
    else if (name == "cycles")
      s.cycles = keywordValue<int>(value, name, "an integer");
    else if (name == "max_iterations")
      s.maxIterations = keywordValue<int>(value, name, "an integer");
    else if (name == "tolerance")
      s.tolerance = keywordValue<double>(value, name, "a number");
    else if (name == "levels")
      s.multigrid.levels = keywordValue<int>(value, name, "an integer");
    else if (name == "sweeps")
      s.multigrid.sweeps = keywordValue<int>(value, name, "an integer");
    else if (name == "line_ratio")
      s.multigrid.lineRatio = keywordValue<double>(value, name, "a number");
    else if (name == "weak_row_reach")
      s.multigrid.weakRowReach = keywordValue<int>(value, name, "an integer");
    else if (name == "threads")
      s.multigrid.threads = keywordValue<int>(value, name, "an integer");
    else
      throw py::type_error("unexpected keyword argument '" + name + "'");
  }
  s.validate();
}

PixelFormat formatOf(SampleType type) {
  switch (type) {
    case SampleType::UInt8:
      return PixelFormat::UInt8;
    case SampleType::UInt16:
      return PixelFormat::UInt16;
    case SampleType::Float32:
    case SampleType::Float64:
      break;
  }
  return PixelFormat::Float;
}

SampleType sampleTypeOf(PixelFormat format) {
  switch (format) {
    case PixelFormat::UInt8:
      return SampleType::UInt8;
    case PixelFormat::UInt16:
      return SampleType::UInt16;
    case PixelFormat::Half:
    case PixelFormat::Float:
      break;
  }
  return SampleType::Float32;
}

}  // namespace texgrad::python
