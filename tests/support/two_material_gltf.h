// A small glTF asset written by the tests: four quads (primitives) with three materials, three
// PNG images and two UV sets, for the reader's materials and samplers, --uv-set and the
// write-back of several images at once (tests/io, tests/cli, tests/gltf-validator).
#pragma once

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <string>
#include <vector>

#include "texgrad/io/image.h"
#include "texgrad/io/image_io.h"

namespace texgrad::test {

/// Side of the fixture's square images, in texels.
inline constexpr int kTwoMaterialImageSize = 8;

/// An 8-bit RGB image whose texels encode (i, j) and `seed`, so images and flips differ.
inline Image fixtureImage(int seed) {
  Image image(kTwoMaterialImageSize, kTwoMaterialImageSize, 3, PixelFormat::UInt8);
  for (int j = 0; j < image.height; ++j)
    for (int i = 0; i < image.width; ++i) {
      image.at(i, j, 0) = static_cast<float>((i * 16 + seed * 50) % 256) / 255.0f;
      image.at(i, j, 1) = static_cast<float>((j * 16 + seed * 30) % 256) / 255.0f;
      image.at(i, j, 2) = static_cast<float>((seed * 70 + i * j) % 256) / 255.0f;
    }
  return image;
}

/// What writeTwoMaterialGltf builds.
///
/// Primitive p (p = 0..3) is the quad [p, p + 1] x [0, 1] (two triangles) with TEXCOORD_0
/// (x - p, 1 - y), i.e. its corners on [0, 1]^2 unflipped (glTF's v points down), and
/// TEXCOORD_1 = 0.25 + TEXCOORD_0 / 2. Materials:
/// 0 "red" (baseColor image 0, CLAMP_TO_EDGE x MIRRORED_REPEAT sampler; normal image 2),
/// 1 unnamed (baseColor image 1, no sampler), 2 "green" (baseColor image 1 again, through another
/// texture with a MIRRORED_REPEAT x CLAMP_TO_EDGE sampler). Primitives 0, 1, 2 use materials
/// 0, 1, 2; primitive 3 has none (or material 0 with everyMaterial). Images are PNG files beside
/// the .gltf, the buffer a .bin.
struct TwoMaterialGltf {
  bool secondUvSet = true;     ///< false: primitive 2 lacks TEXCOORD_1
  bool everyMaterial = false;  ///< true: primitive 3 uses material 0, so every face has an image
  static constexpr int kPrimitives = 4;
  static constexpr int kCorners = 4;

  /// Writes `name`.gltf, `name`.bin and `name`_{0,1,2}.png into `dir`; returns the .gltf path.
  std::filesystem::path write(const std::filesystem::path& dir, const std::string& name) const {
    std::string bin;
    const auto putFloat = [&](float x) { bin.append(reinterpret_cast<const char*>(&x), 4); };
    const float corners[kCorners][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    for (int p = 0; p < kPrimitives; ++p)
      for (const auto& c : corners) {
        putFloat(static_cast<float>(p) + c[0]);
        putFloat(c[1]);
        putFloat(0.0f);
      }
    for (const auto& c : corners) {  // TEXCOORD_0: v down, so charts are not flipped
      putFloat(c[0]);
      putFloat(1.0f - c[1]);
    }
    for (const auto& c : corners) {  // TEXCOORD_1
      putFloat(0.25f + c[0] / 2);
      putFloat(0.25f + (1.0f - c[1]) / 2);
    }
    for (const uint16_t i : std::initializer_list<uint16_t>{0, 1, 2, 0, 2, 3})
      bin.append(reinterpret_cast<const char*>(&i), 2);
    bin.append(2, '\0');  // 4-byte length
    const size_t positionBytes = kPrimitives * kCorners * 12, uvBytes = kCorners * 8;
    std::ofstream(dir / (name + ".bin"), std::ios::binary) << bin;
    for (int k = 0; k < 3; ++k)
      writeImage(dir / (name + "_" + std::to_string(k) + ".png"), fixtureImage(k));

    std::string accessors, primitives;
    for (int p = 0; p < kPrimitives; ++p) {
      accessors += R"({"bufferView":0,"byteOffset":)" + std::to_string(p * kCorners * 12) +
                   R"(,"componentType":5126,"count":4,"type":"VEC3","min":[)" + std::to_string(p) +
                   R"(,0,0],"max":[)" + std::to_string(p + 1) + R"(,1,0]},)";
      const bool uv1 = secondUvSet || p != 2;
      primitives +=
          std::string(p == 0 ? "" : ",") + R"({"attributes":{"POSITION":)" + std::to_string(p) +
          R"(,"TEXCOORD_0":4)" + (uv1 ? R"(,"TEXCOORD_1":5)" : "") + R"(},"indices":6)" +
          (p < 3 || everyMaterial ? R"(,"material":)" + std::to_string(p % 3) : std::string()) +
          "}";
    }
    const std::string json = R"({"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],
  "nodes":[{"mesh":0}],
  "meshes":[{"name":"quads","primitives":[)" +
                             primitives + R"(]}],
  "materials":[
    {"name":"red","pbrMetallicRoughness":{"baseColorTexture":{"index":0}},
     "normalTexture":{"index":2}},
    {"pbrMetallicRoughness":{"baseColorTexture":{"index":1}}},
    {"name":"green","pbrMetallicRoughness":{"baseColorTexture":{"index":3}}}],
  "samplers":[{"wrapS":33071,"wrapT":33648},{"wrapS":33648,"wrapT":33071}],
  "textures":[{"source":0,"sampler":0},{"source":1},{"source":2},{"source":1,"sampler":1}],
  "images":[{"uri":")" + name +
                             R"(_0.png"},{"uri":")" + name + R"(_1.png"},{"uri":")" + name +
                             R"(_2.png"}],
  "buffers":[{"uri":")" + name +
                             ".bin\",\"byteLength\":" + std::to_string(bin.size()) + R"(}],
  "bufferViews":[{"buffer":0,"byteOffset":0,"byteLength":)" +
                             std::to_string(positionBytes) + R"(,"byteStride":12,"target":34962},
    {"buffer":0,"byteOffset":)" +
                             std::to_string(positionBytes) + R"(,"byteLength":)" +
                             std::to_string(2 * uvBytes) +
                             R"(,"byteStride":8,"target":34962},
    {"buffer":0,"byteOffset":)" +
                             std::to_string(positionBytes + 2 * uvBytes) +
                             R"(,"byteLength":12,"target":34963}],
  "accessors":[)" + accessors +
                             R"(
    {"bufferView":1,"byteOffset":0,"componentType":5126,"count":4,"type":"VEC2"},
    {"bufferView":1,"byteOffset":)" +
                             std::to_string(uvBytes) +
                             R"(,"componentType":5126,"count":4,"type":"VEC2"},
    {"bufferView":2,"componentType":5123,"count":6,"type":"SCALAR"}]})";
    const std::filesystem::path path = dir / (name + ".gltf");
    std::ofstream(path, std::ios::binary) << json;
    return path;
  }
};

}  // namespace texgrad::test
