// Stanford PLY input (own parser): ASCII and binary little/big endian, polygon faces fanned into
// triangles, UVs per corner (`texcoord` lists) or per vertex (u/v, s/t, texture_u/texture_v).
#include <algorithm>
#include <bit>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iomanip>
#include <limits>
#include <optional>
#include <sstream>
#include <string_view>

#include "texgrad/core/error.h"
#include "texgrad/io/mesh_reader.h"

namespace texgrad {
namespace {

/// A header longer than this is treated as garbage (real headers are a few hundred bytes).
constexpr size_t kMaxHeaderBytes = size_t{1} << 20;
/// Longest list accepted in a face (corners, or UV values per face).
constexpr size_t kMaxListLength = size_t{1} << 16;

enum class Format { Ascii, BinaryLittleEndian, BinaryBigEndian };
enum class Scalar { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64 };
/// What a property feeds in the mesh.
enum class Role { Ignore, X, Y, Z, U, V, Corners, CornerUvs };

struct Property {
  std::string name;
  Scalar type = Scalar::Float32;
  bool isList = false;
  Scalar countType = Scalar::UInt8;
  Role role = Role::Ignore;
};

struct Element {
  std::string name;
  size_t count = 0;
  std::vector<Property> properties;
};

struct Header {
  Format format = Format::Ascii;
  std::vector<Element> elements;
  std::string textureFile;  ///< from "comment TextureFile NAME"
  size_t bodyOffset = 0;
};

size_t scalarSize(Scalar s) {
  switch (s) {
    case Scalar::Int8:
    case Scalar::UInt8:
      return 1;
    case Scalar::Int16:
    case Scalar::UInt16:
      return 2;
    case Scalar::Int32:
    case Scalar::UInt32:
    case Scalar::Float32:
      return 4;
    case Scalar::Float64:
      return 8;
  }
  return 1;
}

std::optional<Scalar> parseScalar(std::string_view name) {
  if (name == "char" || name == "int8") return Scalar::Int8;
  if (name == "uchar" || name == "uint8") return Scalar::UInt8;
  if (name == "short" || name == "int16") return Scalar::Int16;
  if (name == "ushort" || name == "uint16") return Scalar::UInt16;
  if (name == "int" || name == "int32") return Scalar::Int32;
  if (name == "uint" || name == "uint32") return Scalar::UInt32;
  if (name == "float" || name == "float32") return Scalar::Float32;
  if (name == "double" || name == "float64") return Scalar::Float64;
  return std::nullopt;
}

/// Reads scalars from the body, never past its end.
class Cursor {
 public:
  enum class Status { Ok, End, NotANumber };

  Cursor(std::string_view body, Format format) : body_(body), format_(format) {}

  Status read(Scalar type, double& out) {
    return format_ == Format::Ascii ? readAscii(out) : readBinary(type, out);
  }
  size_t remaining() const { return body_.size() - pos_; }

 private:
  Status readAscii(double& out) {
    while (pos_ < body_.size() && std::isspace(static_cast<unsigned char>(body_[pos_]))) ++pos_;
    if (pos_ == body_.size()) return Status::End;
    size_t end = pos_;
    while (end < body_.size() && !std::isspace(static_cast<unsigned char>(body_[end]))) ++end;
    const auto [ptr, ec] = std::from_chars(body_.data() + pos_, body_.data() + end, out);
    const bool whole = ptr == body_.data() + end;
    pos_ = end;
    return ec == std::errc() && whole ? Status::Ok : Status::NotANumber;
  }

  Status readBinary(Scalar type, double& out) {
    const size_t size = scalarSize(type);
    if (remaining() < size) return Status::End;
    std::array<char, 8> bytes{};
    std::memcpy(bytes.data(), body_.data() + pos_, size);
    pos_ += size;
    const bool fileLittle = format_ == Format::BinaryLittleEndian;
    if (fileLittle != (std::endian::native == std::endian::little))
      std::reverse(bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(size));
    out = decode(type, bytes.data());
    return Status::Ok;
  }

  template <typename T>
  static double as(const char* bytes) {
    T value;
    std::memcpy(&value, bytes, sizeof(T));
    return static_cast<double>(value);
  }

  static double decode(Scalar type, const char* bytes) {
    switch (type) {
      case Scalar::Int8:
        return as<int8_t>(bytes);
      case Scalar::UInt8:
        return as<uint8_t>(bytes);
      case Scalar::Int16:
        return as<int16_t>(bytes);
      case Scalar::UInt16:
        return as<uint16_t>(bytes);
      case Scalar::Int32:
        return as<int32_t>(bytes);
      case Scalar::UInt32:
        return as<uint32_t>(bytes);
      case Scalar::Float32:
        return as<float>(bytes);
      case Scalar::Float64:
        return as<double>(bytes);
    }
    return 0.0;
  }

