// Meshes and image files from Python: texgrad.Mesh (from arrays or read_mesh), the atlas report
// (`texgrad info --json`'s content) and image reading and writing.
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <algorithm>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "bindings.h"
#include "progress.h"
#include "texgrad/atlas/atlas.h"
#include "texgrad/atlas/atlas_report.h"
#include "texgrad/atlas/atlas_report_json.h"
#include "texgrad/atlas/image_coverage.h"
#include "texgrad/atlas/texel_grid.h"
#include "texgrad/core/error.h"
#include "texgrad/io/image_io.h"
#include "texgrad/io/mesh_reader.h"
#include "texgrad/io/mesh_texture.h"
#include "texgrad/io/texture_page_report.h"
#include "texgrad/io/texture_pages.h"
#include "texgrad/io/uv_tiles.h"

namespace texgrad::python {
namespace {

/// Index triples (m x 3 integers, each in [0, count)) of `name`; `countName` says what they index.
std::vector<Triangle> trianglesFromArray(const py::handle& handle, const std::string& name,
                                         size_t count, const std::string& countName) {
  const py::array raw = py::array::ensure(handle);
  if (!raw) {
    PyErr_Clear();
    throw py::type_error(name + " must be an m x 3 integer array");
  }
  if (raw.dtype().kind() != 'i' && raw.dtype().kind() != 'u')
    throw py::type_error(name + " must hold integers, got dtype " + textOf(raw.dtype()));
  const auto a = py::array_t<int64_t, py::array::forcecast>::ensure(raw);
  if (a.ndim() != 2 || a.shape(1) != 3 || a.shape(0) == 0)
    throw InvalidInputError(name + " must be a non-empty m x 3 array of corner indices, got " +
                            std::to_string(a.ndim()) + "-D shape with " + std::to_string(a.size()) +
                            " entries");
  std::vector<Triangle> triangles(static_cast<size_t>(a.shape(0)));
  const auto view = a.unchecked<2>();
  for (py::ssize_t f = 0; f < a.shape(0); ++f)
    for (py::ssize_t k = 0; k < 3; ++k) {
      const int64_t index = view(f, k);
      if (index < 0 || static_cast<uint64_t>(index) >= count)
        throw InvalidInputError(name + "[" + std::to_string(f) + ", " + std::to_string(k) +
                                "] = " + std::to_string(index) + " is out of range: there are " +
                                std::to_string(count) + " " + countName);
      triangles[static_cast<size_t>(f)][static_cast<size_t>(k)] = static_cast<int32_t>(index);
    }
  return triangles;
}

std::shared_ptr<TexturedMesh> meshFromArrays(const py::handle& vertices, const py::handle& faces,
                                             const py::handle& uvs, const py::handle& uvFaces,
                                             double weldTolerance) {
  if (uvs.is_none())
    throw InvalidInputError(
        "uvs is None: texgrad needs texture coordinates (a mesh without UVs "
        "has no atlas)");
  const Eigen::MatrixXd p = matrixFromArray(vertices, "vertices", 3);
  const Eigen::MatrixXd t = matrixFromArray(uvs, "uvs", 2);
  if (p.rows() == 0) throw InvalidInputError("vertices is empty");
  if (t.rows() == 0) throw InvalidInputError("uvs is empty");
  auto mesh = std::make_shared<TexturedMesh>();
  for (Eigen::Index r = 0; r < p.rows(); ++r) mesh->positions.emplace_back(p.row(r).transpose());
  for (Eigen::Index r = 0; r < t.rows(); ++r) mesh->uvs.emplace_back(t.row(r).transpose());
  mesh->triangles = trianglesFromArray(faces, "faces", mesh->positions.size(), "vertices");
  if (uvFaces.is_none()) {
    if (t.rows() != p.rows())
      throw InvalidInputError("uvs has " + std::to_string(t.rows()) + " rows but vertices has " +
                              std::to_string(p.rows()) +
                              "; per-vertex UVs (uv_faces omitted) need one per vertex");
    mesh->uvTriangles = mesh->triangles;
  } else {
    mesh->uvTriangles = trianglesFromArray(uvFaces, "uv_faces", mesh->uvs.size(), "uvs");
    if (mesh->uvTriangles.size() != mesh->triangles.size())
      throw InvalidInputError("uv_faces has " + std::to_string(mesh->uvTriangles.size()) +
                              " rows but faces has " + std::to_string(mesh->triangles.size()));
  }
  MeshReadOptions options;
  options.weldTolerance = weldTolerance;
  options.validate();
  weldPositions(*mesh, weldTolerance);
  validateMesh(*mesh, "the arrays given to texgrad.Mesh");
  return mesh;
}

py::array_t<double> pointArray(const auto& points, py::ssize_t dims) {
  py::array_t<double> out({static_cast<py::ssize_t>(points.size()), dims});
  auto view = out.mutable_unchecked<2>();
  for (size_t r = 0; r < points.size(); ++r)
    for (py::ssize_t c = 0; c < dims; ++c) view(static_cast<py::ssize_t>(r), c) = points[r][c];
  return out;
}

py::array_t<int32_t> triangleArray(const std::vector<Triangle>& triangles) {
  py::array_t<int32_t> out({static_cast<py::ssize_t>(triangles.size()), py::ssize_t{3}});
  auto view = out.mutable_unchecked<2>();
  for (size_t f = 0; f < triangles.size(); ++f)
    for (size_t k = 0; k < 3; ++k)
      view(static_cast<py::ssize_t>(f), static_cast<py::ssize_t>(k)) = triangles[f][k];
  return out;
}

/// The atlas report as the dict `texgrad info --json` prints (the same JSON, parsed).
py::dict atlasReport(const TexturedMesh& mesh, const py::object& resolution) {
  std::optional<std::pair<int, int>> size;
  if (!resolution.is_none()) {
    if (py::isinstance<py::int_>(resolution)) {
      const int n = resolution.cast<int>();
      size.emplace(n, n);
    } else {
      size = resolution.cast<std::pair<int, int>>();
    }
    if (size->first < 1 || size->second < 1)
      throw InvalidInputError("resolution must be positive, got " + std::to_string(size->first) +
                              " x " + std::to_string(size->second));
  }
  std::string json;
  {
    py::gil_scoped_release release;
    const Atlas atlas = buildAtlas(mesh);
    std::optional<TexelGrid> grid;
    if (size) grid = buildTexelGrid(mesh, atlas, size->first, size->second);
    const std::vector<SlotPages> pages = reportTexturePages(mesh);
    const AtlasReport report =
        analyzeAtlas(mesh, atlas, grid ? &*grid : nullptr, slotLayout(pages, "baseColor"));
    json = atlasReportJson(report, mesh, pages, mesh.sourcePath.string());
  }
  return py::module_::import("json").attr("loads")(json).cast<py::dict>();
}

}  // namespace

void registerMesh(py::module_& m) {
  py::class_<TexturedMesh, std::shared_ptr<TexturedMesh>>(
      m, "Mesh",
      "A triangle mesh with texture coordinates (per-corner UV indices), as texgrad reads it.")
      .def(py::init(&meshFromArrays), py::arg("vertices"), py::arg("faces"), py::arg("uvs"),
           py::arg("uv_faces") = py::none(), py::kw_only(), py::arg("weld_tolerance") = 0.0,
           "Mesh from arrays: vertices (n x 3), faces (m x 3 vertex indices), uvs (k x 2, v "
           "upward), uv_faces (m x 3 indices into uvs; omitted: uvs are per vertex). Vertices "
           "closer than weld_tolerance (model units; 0: identical positions only) are welded, "
           "so that split vertices still join charts by seams.")
      .def_property_readonly(
          "vertices", [](const TexturedMesh& mesh) { return pointArray(mesh.positions, 3); },
          "Welded 3-D vertex positions (n x 3 float64, a copy).")
      .def_property_readonly(
          "faces", [](const TexturedMesh& mesh) { return triangleArray(mesh.triangles); },
          "Vertex indices per face (m x 3 int32, a copy).")
      .def_property_readonly(
          "uvs", [](const TexturedMesh& mesh) { return pointArray(mesh.uvs, 2); },
          "Texture coordinates (k x 2 float64, v upward, a copy).")
      .def_property_readonly(
          "uv_faces", [](const TexturedMesh& mesh) { return triangleArray(mesh.uvTriangles); },
          "UV indices per face corner (m x 3 int32, a copy).")
      .def_property_readonly(
          "path", [](const TexturedMesh& mesh) { return mesh.sourcePath.string(); },
          "File the mesh was read from ('' for a mesh made from arrays).")
      .def_property_readonly(
          "textures",
          [](const TexturedMesh& mesh) {
            py::dict slots;
            for (const TextureRef& t : mesh.textures)
              slots[py::str(t.slot)] = t.path.empty() ? std::string("(embedded)") : t.path.string();
            return slots;
          },
          "Textures the file names, by slot ('baseColor', 'normal', ...): path or '(embedded)'.")
      .def(
          "texture",
          [](const TexturedMesh& mesh, const std::string& slot, const py::object& dtype) {
            std::optional<Image> image;
            {
              py::gil_scoped_release release;
              image = readMeshTexture(mesh, slot);
            }
            if (!image) return py::object(py::none());
            const SampleType type = sampleTypeFrom(dtype, SampleType::Float32);
            return py::object(arrayFromImage(std::move(*image), type, false));
          },
          py::arg("slot") = "baseColor", py::kw_only(), py::arg("dtype") = py::none(),
          "The mesh's texture in `slot` as an H x W x C array (row 0 = top; float32 in [0, 1] by "
          "default, as texgrad reads it), or None if the file names none.")
      .def(
          "wrapped",
          [](const TexturedMesh& mesh, const std::string& wrap, const std::string& slot,
             const std::optional<std::filesystem::path>& texture) {
            const UvWrap mode = parseUvWrap(wrap, mesh, slot);
            WrappedMesh wrapped;
            {
              py::gil_scoped_release release;
              wrapped = meshForPages(mesh, mode, slot, texture.value_or(std::filesystem::path()));
            }
            py::array_t<int32_t> parents(static_cast<py::ssize_t>(wrapped.parentFace.size()));
            std::copy(wrapped.parentFace.begin(), wrapped.parentFace.end(), parents.mutable_data());
            return py::make_tuple(std::make_shared<TexturedMesh>(std::move(wrapped.mesh)), parents);
          },
          py::arg("wrap") = "auto", py::arg("slot") = "baseColor", py::kw_only(),
          py::arg("texture") = py::none(),
          "(mesh, parents): the mesh as a texture that wraps reads it, as the CLI's --wrap: "
          "faces crossing an integer UV line cut there (the sides joined by a seam) and every "
          "unit tile moved into [0, 1]^2 (a UDIM texture's tiles are pages: they stay); wrap "
          "'auto' (the sampler of the texture in `slot`, repeat when none), 'repeat', 'mirror' "
          "or 'clamp' (unchanged); `texture` names the image file(s) instead of the mesh's "
          "('t.<UDIM>.png': tiles, as read_texture_pages). parents[f] is the face "
          "of this mesh that face f is part of: per-face 3-D vectors follow as field[parents].")
      .def("atlas_report", &atlasReport, py::arg("resolution") = py::none(),
           "The atlas diagnostics as the dict `texgrad info --json` prints (texel "
           "statistics too when `resolution` is N or (width, height)).")
      .def_property_readonly("vertex_count",
                             [](const TexturedMesh& mesh) { return mesh.positions.size(); })
      .def_property_readonly("face_count", &TexturedMesh::faceCount)
      .def("__repr__", [](const TexturedMesh& mesh) {
        return "<texgrad.Mesh " + std::to_string(mesh.positions.size()) + " vertices, " +
               std::to_string(mesh.faceCount()) + " faces>";
      });

  m.def(
      "read_mesh",
      [](const std::filesystem::path& path, double weldTolerance, int uvSet,
         const std::string& wrap, const std::string& slot,
         const std::optional<std::filesystem::path>& texture) {
        MeshReadOptions options;
        options.weldTolerance = weldTolerance;
        options.uvSet = uvSet;
        py::gil_scoped_release release;
        TexturedMesh mesh = readMesh(path, options);
        const UvWrap mode = parseUvWrap(wrap, mesh, slot);
        return std::make_shared<TexturedMesh>(
            meshForPages(std::move(mesh), mode, slot, texture.value_or(std::filesystem::path()))
                .mesh);
      },
      py::arg("path"), py::kw_only(), py::arg("weld_tolerance") = 0.0, py::arg("uv_set") = 0,
      py::arg("wrap") = "auto", py::arg("slot") = "baseColor", py::arg("texture") = py::none(),
      "Reads a mesh file the CLI reads (.obj with its .mtl, .ply, .gltf, .glb), welding "
      "positions closer than weld_tolerance (model units) so seams are found (uv_set picks glTF's "
      "TEXCOORD_N; OBJ and PLY have only 0), and wraps its UVs (not a UDIM texture's) "
      "as the CLI's --wrap does for the texture in `slot` (Mesh.wrapped): wrap 'auto' (the "
      "file's sampler, repeat when it names none), 'repeat', 'mirror' or 'clamp' (the file's "
      "UVs and faces as they are; per-face data of the file then match the faces). `texture` "
      "names the image file(s) the CLI's TEXTURE argument would ('t.<UDIM>.png': UDIM tiles, "
      "whose faces are cut at the tile borders and stay in their tiles).");

  m.def(
      "read_image",
      [](const std::filesystem::path& path, const py::object& dtype) {
        Image image;
        {
          py::gil_scoped_release release;
          image = readImage(path);
        }
        const SampleType type = sampleTypeFrom(dtype, sampleTypeOf(image.format));
        return arrayFromImage(std::move(image), type, false);
      },
      py::arg("path"), py::kw_only(), py::arg("dtype") = py::none(),
      "Reads an image file (PNG, JPEG, EXR, TIFF) as H x W x C (row 0 = top). dtype None keeps "
      "the file's type (uint8, uint16, float32 for half and float); float32 gives the values "
      "the CLI works on (integers normalised to [0, 1]).");

  m.def(
      "write_image",
      [](const std::filesystem::path& path, const py::handle& image,
         const std::optional<std::string>& bitDepth) {
        ImageArgument argument = imageFromArray(image, "image");
        const PixelFormat format =
            bitDepth ? parsePixelFormat(*bitDepth) : formatOf(argument.sampleType);
        py::gil_scoped_release release;
        checkImageOutput(path, bitDepth ? std::optional<PixelFormat>(format) : std::nullopt);
        writeImage(path, argument.image, format);
      },
      py::arg("path"), py::arg("image"), py::kw_only(), py::arg("bit_depth") = py::none(),
      "Writes an H x W x C image (row 0 = top) atomically; bit_depth '8', '16', 'half' or "
      "'float' (default: the array's dtype, float for float arrays).");
}

}  // namespace texgrad::python
