// Writes a synthetic photo capture of a mesh for scripts/bench-photo.sh: N views around it
// (tests/support/photo_scene.h: per-view gain, colour cast, shading, every other view with radial
// distortion), rendered by the test support's ray caster, as JPEGs plus a COLMAP text model.
//
//   photo_capture MESH TEXTURE OUT_DIR [VIEWS=10] [WIDTH=4000] [HEIGHT=3000]
#include <cstdio>
#include <cstdlib>
#include <string>

#include "photo_renderer.h"
#include "photo_scene.h"
#include "texgrad/core/error.h"
#include "texgrad/io/camera_writer.h"
#include "texgrad/io/image_io.h"
#include "texgrad/io/mesh_reader.h"

int main(int argc, char** argv) {
  if (argc < 4) {
    std::fprintf(stderr, "usage: %s MESH TEXTURE OUT_DIR [VIEWS] [WIDTH] [HEIGHT]\n", argv[0]);
    return 2;
  }
  const int views = argc > 4 ? std::atoi(argv[4]) : 10;
  const int width = argc > 5 ? std::atoi(argv[5]) : 4000;
  const int height = argc > 6 ? std::atoi(argv[6]) : 3000;
  try {
    const texgrad::TexturedMesh mesh = texgrad::readMesh(argv[1]);
    const texgrad::Image texture = texgrad::readImage(argv[2]);
    const std::filesystem::path out = argv[3];
    std::filesystem::create_directories(out / "images");
    const texgrad::test::Capture capture = texgrad::test::captureAround(mesh, views, width, height);
    for (size_t k = 0; k < capture.cameras.size(); ++k) {
      texgrad::Image photo =
          texgrad::test::renderPhoto(mesh, texture, capture.cameras[k], capture.looks[k]);
      photo.format = texgrad::PixelFormat::UInt8;
      texgrad::Camera camera = capture.cameras[k];
      camera.name = "view" + std::to_string(k) + ".jpg";
      texgrad::writeImage(out / "images" / camera.name, photo);
      std::fprintf(stderr, "rendered %s (%dx%d)\n", camera.name.c_str(), width, height);
    }
    std::vector<texgrad::Camera> cameras = capture.cameras;
    for (size_t k = 0; k < cameras.size(); ++k)
      cameras[k].name = "view" + std::to_string(k) + ".jpg";
    texgrad::writeColmapText(out / "sparse", cameras);
  } catch (const texgrad::Error& e) {
    std::fprintf(stderr, "photo_capture: %s\n", e.what());
    return 1;
  }
  return 0;
}