  std::string_view body_;
  Format format_;
  size_t pos_ = 0;
};

/// An index or count read as a double, printed without a fractional part when it has none.
std::string formatIndex(double x) {
  std::ostringstream out;
  out << std::setprecision(17) << x;
  return out.str();
}

std::string readWholeFile(const std::filesystem::path& path) {
  requireReadableFile(path);
  std::ifstream in(path, std::ios::binary);
  std::ostringstream content;
  content << in.rdbuf();
  if (in.bad()) throw IoError("reading " + path.string() + " failed; check the disk");
  return std::move(content).str();
}

/// Next header line (without the line break); advances `pos` past it.
std::optional<std::string_view> nextLine(std::string_view text, size_t& pos) {
  if (pos >= text.size() || pos >= kMaxHeaderBytes) return std::nullopt;
  const size_t end = text.find('\n', pos);
  if (end == std::string_view::npos) return std::nullopt;
  std::string_view line = text.substr(pos, end - pos);
  if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
  pos = end + 1;
  return line;
}

Property parseProperty(std::istringstream& words, const std::string& where) {
  Property p;
  std::string type;
  words >> type;
  if (type == "list") {
    std::string countType, itemType;
    words >> countType >> itemType >> p.name;
    const auto count = parseScalar(countType);
    const auto item = parseScalar(itemType);
    if (!count || !item || p.name.empty())
      throw InvalidInputError(where +
                              ": malformed list property; expected 'property list "
                              "COUNT_TYPE ITEM_TYPE NAME'");
    if (*count == Scalar::Float32 || *count == Scalar::Float64)
      throw InvalidInputError(where + ": list property '" + p.name +
                              "' has a floating-point count type; use an integer type");
    p.isList = true;
    p.countType = *count;
    p.type = *item;
    return p;
  }
  const auto scalar = parseScalar(type);
  words >> p.name;
  if (!scalar || p.name.empty())
    throw InvalidInputError(where + ": unknown property type '" + type +
                            "'; expected char, uchar, short, ushort, int, uint, float or double");
  p.type = *scalar;
  return p;
}

Format parseFormat(std::istringstream& words, const std::string& where) {
  std::string name, version;
  words >> name >> version;
  if (name == "ascii") return Format::Ascii;
  if (name == "binary_little_endian") return Format::BinaryLittleEndian;
  if (name == "binary_big_endian") return Format::BinaryBigEndian;
  throw InvalidInputError(where + ": unknown format '" + name +
                          "'; expected ascii, binary_little_endian or binary_big_endian");
}

size_t parseCount(const std::string& text, const std::string& where) {
  size_t count = 0;
  const auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), count);
  if (ec != std::errc() || ptr != text.data() + text.size())
    throw InvalidInputError(where + ": element count '" + text + "' is not a whole number");
  if (count > static_cast<size_t>(std::numeric_limits<int32_t>::max()))
    throw UnsupportedError(where + ": " + text + " elements exceed the 2^31 limit of texgrad");
  return count;
}

Header parseHeader(std::string_view text, const std::string& file) {
  size_t pos = 0;
  const auto magic = nextLine(text, pos);
  if (!magic || *magic != "ply")
    throw InvalidInputError(file + ": not a PLY file (the first line must be 'ply')");
  Header header;
  bool haveFormat = false;
  for (int lineNumber = 2;; ++lineNumber) {
    const auto line = nextLine(text, pos);
    const std::string where = file + " header line " + std::to_string(lineNumber);
    if (!line)
      throw InvalidInputError(file +
                              ": the header has no 'end_header' line; the file is "
                              "truncated or not a PLY file");
    std::istringstream words{std::string(*line)};
    std::string keyword;
    words >> keyword;
    if (keyword == "end_header") break;
    if (keyword == "format") {
      header.format = parseFormat(words, where);
      haveFormat = true;
    } else if (keyword == "element") {
      Element element;
      std::string count;
      words >> element.name >> count;
      element.count = parseCount(count, where);
      header.elements.push_back(std::move(element));
    } else if (keyword == "property") {
      if (header.elements.empty())
        throw InvalidInputError(where + ": 'property' before any 'element'");
      header.elements.back().properties.push_back(parseProperty(words, where));
    } else if (keyword == "comment") {
      std::string tag;
      words >> tag;
      if (tag == "TextureFile") {
        std::getline(words >> std::ws, header.textureFile);
      }
    } else if (!keyword.empty() && keyword != "obj_info") {
      throw InvalidInputError(where + ": unknown header keyword '" + keyword + "'");
    }
  }
  if (!haveFormat) throw InvalidInputError(file + ": the header has no 'format' line");
  header.bodyOffset = pos;
  return header;
}

