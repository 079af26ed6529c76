// Wavefront OBJ + MTL writer for TexturedMesh (used by `texgrad sample` and tests).
#include "texgrad/io/mesh_writer.h"

#include <fstream>
#include <functional>
#include <iomanip>

#include "texgrad/core/error.h"
#include "texgrad/io/atomic_file.h"

namespace texgrad {
namespace {

void writeObjBody(std::ostream& out, const TexturedMesh& mesh, const std::string& mtlName) {
  out << "# written by texgrad\n" << std::setprecision(17);
  if (!mtlName.empty()) out << "mtllib " << mtlName << "\nusemtl texture\n";
  for (const auto& p : mesh.positions) out << "v " << p.x() << " " << p.y() << " " << p.z() << "\n";
  for (const auto& t : mesh.uvs) out << "vt " << t.x() << " " << t.y() << "\n";
  for (size_t f = 0; f < mesh.triangles.size(); ++f) {
    out << "f";
    for (int k = 0; k < 3; ++k)
      out << " " << mesh.triangles[f][static_cast<size_t>(k)] + 1 << "/"
          << mesh.uvTriangles[f][static_cast<size_t>(k)] + 1;
    out << "\n";
  }
}

void writeText(const std::filesystem::path& path, const std::function<void(std::ostream&)>& body) {
  writeAtomically(path, [&](const std::filesystem::path& temporary) {
    std::ofstream out(temporary);
    if (!out) throw IoError("cannot write " + path.string() + "; check the folder exists");
    body(out);
    out.flush();
    if (!out) throw IoError("writing " + path.string() + " failed (disk full?)");
  });
}

}  // namespace

void writeObj(const std::filesystem::path& path, const TexturedMesh& mesh,
              const std::filesystem::path& texture) {
  std::string mtlName;
  if (!texture.empty()) {
    const std::filesystem::path mtlPath = std::filesystem::path(path).replace_extension(".mtl");
    mtlName = mtlPath.filename().string();
    writeText(mtlPath, [&](std::ostream& out) {
      out << "# written by texgrad\nnewmtl texture\nKd 1 1 1\nmap_Kd " << texture.string()
          << "\n";
    });
  }
  writeText(path, [&](std::ostream& out) { writeObjBody(out, mesh, mtlName); });
}

}  // namespace texgrad
