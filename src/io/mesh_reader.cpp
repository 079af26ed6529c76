// Entry point of mesh input: dispatches on the extension to the OBJ/PLY/glTF readers, then
// checks the result and welds split vertices so the atlas stage can recover seams.
#include "texgrad/io/mesh_reader.h"

#include <algorithm>
#include <bit>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>
#include <unordered_map>

#include "texgrad/core/error.h"

namespace texgrad {
namespace {

/// Largest grid coordinate used by tolerance welding; keeps cell keys far from int64 overflow.
constexpr double kMaxGridCoordinate = 4.0e18;

std::string lowercase(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return text;
}

std::string formatNumber(double x) {
  std::ostringstream out;
  out << x;
  return out.str();
}

std::string formatPoint(const Eigen::Vector3d& p) {
  std::ostringstream out;
  out << "(" << p.x() << ", " << p.y() << ", " << p.z() << ")";
  return out.str();
}

std::string formatUv(const Eigen::Vector2d& p) {
  std::ostringstream out;
  out << "(" << p.x() << ", " << p.y() << ")";
  return out.str();
}

struct Cell {
  std::array<int64_t, 3> key;
  bool operator==(const Cell&) const = default;
};

struct CellHash {
  size_t operator()(const Cell& c) const {
    uint64_t h = 0x9e3779b97f4a7c15ull;
    for (int64_t k : c.key) h = (h ^ static_cast<uint64_t>(k)) * 0x100000001b3ull + (h >> 29);
    return static_cast<size_t>(h);
  }
};

/// Exact welding: one representative per bit pattern (with -0 folded onto +0).
std::vector<int32_t> exactRepresentatives(const std::vector<Eigen::Vector3d>& positions) {
  std::unordered_map<Cell, int32_t, CellHash> first;
  first.reserve(positions.size());
  std::vector<int32_t> representative(positions.size());
  for (size_t i = 0; i < positions.size(); ++i) {
    Cell key{};
    for (int c = 0; c < 3; ++c)
      key.key[static_cast<size_t>(c)] = std::bit_cast<int64_t>(positions[i][c] + 0.0);
    representative[i] = first.try_emplace(key, static_cast<int32_t>(i)).first->second;
  }
  return representative;
}

/// Tolerance welding on a uniform grid of cell size `tolerance`: each vertex joins the first
/// earlier representative within `tolerance` found in the 27 surrounding cells (greedy, in
/// vertex order), otherwise it becomes a representative itself.
std::vector<int32_t> gridRepresentatives(const std::vector<Eigen::Vector3d>& positions,
                                         double tolerance) {
  std::unordered_map<Cell, std::vector<int32_t>, CellHash> grid;
  grid.reserve(positions.size());
  std::vector<int32_t> representative(positions.size());
  for (size_t i = 0; i < positions.size(); ++i) {
    const Eigen::Vector3d& p = positions[i];
    Cell cell{};
    for (int c = 0; c < 3; ++c) {
      const double g = std::floor(p[c] / tolerance);
      if (!(std::abs(g) < kMaxGridCoordinate))
        throw InvalidInputError("weld tolerance " + formatNumber(tolerance) +
                                " is too small for vertex " + std::to_string(i) + " at " +
                                formatPoint(p) + "; use a larger tolerance or 0 (exact welding)");
      cell.key[static_cast<size_t>(c)] = static_cast<int64_t>(g);
    }
    int32_t found = -1;
    for (int64_t dx = -1; dx <= 1 && found < 0; ++dx)
      for (int64_t dy = -1; dy <= 1 && found < 0; ++dy)
        for (int64_t dz = -1; dz <= 1 && found < 0; ++dz) {
          const Cell near{{cell.key[0] + dx, cell.key[1] + dy, cell.key[2] + dz}};
          const auto it = grid.find(near);
          if (it == grid.end()) continue;
          for (int32_t r : it->second)
            if ((positions[static_cast<size_t>(r)] - p).norm() <= tolerance) {
              found = r;
              break;
            }
        }
    if (found < 0) {
      found = static_cast<int32_t>(i);
      grid[cell].push_back(found);
    }
    representative[i] = found;
  }
  return representative;
}

}  // namespace

void MeshReadOptions::validate() const {
  if (!std::isfinite(weldTolerance) || weldTolerance < 0.0)
    throw InvalidInputError("weldTolerance must be a finite number >= 0 (got " +
                            formatNumber(weldTolerance) +
                            "); use 0 to weld only identical positions");
  if (uvSet < 0)
    throw InvalidInputError("uvSet must be >= 0 (got " + std::to_string(uvSet) +
                            "); UV sets are numbered from 0 (glTF TEXCOORD_0)");
}

void requireReadableFile(const std::filesystem::path& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw IoError("cannot open " + path.string() + ": it is a folder; pass a mesh file");
  std::ifstream probe(path, std::ios::binary);
  if (!probe) {
    const int code = errno;
    throw IoError("cannot open " + path.string() + ": " +
                  (code != 0 ? std::strerror(code) : "unreadable file") +
                  "; check the path and permissions");
  }
}

TexturedMesh readMesh(const std::filesystem::path& path, const MeshReadOptions& options) {
  options.validate();
  const std::string extension = lowercase(path.extension().string());
  const bool gltf = extension == ".gltf" || extension == ".glb";
  if (options.uvSet != 0 && (extension == ".obj" || extension == ".ply")) {
    requireReadableFile(path);
    throw InvalidInputError(path.string() + ": UV set " + std::to_string(options.uvSet) +
                            " asked for, but " + extension +
                            " files hold one UV set (0); UV sets are a glTF feature");
  }
  TexturedMesh mesh;
  if (extension == ".obj") {
    mesh = readObj(path);
  } else if (extension == ".ply") {
    mesh = readPly(path);
  } else if (gltf) {
    mesh = readGltf(path, options.uvSet);
  } else {
    requireReadableFile(path);
    throw UnsupportedError(path.string() + ": unknown mesh extension '" + extension +
                           "'; use .obj, .ply, .gltf or .glb");
  }
  // Each reader has already run validateMesh, so the welding below sees in-range indices.
  weldPositions(mesh, options.weldTolerance);
  mesh.sourcePath = path;
  return mesh;
}

size_t weldPositions(TexturedMesh& mesh, double tolerance) {
  if (!std::isfinite(tolerance) || tolerance < 0.0)
    throw InvalidInputError("weld tolerance must be a finite number >= 0 (got " +
                            formatNumber(tolerance) + ")");
  const size_t n = mesh.positions.size();
  for (size_t f = 0; f < mesh.triangles.size(); ++f)
    for (int32_t v : mesh.triangles[f])
      if (v < 0 || static_cast<size_t>(v) >= n)
        throw InvalidInputError("cannot weld: face " + std::to_string(f) + " references vertex " +
                                std::to_string(v) + " but there are " + std::to_string(n) +
                                " vertices; run validateMesh first");
  const std::vector<int32_t> representative = tolerance == 0.0
                                                  ? exactRepresentatives(mesh.positions)
                                                  : gridRepresentatives(mesh.positions, tolerance);
  // Representatives always precede the vertices they absorb, so one pass compacts in order.
  std::vector<int32_t> newIndex(n, -1);
  std::vector<Eigen::Vector3d> kept;
  kept.reserve(n);
  for (size_t i = 0; i < n; ++i) {
    const auto r = static_cast<size_t>(representative[i]);
    if (r == i) {
      newIndex[i] = static_cast<int32_t>(kept.size());
      kept.push_back(mesh.positions[i]);
    } else {
      newIndex[i] = newIndex[r];
    }
  }
  for (Triangle& t : mesh.triangles)
    for (int32_t& v : t) v = newIndex[static_cast<size_t>(v)];
  const size_t removed = n - kept.size();
  mesh.positions = std::move(kept);
  return removed;
}

void validateMesh(const TexturedMesh& mesh, const std::string& what) {
  if (mesh.triangles.empty())
    throw InvalidInputError(what + ": the mesh has no faces; export it as a surface mesh");
  if (mesh.uvs.empty())
    throw InvalidInputError(what +
                            ": the mesh has no texture coordinates; UV-unwrap it and export "
                            "it with UVs");
  if (mesh.uvTriangles.size() != mesh.triangles.size())
    throw InvalidInputError(what + ": " + std::to_string(mesh.triangles.size()) + " faces but " +
                            std::to_string(mesh.uvTriangles.size()) +
                            " UV faces; every face needs texture coordinates at its corners");
  for (size_t v = 0; v < mesh.positions.size(); ++v)
    if (!mesh.positions[v].allFinite())
      throw InvalidInputError(what + ": vertex " + std::to_string(v) +
                              " has a non-finite coordinate " + formatPoint(mesh.positions[v]) +
                              "; fix or remove it in the mesh file");
  for (size_t t = 0; t < mesh.uvs.size(); ++t)
    if (!mesh.uvs[t].allFinite())
      throw InvalidInputError(what + ": texture coordinate " + std::to_string(t) +
                              " is non-finite " + formatUv(mesh.uvs[t]) +
                              "; fix the UVs in the mesh file");
  const auto checkIndices = [&](const std::vector<Triangle>& faces, size_t count, const char* kind,
                                const char* kinds) {
    for (size_t f = 0; f < faces.size(); ++f)
      for (int32_t v : faces[f])
        if (v < 0 || static_cast<size_t>(v) >= count)
          throw InvalidInputError(what + ": face " + std::to_string(f) + " references " + kind +
                                  " " + std::to_string(v) + " but there are " +
                                  std::to_string(count) + " " + kinds +
                                  " (0-based); the file is corrupt or truncated, re-export it");
  };
  checkIndices(mesh.triangles, mesh.positions.size(), "vertex", "vertices");
  checkIndices(mesh.uvTriangles, mesh.uvs.size(), "texture coordinate", "texture coordinates");
  if (!mesh.faceMaterial.empty() && mesh.faceMaterial.size() != mesh.triangles.size())
    throw InvalidInputError(what + ": " + std::to_string(mesh.faceMaterial.size()) +
                            " face materials for " + std::to_string(mesh.triangles.size()) +
                            " faces; give every face a material or none");
  for (size_t f = 0; f < mesh.faceMaterial.size(); ++f)
    if (mesh.faceMaterial[f] < -1 ||
        mesh.faceMaterial[f] >= static_cast<int32_t>(mesh.materials.size()))
      throw InvalidInputError(what + ": face " + std::to_string(f) + " uses material " +
                              std::to_string(mesh.faceMaterial[f]) + " but there are " +
                              std::to_string(mesh.materials.size()) +
                              " materials (0-based); the file is corrupt, re-export it");
}

}  // namespace texgrad
