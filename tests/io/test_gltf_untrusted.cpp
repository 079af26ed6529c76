// Hostile glTF/GLB files found by fuzzing (issue 27): JSON nested very deeply (tinygltf's parse
// recursed until the stack overflowed), image bufferViews past their buffer (read past it), and
// buffer or image URIs naming a folder (tinygltf allocated 2^63 - 1 bytes for it).
#include <gtest/gtest.h>

#include <cstdint>
#include <fstream>
#include <string>

#include "test_paths.h"
#include "texgrad/core/error.h"
#include "texgrad/io/mesh_reader.h"

namespace texgrad {
namespace {

namespace fs = std::filesystem;

constexpr int kCrashDepth = 100000;  ///< deep enough to overflow the stack of an unbounded parse

/// A glTF document whose "extras" nest `depth` arrays (`[[...]]`) or objects (`{"a":{...}}`).
std::string deepJson(int depth, bool objects) {
  std::string extras;
  extras.reserve(static_cast<size_t>(depth) * 6);
  for (int i = 0; i < depth; ++i) extras += objects ? R"({"a":)" : "[";
  extras += objects ? "0" : "";
  for (int i = 0; i < depth; ++i) extras += objects ? "}" : "]";
  return R"({"asset":{"version":"2.0"},"extras":)" + extras + "}";
}

/// GLB container around `json`: 12-byte header, JSON chunk (space padded), BIN chunk if any.
std::string glbOf(std::string json, const std::string& bin = "") {
  json.append((4 - json.size() % 4) % 4, ' ');
  std::string out = "glTF";
  const auto put = [&](uint32_t x) { out.append(reinterpret_cast<const char*>(&x), 4); };
  put(2);
  put(static_cast<uint32_t>(12 + 8 + json.size() + (bin.empty() ? 0 : 8 + bin.size())));
  put(static_cast<uint32_t>(json.size()));
  out += "JSON" + json;
  if (bin.empty()) return out;
  put(static_cast<uint32_t>(bin.size()));
  return out + std::string("BIN\0", 4) + bin;
}

fs::path writeAsset(const std::string& name, const std::string& bytes) {
  const fs::path path = test::tempDir("gltf_depth") / name;
  std::ofstream(path, std::ios::binary) << bytes;
  return path;
}

/// The message readMesh throws for `path`, which must be one line naming the file.
void expectRefusedInOneLine(const fs::path& path) {
  try {
    readMesh(path);
    ADD_FAILURE() << path << " was read";
  } catch (const InvalidInputError& e) {
    const std::string message = e.what();
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
    EXPECT_NE(message.find(path.string()), std::string::npos) << message;
    EXPECT_NE(message.find("nests deeper than"), std::string::npos) << message;
  }
}

TEST(GltfJsonDepth, DeeplyNestedArraysInGltfAreRefused) {
  expectRefusedInOneLine(writeAsset("arrays.gltf", deepJson(kCrashDepth, false)));
}

TEST(GltfJsonDepth, DeeplyNestedObjectsInGltfAreRefused) {
  expectRefusedInOneLine(writeAsset("objects.gltf", deepJson(kCrashDepth, true)));
}

TEST(GltfJsonDepth, DeeplyNestedJsonChunkInGlbIsRefused) {
  expectRefusedInOneLine(writeAsset("arrays.glb", glbOf(deepJson(kCrashDepth, false))));
  expectRefusedInOneLine(writeAsset("objects.glb", glbOf(deepJson(kCrashDepth, true))));
}

TEST(GltfJsonDepth, BracketsInStringsAndModestNestingAreParsed) {
  // 60 levels of extras (+1 for the document) is within the limit; the brackets inside the
  // string would exceed it if strings were not skipped (with an escaped quote inside too).
  std::string json = deepJson(60, false);
  json.insert(1, R"("x":")" + std::string(200, '[') + R"(\"",)");
  try {
    readMesh(writeAsset("modest.gltf", json));
  } catch (const InvalidInputError& e) {
    // A document without meshes is refused later, for having no triangles, not for its depth.
    EXPECT_EQ(std::string(e.what()).find("nests deeper"), std::string::npos) << e.what();
  }
}

TEST(GltfUntrusted, ImageBufferViewPastItsBufferIsRefused) {
  // 8 bytes of buffer; the image's view asks for 9 from byte 4 (ASan saw the read past the end).
  const std::string json = R"({"asset":{"version":"2.0"},"buffers":[{"byteLength":8}],
    "bufferViews":[{"buffer":0,"byteOffset":4,"byteLength":9}],
    "images":[{"bufferView":0,"mimeType":"image/png"}]})";
  const fs::path path = writeAsset("view.glb", glbOf(json, std::string(8, 'x')));
  try {
    readMesh(path);
    ADD_FAILURE() << "read";
  } catch (const InvalidInputError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("image 0: bufferView 0 (bytes 4 + 9) reaches past the end of buffer 0 "
                           "(8 bytes)"),
              std::string::npos)
        << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  }
}

/// A one-triangle glTF with its buffer embedded and one base-colour image at `imageUri`, or its
/// buffer at `bufferUri` if that is given.
std::string triangleWithUris(const std::string& imageUri, const std::string& bufferUri = "") {
  const std::string embedded =
      "data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD9AAAAAAAAAAA"
      "AAgD8AAIA/AACAPwAAAAAAAAAAAAABAAIAAAA=";
  return R"({"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}],
    "meshes":[{"primitives":[{"attributes":{"POSITION":0,"TEXCOORD_0":1},"indices":2,
      "material":0}]}],
    "materials":[{"pbrMetallicRoughness":{"baseColorTexture":{"index":0}}}],
    "textures":[{"source":0}],"images":[{"uri":")" + imageUri + R"("}],
    "buffers":[{"byteLength":68,"uri":")" + (bufferUri.empty() ? embedded : bufferUri) + R"("}],
    "bufferViews":[{"buffer":0,"byteOffset":0,"byteLength":36},
      {"buffer":0,"byteOffset":36,"byteLength":24},{"buffer":0,"byteOffset":60,"byteLength":6}],
    "accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3",
      "min":[0,0,0],"max":[1,1,0]},{"bufferView":1,"componentType":5126,"count":3,"type":"VEC2"},
      {"bufferView":2,"componentType":5123,"count":3,"type":"SCALAR"}]})";
}

TEST(GltfUntrusted, ImageUriNamingTheFolderIsAMissingImage) {
  // "." (or a URI that decodes to a NUL byte) names the asset's folder, which tinygltf's own file
  // reader took for a file of 2^63 - 1 bytes and allocated (found by fuzzing): now the image is
  // missing, as a file that is not there would be, and the mesh is read.
  for (const char* uri : {".", "%00"}) {
    const TexturedMesh mesh = readMesh(writeAsset("folder_image.gltf", triangleWithUris(uri)));
    EXPECT_EQ(mesh.triangles.size(), 1u) << uri;
  }
}

TEST(GltfUntrusted, BufferUriNamingTheFolderIsAMissingFile) {
  const fs::path path = writeAsset("folder_buffer.gltf", triangleWithUris("", "."));
  try {
    readMesh(path);
    ADD_FAILURE() << "read";
  } catch (const IoError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("File not found"), std::string::npos) << message;
    EXPECT_NE(message.find(path.string()), std::string::npos) << message;
  }
}

}  // namespace
}  // namespace texgrad
