// Small mesh files, written by the tests themselves, for the inputs readers used to accept with
// part of them silently lost: a cut face, two materials with two textures, a missing .mtl, a
// glTF image file that is not there.
#pragma once

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace texgrad::test::fixtures {

/// Writes `content` to dir/name and returns the path.
inline std::filesystem::path write(const std::filesystem::path& dir, const std::string& name,
                                   const std::string& content) {
  std::ofstream(dir / name, std::ios::binary) << content;
  return dir / name;
}

/// The unit square as two triangles, with UVs; `beforeFaces` goes just before the first face and
/// `betweenFaces` between the two.
inline std::string squareObj(const std::string& head, const std::string& beforeFaces = "",
                             const std::string& betweenFaces = "") {
  return head +
         "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
         "vt 0.1 0.1\nvt 0.9 0.1\nvt 0.9 0.9\nvt 0.1 0.9\n" +
         beforeFaces + "f 1/1 2/2 3/3\n" + betweenFaces + "f 1/1 3/3 4/4\n";
}

/// squareObj cut in the middle of its last face line (line 10 keeps two corners).
inline std::string truncatedObj() {
  const std::string whole = squareObj("");
  return whole.substr(0, whole.size() - std::string(" 4/4\n").size());
}

/// An OBJ whose two faces use materials 'red' and 'blue' of two.mtl.
inline std::string twoMaterialObj() {
  return squareObj("mtllib two.mtl\n", "usemtl red\n", "usemtl blue\n");
}

/// two.mtl: 'red' and 'blue' with their colour maps.
inline std::string twoMaterialMtl(const std::string& redMap, const std::string& blueMap) {
  return "newmtl red\nmap_Kd " + redMap + "\nnewmtl blue\nmap_Kd " + blueMap + "\n";
}

/// An OBJ whose 'mtllib' (line 1) names gone.mtl, which is not written.
inline std::string missingMtlObj() {
  return squareObj("mtllib gone.mtl\n", "usemtl paint\n");
}

/// Standard base64 (RFC 4648) of `bytes`.
inline std::string base64(const std::string& bytes) {
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

/// A one-triangle .gltf (geometry in a data URI) whose material has a baseColor texture (image 0,
/// file `baseColorUri`) and a normal texture (image 1, file `normalUri`); neither file is written.
inline std::string triangleGltf(const std::string& baseColorUri, const std::string& normalUri) {
  // UVs with glTF's v downward, so the triangle is counter-clockwise in the atlas too.
  const std::vector<float> floats = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0.1f, 0.9f, 0.9f, 0.9f, 0.1f, 0.1f};
  std::string bin(floats.size() * sizeof(float), '\0');
  std::memcpy(bin.data(), floats.data(), bin.size());
  for (uint16_t i : {uint16_t{0}, uint16_t{1}, uint16_t{2}})
    bin.append(reinterpret_cast<const char*>(&i), sizeof i);
  return R"({"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}],
  "meshes":[{"primitives":[{"attributes":{"POSITION":0,"TEXCOORD_0":1},"indices":2,"material":0}]}],
  "materials":[{"pbrMetallicRoughness":{"baseColorTexture":{"index":0}},
                "normalTexture":{"index":1}}],
  "textures":[{"source":0},{"source":1}],
  "images":[{"uri":")" +
         baseColorUri + R"("},{"uri":")" + normalUri + R"("}],
  "buffers":[{"byteLength":)" +
         std::to_string(bin.size()) + R"(,"uri":"data:application/octet-stream;base64,)" +
         base64(bin) + R"("}],
  "bufferViews":[{"buffer":0,"byteOffset":0,"byteLength":36},
                 {"buffer":0,"byteOffset":36,"byteLength":24},
                 {"buffer":0,"byteOffset":60,"byteLength":6}],
  "accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3",
                "min":[0,0,0],"max":[1,1,0]},
               {"bufferView":1,"componentType":5126,"count":3,"type":"VEC2"},
               {"bufferView":2,"componentType":5123,"count":3,"type":"SCALAR"}]})";
}

}  // namespace texgrad::test::fixtures