Property* findProperty(Element& element, std::string_view name) {
  for (Property& p : element.properties)
    if (p.name == name) return &p;
  return nullptr;
}

Element* findElement(Header& header, std::string_view name) {
  for (Element& e : header.elements)
    if (e.name == name) return &e;
  return nullptr;
}

/// Tags the properties the mesh needs; returns whether the vertices carry UVs.
bool assignRoles(Header& header, const std::string& file) {
  Element* vertex = findElement(header, "vertex");
  Element* face = findElement(header, "face");
  if (vertex == nullptr || face == nullptr)
    throw InvalidInputError(file +
                            ": needs 'vertex' and 'face' elements; texgrad reads "
                            "triangle or polygon meshes, not point clouds");
  for (const char* axis : {"x", "y", "z"}) {
    Property* p = findProperty(*vertex, axis);
    if (p == nullptr || p->isList)
      throw InvalidInputError(file + ": vertex property '" + axis + "' is missing");
    p->role = axis[0] == 'x' ? Role::X : axis[0] == 'y' ? Role::Y : Role::Z;
  }
  Property* corners = findProperty(*face, "vertex_indices");
  if (corners == nullptr) corners = findProperty(*face, "vertex_index");
  if (corners == nullptr || !corners->isList)
    throw InvalidInputError(file + ": faces need a 'vertex_indices' list property");
  corners->role = Role::Corners;
  if (Property* uv = findProperty(*face, "texcoord"); uv != nullptr && uv->isList) {
    uv->role = Role::CornerUvs;
    return false;
  }
  constexpr std::array<std::pair<const char*, const char*>, 4> kUvNames{
      {{"u", "v"}, {"s", "t"}, {"texture_u", "texture_v"}, {"texture_s", "texture_t"}}};
  for (const auto& [uName, vName] : kUvNames) {
    Property* u = findProperty(*vertex, uName);
    Property* v = findProperty(*vertex, vName);
    if (u != nullptr && v != nullptr && !u->isList && !v->isList) {
      u->role = Role::U;
      v->role = Role::V;
      return true;
    }
  }
  return false;
}

/// Reads all elements of the body into the mesh.
class BodyReader {
 public:
  BodyReader(std::string_view body, const Header& header, std::string file, bool vertexUvs)
      : cursor_(body, header.format),
        header_(header),
        file_(std::move(file)),
        vertexUvs_(vertexUvs) {
    for (const Element& e : header_.elements) {
      if (e.name == "vertex") vertexCount_ = e.count;
      if (e.name == "face")
        cornerUvs_ = std::any_of(e.properties.begin(), e.properties.end(),
                                 [](const Property& p) { return p.role == Role::CornerUvs; });
    }
  }

  TexturedMesh read() {
    for (const Element& element : header_.elements) {
      if (element.properties.empty()) continue;
      checkCountFits(element);
      for (size_t i = 0; i < element.count; ++i) readInstance(element, i);
    }
    return std::move(mesh_);
  }

 private:
  /// Rejects counts the remaining bytes cannot hold, before anything is allocated.
  void checkCountFits(const Element& element) {
    size_t minBytes = 0;
    for (const Property& p : element.properties)
      minBytes += header_.format == Format::Ascii ? 1 : scalarSize(p.isList ? p.countType : p.type);
    if (element.count > cursor_.remaining() / minBytes)
      throw InvalidInputError(file_ + ": the header declares " + std::to_string(element.count) +
                              " '" + element.name + "' elements but only " +
                              std::to_string(cursor_.remaining()) +
                              " bytes remain; the file is truncated, re-export it");
    if (element.name == "vertex") mesh_.positions.reserve(element.count);
    if (element.name == "face") mesh_.triangles.reserve(element.count);
  }

  double value(Scalar type, const Element& element, size_t i, const Property& p) {
    double out = 0.0;
    const Cursor::Status status = cursor_.read(type, out);
    if (status == Cursor::Status::Ok) return out;
    const std::string where =
        file_ + ": " + element.name + " " + std::to_string(i) + " property '" + p.name + "'";
    if (status == Cursor::Status::End)
      throw InvalidInputError(where + ": the file ends early; it is truncated, re-export it");
    throw InvalidInputError(where + ": not a number; the ASCII body is malformed");
  }

