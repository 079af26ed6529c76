// Mesh readers: the shared meshes in every format against INDEX.md, plus small hand-written
// files for polygons, negative indices, PLY encodings and every kind of broken input.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <fstream>
#include <functional>
#include <iterator>
#include <limits>

#include "test_paths.h"
#include "texgrad/core/error.h"
#include "texgrad/io/mesh_reader.h"

namespace texgrad {
namespace {

namespace fs = std::filesystem;

struct IndexEntry {
  const char* obj;
  const char* ply;
  size_t vertices;
  size_t faces;
  const char* baseColor;  ///< file name of the colour map the OBJ's MTL names, or empty
};

// Rows of ../shared/data/INDEX.md.
const std::vector<IndexEntry>& indexEntries() {
  static const std::vector<IndexEntry> entries = {
      {"spot/spot_triangulated.obj", "spot/spot.tsp.ply", 2930, 5856, "spot_texture.png"},
      {"bob/bob_tri.obj", "bob/bob.tsp.ply", 5344, 10688, "bob_diffuse.png"},
      {"blub/blub_triangulated.obj", "blub/blub.tsp.ply", 7106, 14208, ""},
      {"lpshead/head_triangulated.obj", "lpshead/head.tsp.ply", 8844, 17684, "lambertian_1k.jpg"},
      {"ycb_scissors/textured_simple_reoriented.obj", "ycb_scissors/scissors.tsp.ply", 7860, 15728,
       "texture_map.png"},
      {"BoomBox/obj/BoomBox.obj", "BoomBox/obj/BoomBox.tsp.ply", 3133, 6036,
       "BoomBox_baseColor.png"},
      {"WaterBottle/obj/WaterBottle.obj", "WaterBottle/obj/WaterBottle.tsp.ply", 2385, 4510,
       "WaterBottle_baseColor.png"},
      {"Lantern/obj/Lantern.obj", "Lantern/obj/Lantern.tsp.ply", 2737, 5394, "Lantern_diffuse.png"},
      {"Avocado/obj/Avocado.obj", "Avocado/obj/Avocado.tsp.ply", 363, 682, "Avocado_baseColor.png"},
      {"Suzanne/obj/Suzanne.obj", "Suzanne/obj/Suzanne.tsp.ply", 2012, 3936,
       "Suzanne_BaseColor.png"},
  };
  return entries;
}

fs::path data(const std::string& relative) {
  return test::sharedData() / relative;
}

fs::path writeFile(const fs::path& dir, const std::string& name, const std::string& content) {
  const fs::path path = dir / name;
  std::ofstream out(path, std::ios::binary);
  out << content;
  return path;
}

Eigen::Vector3d cornerPosition(const TexturedMesh& m, size_t f, size_t k) {
  return m.positions[static_cast<size_t>(m.triangles[f][k])];
}

Eigen::Vector2d cornerUv(const TexturedMesh& m, size_t f, size_t k) {
  return m.uvs[static_cast<size_t>(m.uvTriangles[f][k])];
}

/// Largest per-corner difference of positions and UVs between two meshes with equal faces.
std::pair<double, double> cornerDifference(const TexturedMesh& a, const TexturedMesh& b) {
  double position = 0.0, uv = 0.0;
  for (size_t f = 0; f < a.faceCount(); ++f)
    for (size_t k = 0; k < 3; ++k) {
      position = std::max(position, (cornerPosition(a, f, k) - cornerPosition(b, f, k)).norm());
      uv = std::max(uv, (cornerUv(a, f, k) - cornerUv(b, f, k)).norm());
    }
  return {position, uv};
}

/// Compares meshes whose faces may be in another order: maps every vertex of `a` to the nearest
/// vertex of `b`, then every face of `a` to the face of `b` with the same (rotated) corners.
/// Returns the largest position distance, the largest corner UV distance and unmatched faces.
struct MatchResult {
  double position = 0.0, uv = 0.0;
  size_t unmatchedFaces = 0;
};

MatchResult matchMeshes(const TexturedMesh& a, const TexturedMesh& b) {
  constexpr double kCell = 1e-3;
  const auto cellOf = [&](const Eigen::Vector3d& p) {
    return std::array<int64_t, 3>{static_cast<int64_t>(std::floor(p.x() / kCell)),
                                  static_cast<int64_t>(std::floor(p.y() / kCell)),
                                  static_cast<int64_t>(std::floor(p.z() / kCell))};
  };
  std::map<std::array<int64_t, 3>, std::vector<int32_t>> grid;
  for (size_t v = 0; v < b.positions.size(); ++v)
    grid[cellOf(b.positions[v])].push_back(static_cast<int32_t>(v));
  MatchResult result;
  std::vector<int32_t> toB(a.positions.size(), -1);
  for (size_t v = 0; v < a.positions.size(); ++v) {
    const auto c = cellOf(a.positions[v]);
    double best = std::numeric_limits<double>::infinity();
    for (int64_t dx = -1; dx <= 1; ++dx)
      for (int64_t dy = -1; dy <= 1; ++dy)
        for (int64_t dz = -1; dz <= 1; ++dz) {
          const auto it = grid.find({c[0] + dx, c[1] + dy, c[2] + dz});
          if (it == grid.end()) continue;
          for (int32_t w : it->second) {
            const double d = (a.positions[v] - b.positions[static_cast<size_t>(w)]).norm();
            if (d < best) best = d, toB[v] = w;
          }
        }
    result.position = std::max(result.position, best);
  }
  // Faces keyed by their corners rotated so the smallest vertex index comes first.
  const auto rotation = [](const Triangle& t) {
    return t[0] < t[1] && t[0] < t[2] ? 0 : (t[1] < t[2] ? 1 : 2);
  };
  std::multimap<std::array<int32_t, 3>, std::pair<size_t, int>> facesOfB;
  for (size_t f = 0; f < b.faceCount(); ++f) {
    const Triangle& t = b.triangles[f];
    const int r = rotation(t);
    facesOfB.insert({{t[r], t[(r + 1) % 3], t[(r + 2) % 3]}, {f, r}});
  }
  for (size_t f = 0; f < a.faceCount(); ++f) {
    Triangle t;
    for (size_t k = 0; k < 3; ++k) t[k] = toB[static_cast<size_t>(a.triangles[f][k])];
    const int r = rotation(t);
    const auto [first, last] = facesOfB.equal_range({t[r], t[(r + 1) % 3], t[(r + 2) % 3]});
    double bestUv = std::numeric_limits<double>::infinity();
    for (auto it = first; it != last; ++it) {
      double uv = 0.0;
      for (int k = 0; k < 3; ++k)
        uv = std::max(
            uv, (cornerUv(a, f, static_cast<size_t>((r + k) % 3)) -
                 cornerUv(b, it->second.first, static_cast<size_t>((it->second.second + k) % 3)))
                    .norm());
      bestUv = std::min(bestUv, uv);
    }
    if (first == last)
      ++result.unmatchedFaces;
    else
      result.uv = std::max(result.uv, bestUv);
  }
  return result;
}

template <typename Error>
std::string messageOf(const std::function<void()>& action) {
  try {
    action();
  } catch (const Error& e) {
    return e.what();
  }
  ADD_FAILURE() << "expected an exception";
  return {};
}

// --- shared meshes -------------------------------------------------------------------------

TEST(MeshReader, ObjCountsMatchIndex) {
  for (const IndexEntry& e : indexEntries()) {
    SCOPED_TRACE(e.obj);
    const TexturedMesh mesh = readMesh(data(e.obj));
    EXPECT_EQ(mesh.positions.size(), e.vertices);
    EXPECT_EQ(mesh.faceCount(), e.faces);
    EXPECT_EQ(mesh.uvTriangles.size(), e.faces);
    EXPECT_EQ(mesh.sourcePath, data(e.obj));
    if (e.baseColor != nullptr && *e.baseColor != '\0') {
      const TextureRef* color = mesh.texture("baseColor");
      ASSERT_NE(color, nullptr);
      EXPECT_TRUE(color->path.is_absolute());
      EXPECT_EQ(color->path.filename(), e.baseColor);
      EXPECT_TRUE(fs::exists(color->path)) << color->path;
    }
  }
}

TEST(MeshReader, ObjNormalMapFromMtl) {
  const TexturedMesh mesh = readMesh(data("BoomBox/obj/BoomBox.obj"));
  const TextureRef* normal = mesh.texture("normal");
  ASSERT_NE(normal, nullptr);
  EXPECT_EQ(normal->path,
            (test::sharedData() / "BoomBox/glTF/BoomBox_normal.png").lexically_normal());
  EXPECT_TRUE(fs::exists(normal->path));
}

TEST(MeshReader, ObjQuadsAreTriangulated) {
  const TexturedMesh quads = readMesh(data("spot/spot_quadrangulated.obj"));
  EXPECT_EQ(quads.positions.size(), 2930u);
  EXPECT_EQ(quads.faceCount(), 2u * 2928u);
}

TEST(MeshReader, TspPlyMatchesObj) {
  for (const IndexEntry& e : indexEntries()) {
    SCOPED_TRACE(e.ply);
    const TexturedMesh obj = readMesh(data(e.obj));
    const TexturedMesh ply = readMesh(data(e.ply));
    ASSERT_EQ(ply.faceCount(), obj.faceCount());
    EXPECT_EQ(ply.positions.size(), obj.positions.size());
    EXPECT_EQ(ply.triangles, obj.triangles);
    const auto [position, uv] = cornerDifference(ply, obj);
    // The PLYs store float32, the OBJs decimal text read as double: differences are float
    // rounding of coordinates up to ~10 model units.
    EXPECT_LT(position, 1e-5);
    EXPECT_LT(uv, 1e-6 * 2);
    ASSERT_NE(ply.texture("baseColor"), nullptr);
    EXPECT_TRUE(fs::exists(ply.texture("baseColor")->path)) << ply.texture("baseColor")->path;
    if (const TextureRef* color = obj.texture("baseColor")) {
      EXPECT_EQ(ply.texture("baseColor")->path, color->path);
    }
  }
}

TEST(MeshReader, GltfMatchesObjConversion) {
  for (const char* model : {"Avocado", "BoomBox", "WaterBottle", "Lantern", "Suzanne"}) {
    SCOPED_TRACE(model);
    const std::string name(model);
    const TexturedMesh obj = readMesh(data(name + "/obj/" + name + ".obj"));
    const TexturedMesh gltf = readMesh(data(name + "/glTF/" + name + ".gltf"));
    ASSERT_EQ(gltf.faceCount(), obj.faceCount());
    EXPECT_EQ(gltf.positions.size(), obj.positions.size());
    const MatchResult match = matchMeshes(gltf, obj);
    EXPECT_LT(match.position, 1e-5);
    EXPECT_LT(match.uv, 1e-6);
    EXPECT_EQ(match.unmatchedFaces, 0u);
    const TextureRef* color = gltf.texture("baseColor");
    ASSERT_NE(color, nullptr);
    EXPECT_TRUE(color->path.is_absolute());
    EXPECT_TRUE(color->embedded.empty());
    EXPECT_EQ(color->path.parent_path(), data(name + "/glTF").lexically_normal());
    EXPECT_NE(gltf.texture("metallicRoughness"), nullptr);
    if (name != "Suzanne") {
      ASSERT_NE(gltf.texture("normal"), nullptr);
      EXPECT_TRUE(fs::exists(gltf.texture("normal")->path));
    }
  }
  const TexturedMesh boomBox = readMesh(data("BoomBox/glTF/BoomBox.gltf"));
  EXPECT_NE(boomBox.texture("emissive"), nullptr);
  EXPECT_NE(boomBox.texture("occlusion"), nullptr);
}

// --- hand-written OBJ ----------------------------------------------------------------------

TEST(MeshReader, ObjQuadNegativeIndicesAndMtl) {
  const fs::path dir = test::tempDir("obj_quads");
  writeFile(dir, "m.mtl", "newmtl a\nmap_Kd tex/color.png\nmap_Bump bump.png\n");
  const fs::path obj = writeFile(dir, "M.OBJ",
                                 "mtllib m.mtl\nusemtl a\n"
                                 "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\n"
                                 "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
                                 "f 1/1 2/2 3/3 4/4\n"
                                 "f -4/-3 -1/-2 -3/-4\n");
  const TexturedMesh mesh = readMesh(obj);
  ASSERT_EQ(mesh.faceCount(), 3u);
  EXPECT_EQ(mesh.positions.size(), 5u);
  EXPECT_EQ(mesh.triangles[0], (Triangle{0, 1, 2}));
  EXPECT_EQ(mesh.triangles[1], (Triangle{0, 2, 3}));
  EXPECT_EQ(mesh.triangles[2], (Triangle{1, 4, 2}));
  EXPECT_EQ(mesh.uvTriangles[2], (Triangle{1, 2, 0}));
  ASSERT_NE(mesh.texture("baseColor"), nullptr);
  EXPECT_EQ(mesh.texture("baseColor")->path, fs::absolute(dir / "tex/color.png"));
  ASSERT_NE(mesh.texture("normal"), nullptr);
  EXPECT_EQ(mesh.texture("normal")->path, fs::absolute(dir / "bump.png"));
}

TEST(MeshReader, ObjOutOfRangeIndexNamesLine) {
  const fs::path dir = test::tempDir("obj_range");
  const fs::path obj = writeFile(dir, "bad.obj",
                                 "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\n"
                                 "f 1/1 2/1 3/1\nf 1/1 2/1 3/1\nf 1/1 2/1 9/1\n");
  const std::string message = messageOf<InvalidInputError>([&] { readMesh(obj); });
  EXPECT_NE(message.find("bad.obj"), std::string::npos) << message;
  EXPECT_NE(message.find("bad.obj line 7"), std::string::npos) << message;
  EXPECT_NE(message.find("vertex 9"), std::string::npos) << message;
  EXPECT_NE(message.find("has 3"), std::string::npos) << message;
}

TEST(MeshReader, ObjNanCoordinateThrows) {
  const fs::path dir = test::tempDir("obj_nan");
  const fs::path obj =
      writeFile(dir, "nan.obj", "v 0 0 0\nv 1 nan 0\nv 0 1 0\nvt 0 0\nf 1/1 2/1 3/1\n");
  const std::string message = messageOf<InvalidInputError>([&] { readMesh(obj); });
  EXPECT_NE(message.find("nan.obj line 2: vertex 1"), std::string::npos) << message;
  const fs::path inf =
      writeFile(dir, "inf.obj", "v 0 0 0\nv 1 1e400 0\nv 0 1 0\nvt 0 0\nf 1/1 2/1 3/1\n");
  EXPECT_THROW(readMesh(inf), InvalidInputError);
  const fs::path word =
      writeFile(dir, "word.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 x\nf 1/1 2/1 3/1\n");
  EXPECT_THROW(readMesh(word), InvalidInputError);
}

TEST(MeshReader, ObjWithoutUvsThrows) {
  const fs::path dir = test::tempDir("obj_nouv");
  const fs::path obj = writeFile(dir, "plain.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  const std::string message = messageOf<InvalidInputError>([&] { readMesh(obj); });
  EXPECT_NE(message.find("texture coordinates"), std::string::npos) << message;
}

TEST(MeshReader, MissingFileIsIoError) {
  for (const char* name : {"missing.obj", "missing.ply", "missing.gltf", "missing.glb"}) {
    const fs::path path = test::tempDir("missing") / name;
    const std::string message = messageOf<IoError>([&] { readMesh(path); });
    EXPECT_NE(message.find("cannot open " + path.string() + ": No such file"), std::string::npos)
        << message;
  }
}

TEST(MeshReader, UnknownExtensionIsUnsupported) {
  const fs::path path = writeFile(test::tempDir("ext"), "mesh.stl", "solid\n");
  EXPECT_THROW(readMesh(path), UnsupportedError);
}

// --- hand-written PLY ----------------------------------------------------------------------

const char* kAsciiPlyPerVertexUv =
    "ply\r\nformat ascii 1.0\r\ncomment TextureFile img.png\r\n"
    "element vertex 4\r\nproperty float x\r\nproperty float y\r\nproperty float z\r\n"
    "property float u\r\nproperty float v\r\n"
    "element face 1\r\nproperty list uchar int vertex_indices\r\nend_header\r\n"
    "0 0 0 0 0\r\n1 0 0 0.5 0\r\n1 1 0 0.5 0.5\r\n0 1 0 0 0.5\r\n4 0 1 2 3\r\n";

TEST(MeshReader, AsciiPlyPerVertexUv) {
  const fs::path dir = test::tempDir("ply_ascii");
  const TexturedMesh mesh = readMesh(writeFile(dir, "quad.PLY", kAsciiPlyPerVertexUv));
  ASSERT_EQ(mesh.faceCount(), 2u);
  EXPECT_EQ(mesh.positions.size(), 4u);
  EXPECT_EQ(mesh.triangles[1], (Triangle{0, 2, 3}));
  EXPECT_EQ(mesh.uvTriangles, mesh.triangles);
  EXPECT_EQ(mesh.uvs[2], Eigen::Vector2d(0.5, 0.5));
  ASSERT_NE(mesh.texture("baseColor"), nullptr);
  EXPECT_EQ(mesh.texture("baseColor")->path, fs::absolute(dir / "img.png"));
}

TEST(MeshReader, PlyPerVertexUvSplitVerticesAreWelded) {
  // Two triangles sharing an edge, written with split (duplicated) vertices as glTF does.
  const std::string ply =
      "ply\nformat ascii 1.0\nelement vertex 6\nproperty double x\nproperty double y\n"
      "property double z\nproperty float s\nproperty float t\nelement face 2\n"
      "property list uchar uint vertex_index\nend_header\n"
      "0 0 0 0 0\n1 0 0 1 0\n0 1 0 0 1\n1 0 0 0.5 0\n1 1 0 1 1\n0 1 0 0 0.5\n3 0 1 2\n3 3 4 5\n";
  const TexturedMesh mesh = readMesh(writeFile(test::tempDir("ply_split"), "split.ply", ply));
  EXPECT_EQ(mesh.positions.size(), 4u);
  EXPECT_EQ(mesh.uvs.size(), 6u);
  EXPECT_EQ(mesh.triangles[1], (Triangle{1, 3, 2}));
  EXPECT_EQ(mesh.uvTriangles[1], (Triangle{3, 4, 5}));
}

/// Binary PLY of one quad with per-corner texcoord lists, in either byte order.
std::string binaryPly(bool bigEndian) {
  std::string out = std::string("ply\nformat ") +
                    (bigEndian ? "binary_big_endian" : "binary_little_endian") +
                    " 1.0\ncomment TextureFile t.png\nelement vertex 4\nproperty float x\n"
                    "property float y\nproperty float z\nelement face 1\n"
                    "property list uchar int vertex_indices\nproperty list uchar float texcoord\n"
                    "end_header\n";
  const auto put = [&](auto value) {
    auto bytes = std::bit_cast<std::array<char, sizeof(value)>>(value);
    if (bigEndian == (std::endian::native == std::endian::little))
      std::reverse(bytes.begin(), bytes.end());
    out.append(bytes.data(), bytes.size());
  };
  const float xyz[4][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  for (const auto& p : xyz)
    for (float c : p) put(c);
  put(static_cast<uint8_t>(4));
  for (int32_t i : {0, 1, 2, 3}) put(i);
  put(static_cast<uint8_t>(8));
  for (float c : {0.f, 0.f, 0.25f, 0.f, 0.25f, 0.75f, 0.f, 0.75f}) put(c);
  return out;
}

TEST(MeshReader, BinaryPlyBothByteOrders) {
  const fs::path dir = test::tempDir("ply_binary");
  for (bool big : {false, true}) {
    SCOPED_TRACE(big ? "big endian" : "little endian");
    const TexturedMesh mesh = readMesh(writeFile(dir, "q.ply", binaryPly(big)));
    ASSERT_EQ(mesh.faceCount(), 2u);
    EXPECT_EQ(mesh.positions[2], Eigen::Vector3d(1, 1, 0));
    EXPECT_EQ(mesh.triangles[1], (Triangle{0, 2, 3}));
    EXPECT_EQ(cornerUv(mesh, 1, 1), Eigen::Vector2d(0.25, 0.75));
    EXPECT_EQ(cornerUv(mesh, 1, 2), Eigen::Vector2d(0.0, 0.75));
    EXPECT_EQ(mesh.texture("baseColor")->path, fs::absolute(dir / "t.png"));
  }
}

TEST(MeshReader, TruncatedBinaryPlyThrowsAtEveryLength) {
  const fs::path dir = test::tempDir("ply_truncated");
  const std::string full = binaryPly(false);
  for (size_t length = 0; length < full.size(); ++length) {
    SCOPED_TRACE(length);
    const fs::path path = writeFile(dir, "cut.ply", full.substr(0, length));
    EXPECT_THROW(readMesh(path), InvalidInputError);
  }
  const std::string real = [] {
    std::ifstream in(data("spot/spot.tsp.ply"), std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  }();
  for (size_t length : {real.size() / 2, real.size() - 1}) {
    const fs::path path = writeFile(dir, "spot_cut.ply", real.substr(0, length));
    const std::string message = messageOf<InvalidInputError>([&] { readMesh(path); });
    EXPECT_NE(message.find("truncated"), std::string::npos) << message;
  }
}

TEST(MeshReader, PlyHugeCountsAreRejectedNotAllocated) {
  const fs::path dir = test::tempDir("ply_huge");
  std::string ply = binaryPly(false);
  ply.replace(ply.find("vertex 4"), 8, "vertex 2000000000");
  EXPECT_THROW(readMesh(writeFile(dir, "huge.ply", ply)), InvalidInputError);
  std::string list = kAsciiPlyPerVertexUv;
  list.replace(list.find("4 0 1 2 3"), 1, "100000");
  const std::string message =
      messageOf<InvalidInputError>([&] { readMesh(writeFile(dir, "list.ply", list)); });
  EXPECT_NE(message.find("length 100000"), std::string::npos) << message;
}

TEST(MeshReader, PlyOutOfRangeIndexNamesFace) {
  std::string ply = kAsciiPlyPerVertexUv;
  ply.replace(ply.find("4 0 1 2 3"), 9, "4 0 1 2 7");
  const fs::path path = writeFile(test::tempDir("ply_range"), "bad.ply", ply);
  const std::string message = messageOf<InvalidInputError>([&] { readMesh(path); });
  EXPECT_NE(message.find("bad.ply: face 0 references vertex 7 but there are 4 vertices"),
            std::string::npos)
      << message;
}

TEST(MeshReader, PlyWithoutUvsOrWithBadHeaderThrows) {
  const fs::path dir = test::tempDir("ply_bad");
  std::string noUv = kAsciiPlyPerVertexUv;
  noUv.replace(noUv.find("property float u"), 16, "property float q");
  EXPECT_THROW(readMesh(writeFile(dir, "nouv.ply", noUv)), InvalidInputError);
  EXPECT_THROW(readMesh(writeFile(dir, "notply.ply", "solid x\n")), InvalidInputError);
  std::string badNumber = kAsciiPlyPerVertexUv;
  badNumber.replace(badNumber.find("0.5 0.5"), 3, "abc");
  EXPECT_THROW(readMesh(writeFile(dir, "nan.ply", badNumber)), InvalidInputError);
  std::string nan = kAsciiPlyPerVertexUv;
  nan.replace(nan.find("1 1 0 0.5"), 5, "1 nan 0");
  EXPECT_THROW(readMesh(writeFile(dir, "nanpos.ply", nan)), InvalidInputError);
}

// --- hand-written glTF ---------------------------------------------------------------------

const std::string kPngSignature = "\x89PNG\r\n\x1a\n";  // stand-in embedded image bytes

std::string base64(const std::string& bytes) {
  static const char* kAlphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  for (size_t i = 0; i < bytes.size(); i += 3) {
    const size_t chunk = std::min<size_t>(3, bytes.size() - i);
    uint32_t n = 0;
    for (size_t k = 0; k < 3; ++k)
      n = (n << 8) | (k < chunk ? static_cast<uint8_t>(bytes[i + k]) : 0u);
    for (size_t k = 0; k < 4; ++k) out += k <= chunk ? kAlphabet[(n >> (18 - 6 * k)) & 63] : '=';
  }
  return out;
}

/// One-triangle glTF asset: 3 positions, 3 UVs, 3 indices of `indexType` (5121/5123/5125),
/// a node transform and a base-colour image embedded as a data URI (.gltf) or bufferView (.glb).
struct TinyGltf {
  std::string mode = "4";
  std::string nodeTransform = R"("name":"n")";
  int indexType = 5123;

  std::string buffer() const {
    const std::vector<float> floats = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 1, 1, 1, 0, 0};
    std::string bytes(floats.size() * sizeof(float), '\0');
    std::memcpy(bytes.data(), floats.data(), bytes.size());
    for (uint32_t i : {0u, 1u, 2u}) bytes.append(reinterpret_cast<const char*>(&i), indexSize());
    bytes.append((4 - bytes.size() % 4) % 4, '\0');
    return bytes + kPngSignature;
  }

  size_t indexSize() const { return indexType == 5121 ? 1 : indexType == 5123 ? 2 : 4; }

  std::string json(bool glb) const {
    const std::string bin = buffer();
    const size_t imageOffset = bin.size() - kPngSignature.size();
    const std::string image =
        glb ? R"({"bufferView":3,"mimeType":"image/png"})"
            : R"({"uri":"data:image/png;base64,)" + base64(kPngSignature) + R"("})";
    const std::string uri =
        glb ? "" : R"(,"uri":"data:application/octet-stream;base64,)" + base64(bin) + "\"";
    return R"({"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],
    "nodes":[{"mesh":0,)" +
           nodeTransform + R"(}],
    "meshes":[{"primitives":[{"attributes":{"POSITION":0,"TEXCOORD_0":1},"indices":2,
      "material":0,"mode":)" +
           mode + R"(}]}],
    "materials":[{"pbrMetallicRoughness":{"baseColorTexture":{"index":0}}}],
    "textures":[{"source":0}], "images":[)" +
           image + R"(],
    "buffers":[{"byteLength":)" +
           std::to_string(bin.size()) + uri + R"(}],
    "bufferViews":[{"buffer":0,"byteOffset":0,"byteLength":36},
                   {"buffer":0,"byteOffset":36,"byteLength":24},
                   {"buffer":0,"byteOffset":60,"byteLength":)" +
           std::to_string(3 * indexSize()) + R"(},
                   {"buffer":0,"byteOffset":)" +
           std::to_string(imageOffset) + R"(,"byteLength":8}],
    "accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3",
                  "min":[0,0,0],"max":[1,1,0]},
                 {"bufferView":1,"componentType":5126,"count":3,"type":"VEC2"},
                 {"bufferView":2,"componentType":)" +
           std::to_string(indexType) + R"(,"count":3,"type":"SCALAR"}]})";
  }

  /// Binary container: 12-byte header, JSON chunk (space padded), BIN chunk (zero padded).
  std::string glb() const {
    std::string text = json(true);
    text.append((4 - text.size() % 4) % 4, ' ');
    const std::string bin = buffer();
    std::string out;
    const auto put = [&](uint32_t x) { out.append(reinterpret_cast<const char*>(&x), 4); };
    out += "glTF";
    put(2);
    put(static_cast<uint32_t>(12 + 8 + text.size() + 8 + bin.size()));
    put(static_cast<uint32_t>(text.size()));
    out += "JSON";
    out += text;
    put(static_cast<uint32_t>(bin.size()));
    out += std::string("BIN\0", 4);
    out += bin;
    return out;
  }
};

TEST(MeshReader, GltfNodeTransformFlipAndEmbeddedTexture) {
  const fs::path dir = test::tempDir("gltf_tiny");
  TinyGltf asset;
  asset.nodeTransform = R"("translation":[10,0,0],"scale":[2,2,2])";
  const TexturedMesh mesh = readMesh(writeFile(dir, "t.gltf", asset.json(false)));
  ASSERT_EQ(mesh.faceCount(), 1u);
  EXPECT_TRUE(mesh.positions[1].isApprox(Eigen::Vector3d(12, 0, 0)));
  EXPECT_TRUE(mesh.positions[2].isApprox(Eigen::Vector3d(10, 2, 0)));
  EXPECT_TRUE(mesh.uvs[1].isApprox(Eigen::Vector2d(1, 0)));  // v_gltf = 1 -> 0
  EXPECT_TRUE(mesh.uvs[2].isApprox(Eigen::Vector2d(0, 1)));  // v_gltf = 0 -> 1
  const TextureRef* color = mesh.texture("baseColor");
  ASSERT_NE(color, nullptr);
  EXPECT_TRUE(color->path.empty());
  EXPECT_EQ(color->mimeType, "image/png");
  EXPECT_EQ(std::string(color->embedded.begin(), color->embedded.end()), kPngSignature);

  asset.nodeTransform = R"("matrix":[-1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1])";
  const TexturedMesh mirrored = readMesh(writeFile(dir, "m.gltf", asset.json(false)));
  EXPECT_EQ(mirrored.triangles[0], (Triangle{0, 2, 1}));
  EXPECT_TRUE(mirrored.positions[1].isApprox(Eigen::Vector3d(-1, 0, 0)));
}

TEST(MeshReader, GlbWithEveryIndexTypeAndBufferViewImage) {
  const fs::path dir = test::tempDir("glb");
  for (int indexType : {5121, 5123, 5125}) {
    SCOPED_TRACE(indexType);
    TinyGltf asset;
    asset.indexType = indexType;
    asset.nodeTransform = R"("rotation":[0,1,0,0])";  // 180 degrees about y
    const TexturedMesh mesh = readMesh(writeFile(dir, "t.GLB", asset.glb()));
    ASSERT_EQ(mesh.faceCount(), 1u);
    EXPECT_EQ(mesh.triangles[0], (Triangle{0, 1, 2}));
    EXPECT_TRUE(mesh.positions[1].isApprox(Eigen::Vector3d(-1, 0, 0)));
    const TextureRef* color = mesh.texture("baseColor");
    ASSERT_NE(color, nullptr);
    EXPECT_EQ(color->mimeType, "image/png");
    EXPECT_EQ(std::string(color->embedded.begin(), color->embedded.end()), kPngSignature);
  }
}

TEST(MeshReader, GltfNonTriangleModeIsUnsupported) {
  TinyGltf asset;
  asset.mode = "1";
  const fs::path path = writeFile(test::tempDir("gltf_lines"), "l.gltf", asset.json(false));
  EXPECT_THROW(readMesh(path), UnsupportedError);
}

TEST(MeshReader, GltfIndexOutOfRangeOrTruncatedBufferThrows) {
  const fs::path dir = test::tempDir("gltf_bad");
  TinyGltf asset;
  std::string json = asset.json(false);
  json.replace(json.find(R"("count":3,"type":"SCALAR")"), 9, R"("count":4)");
  EXPECT_THROW(readMesh(writeFile(dir, "count.gltf", json)), InvalidInputError);
  std::string fewer = asset.json(false);
  fewer.replace(fewer.find(R"("count":3,"type":"VEC3")"), 9, R"("count":2)");
  fewer.replace(fewer.find(R"("count":3,"type":"VEC2")"), 9, R"("count":2)");
  const std::string message =
      messageOf<InvalidInputError>([&] { readMesh(writeFile(dir, "fewer.gltf", fewer)); });
  EXPECT_NE(message.find("fewer.gltf: mesh 0 ('') primitive 0: face 0 references vertex 2 but "
                         "the primitive has 2 vertices"),
            std::string::npos)
      << message;
  const std::string glb = asset.glb();
  for (size_t length : {glb.size() / 2, glb.size() - 9})
    EXPECT_THROW(readMesh(writeFile(dir, "cut.glb", glb.substr(0, length))), InvalidInputError);
}

TEST(MeshReader, GltfMissingBufferIsIoError) {
  const fs::path dir = test::tempDir("gltf_nobin");
  std::ifstream in(data("Avocado/glTF/Avocado.gltf"));
  const std::string json((std::istreambuf_iterator<char>(in)), {});
  EXPECT_THROW(readMesh(writeFile(dir, "Avocado.gltf", json)), IoError);
}

// --- welding -------------------------------------------------------------------------------

TEST(WeldPositions, ExactAndTolerance) {
  TexturedMesh mesh;
  mesh.positions = {{0, 0, 0},        {1, 0, 0},    {0, 1, 0},   {1, 0, 0},
                    {1 + 1e-7, 1, 0}, {0, 1e-7, 0}, {-0.0, 0, 0}};
  mesh.uvs = {{0, 0}};
  mesh.triangles = {{0, 1, 2}, {3, 4, 5}, {6, 3, 4}};
  mesh.uvTriangles = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}};

  TexturedMesh exact = mesh;
  EXPECT_EQ(weldPositions(exact, 0.0), 2u);  // {1,0,0} twice, -0 == +0
  EXPECT_EQ(exact.positions.size(), 5u);
  EXPECT_EQ(exact.triangles[1], (Triangle{1, 3, 4}));
  EXPECT_EQ(exact.triangles[2], (Triangle{0, 1, 3}));
  EXPECT_EQ(exact.uvTriangles, mesh.uvTriangles);

  TexturedMesh loose = mesh;
  EXPECT_EQ(weldPositions(loose, 1e-6), 3u);  // also {0,1e-7,0} onto {0,0,0}
  EXPECT_EQ(loose.positions.size(), 4u);
  EXPECT_EQ(loose.triangles[1], (Triangle{1, 3, 0}));

  TexturedMesh coarse = mesh;
  EXPECT_EQ(weldPositions(coarse, 10.0), 6u);
  EXPECT_THROW(weldPositions(coarse, -1.0), InvalidInputError);
}

TEST(WeldPositions, ReadMeshOptionTolerance) {
  MeshReadOptions options;
  options.weldTolerance = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(options.validate(), InvalidInputError);
  options.weldTolerance = 1e-9;
  EXPECT_NO_THROW(options.validate());
  const TexturedMesh spot = readMesh(data("spot/spot.tsp.ply"), options);
  EXPECT_EQ(spot.positions.size(), 2930u);
}

TEST(ValidateMesh, ReportsUvIndexAndCountMismatch) {
  TexturedMesh mesh;
  mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  mesh.uvs = {{0, 0}};
  mesh.triangles = {{0, 1, 2}};
  mesh.uvTriangles = {{0, 0, 3}};
  const std::string message =
      messageOf<InvalidInputError>([&] { validateMesh(mesh, "thing.obj"); });
  EXPECT_NE(message.find("thing.obj: face 0 references texture coordinate 3"), std::string::npos)
      << message;
  mesh.uvTriangles.clear();
  EXPECT_THROW(validateMesh(mesh, "x"), InvalidInputError);
}

}  // namespace
}  // namespace texgrad
