// The meshes of ../shared/data with the counts INDEX.md lists for them (what tests check against).
#pragma once

#include <gtest/gtest.h>

#include <ostream>
#include <string>
#include <vector>

#include "test_paths.h"

namespace texgrad::test {

/// One shared model: its OBJ, colour texture and the INDEX.md figures.
struct SharedMesh {
  std::string name;
  std::string obj;      ///< relative to sharedData()
  std::string texture;  ///< relative to sharedData()
  int vertices, faces, charts, seamEdges, boundaryEdges;
};

/// GoogleTest prints a SharedMesh parameter by its name (not as a byte dump).
inline void PrintTo(const SharedMesh& mesh, std::ostream* os) { *os << mesh.name; }

/// Every model of ../shared/data/INDEX.md.
inline const std::vector<SharedMesh>& sharedMeshes() {
  static const std::vector<SharedMesh> meshes{
      {"spot", "spot/spot_triangulated.obj", "spot/spot_texture.png", 2930, 5856, 13, 288, 0},
      {"bob", "bob/bob_tri.obj", "bob/bob_diffuse.png", 5344, 10688, 3, 300, 0},
      {"blub", "blub/blub_triangulated.obj", "blub/blub_texture.png", 7106, 14208, 5, 208, 0},
      {"lpshead", "lpshead/head_triangulated.obj", "lpshead/lambertian_1k.jpg", 8844, 17684, 11,
       375, 0},
      {"ycb_scissors", "ycb_scissors/textured_simple_reoriented.obj",
       "ycb_scissors/texture_map.png", 7860, 15728, 7, 759, 0},
      {"BoomBox", "BoomBox/obj/BoomBox.obj", "BoomBox/glTF/BoomBox_baseColor.png", 3133, 6036, 20,
       402, 194},
      {"WaterBottle", "WaterBottle/obj/WaterBottle.obj",
       "WaterBottle/glTF/WaterBottle_baseColor.png", 2385, 4510, 5, 119, 264},
      {"Lantern", "Lantern/obj/Lantern.obj",
       "Lantern/glTF-pbrSpecularGlossiness/Lantern_diffuse.png", 2737, 5394, 147, 900, 48},
      {"Avocado", "Avocado/obj/Avocado.obj", "Avocado/glTF/Avocado_baseColor.png", 363, 682, 3, 43,
       38},
      {"Suzanne", "Suzanne/obj/Suzanne.obj", "Suzanne/glTF/Suzanne_BaseColor.png", 2012, 3936, 3,
       0, 84},
  };
  return meshes;
}

/// Test-name generator for suites parameterised over sharedMeshes().
inline std::string sharedMeshName(const ::testing::TestParamInfo<SharedMesh>& param) {
  return param.param.name;
}

}  // namespace texgrad::test
