// glTF/GLB whose JSON nests very deeply: refused with one line before tinygltf parses it (the
// parse used to recurse until the stack overflowed, issue 27).
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

/// GLB container around `json`: 12-byte header and one JSON chunk (space padded).
std::string glbOf(std::string json) {
  json.append((4 - json.size() % 4) % 4, ' ');
  std::string out = "glTF";
  const auto put = [&](uint32_t x) { out.append(reinterpret_cast<const char*>(&x), 4); };
  put(2);
  put(static_cast<uint32_t>(12 + 8 + json.size()));
  put(static_cast<uint32_t>(json.size()));
  return out + "JSON" + json;
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

}  // namespace
}  // namespace texgrad