  void readList(const Element& element, size_t i, const Property& p, std::vector<double>& out) {
    const double n = value(p.countType, element, i, p);
    if (!(n >= 0.0) || n > static_cast<double>(kMaxListLength) || n != std::floor(n))
      throw InvalidInputError(file_ + ": " + element.name + " " + std::to_string(i) + " list '" +
                              p.name + "' has length " + formatIndex(n) + "; at most " +
                              std::to_string(kMaxListLength) +
                              " is accepted (the file is corrupt or truncated)");
    out.resize(static_cast<size_t>(n));
    for (double& x : out) x = value(p.type, element, i, p);
  }

  void readInstance(const Element& element, size_t i) {
    Eigen::Vector3d position = Eigen::Vector3d::Zero();
    Eigen::Vector2d uv = Eigen::Vector2d::Zero();
    for (const Property& p : element.properties) {
      if (p.isList) {
        if (p.role == Role::Corners || p.role == Role::CornerUvs)
          readList(element, i, p, p.role == Role::CornerUvs ? cornerUvValues_ : corners_);
        else
          readList(element, i, p, ignoredList_);
        continue;
      }
      const double x = value(p.type, element, i, p);
      switch (p.role) {
        case Role::X:
          position.x() = x;
          break;
        case Role::Y:
          position.y() = x;
          break;
        case Role::Z:
          position.z() = x;
          break;
        case Role::U:
          uv.x() = x;
          break;
        case Role::V:
          uv.y() = x;
          break;
        default:
          break;
      }
    }
    if (element.name == "vertex") {
      mesh_.positions.push_back(position);
      if (vertexUvs_) mesh_.uvs.push_back(uv);
    } else if (element.name == "face") {
      addFace(i);
    }
    corners_.clear();
    cornerUvValues_.clear();
  }

  void addFace(size_t face) {
    const std::string where = file_ + ": face " + std::to_string(face);
    const size_t n = corners_.size();
    if (n < 3)
      throw InvalidInputError(where + " has " + std::to_string(n) +
                              " corners; faces need at least 3");
    std::vector<int32_t> vertices(n);
    for (size_t k = 0; k < n; ++k) {
      const double v = corners_[k];
      if (!(v >= 0.0) || v >= static_cast<double>(vertexCount_) || v != std::floor(v))
        throw InvalidInputError(where + " references vertex " + formatIndex(v) + " but there are " +
                                std::to_string(vertexCount_) +
                                " vertices (0-based); the file is corrupt, re-export it");
      vertices[k] = static_cast<int32_t>(v);
    }
    if (cornerUvs_ && cornerUvValues_.size() != 2 * n)
      throw InvalidInputError(where + " has " + std::to_string(n) + " corners but " +
                              std::to_string(cornerUvValues_.size()) +
                              " texcoord values; expected 2 per corner (u v)");
    const auto uvBase = static_cast<int32_t>(mesh_.uvs.size());
    if (cornerUvs_)
      for (size_t k = 0; k < n; ++k)
        mesh_.uvs.emplace_back(cornerUvValues_[2 * k], cornerUvValues_[2 * k + 1]);
    for (size_t k = 1; k + 1 < n; ++k) {
      const Triangle t{vertices[0], vertices[k], vertices[k + 1]};
      mesh_.triangles.push_back(t);
      if (cornerUvs_)
        mesh_.uvTriangles.push_back(
            {uvBase, uvBase + static_cast<int32_t>(k), uvBase + static_cast<int32_t>(k + 1)});
      else if (vertexUvs_)
        mesh_.uvTriangles.push_back(t);
    }
  }

  Cursor cursor_;
  const Header& header_;
  std::string file_;
  bool vertexUvs_;
  bool cornerUvs_ = false;  ///< faces carry a `texcoord` list
  size_t vertexCount_ = 0;
  TexturedMesh mesh_;
  std::vector<double> corners_, cornerUvValues_, ignoredList_;  ///< lists being read
};

}  // namespace

TexturedMesh readPly(const std::filesystem::path& path) {
  const std::string file = path.string();
  const std::string content = readWholeFile(path);
  Header header = parseHeader(content, file);
  const bool vertexUvs = assignRoles(header, file);
  const std::string_view body = std::string_view(content).substr(header.bodyOffset);
  TexturedMesh mesh = BodyReader(body, header, file, vertexUvs).read();
  if (!header.textureFile.empty()) {
    TextureRef ref;
    ref.slot = "baseColor";
    ref.path =
        (std::filesystem::absolute(path).parent_path() / header.textureFile).lexically_normal();
    mesh.textures.push_back(std::move(ref));
  }
  validateMesh(mesh, file);
  mesh.sourcePath = path;
  return mesh;
}

}  // namespace texgrad
