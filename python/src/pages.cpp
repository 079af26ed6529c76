// Texture pages from Python (docs/python.md, Texture pages): a texture spread over several images
// (UDIM tiles, one image per material) read as one layout image with the mesh placed on it, cut
// back into its pages, and written one image per page (or into a glTF copy) with the CLI's names.
// The layout logic and the choice between one image and several pages are the io module's
// (texture_pages.h, mesh_texture_pages.h); this file converts arguments and results.
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "bindings.h"
#include "texgrad/core/error.h"
#include "texgrad/io/image_io.h"
#include "texgrad/io/mesh_texture_pages.h"
#include "texgrad/io/texture_pages.h"

namespace texgrad::python {
namespace {

/// texgrad.PageLayout: the arranged pages and the mesh placed on them (a glTF output needs the
/// mesh's source asset and images).
struct PagesHandle {
  PageLayout layout;
  std::shared_ptr<TexturedMesh> mesh;  ///< UVs in the layout's UV space
};

/// `pages` as a handle: the placed mesh, or `mesh` itself on one page.
std::shared_ptr<PagesHandle> pagesHandle(const std::shared_ptr<TexturedMesh>& mesh,
                                         MeshPages pages) {
  auto handle = std::make_shared<PagesHandle>();
  handle->layout = std::move(pages.layout);
  handle->mesh = pages.placed ? std::make_shared<TexturedMesh>(std::move(*pages.placed)) : mesh;
  return handle;
}

py::tuple readPages(const std::shared_ptr<TexturedMesh>& mesh, const std::string& slot,
                    const std::optional<std::filesystem::path>& texture, const py::object& dtype) {
  std::shared_ptr<PagesHandle> pages;
  Image image;
  {
    py::gil_scoped_release release;
    MeshTexturePages read = readMeshTexturePages(
        *mesh, slot, texture.value_or(std::filesystem::path()), [&]() -> Image {
          throw InvalidInputError(
              (mesh->sourcePath.empty() ? std::string("the mesh") : mesh->sourcePath.string()) +
              " references no " + slot + " texture; pass the image file as texture=");
        });
    image = std::move(read.image);
    pages = pagesHandle(mesh, std::move(read));
  }
  const SampleType type = sampleTypeFrom(dtype, sampleTypeOf(image.format));
  py::array array = arrayFromImage(std::move(image), type, false);
  return py::make_tuple(pages->mesh, array, pages);
}

py::tuple placePages(const std::shared_ptr<TexturedMesh>& mesh, const py::object& resolution,
                     const std::string& slot, const std::optional<std::filesystem::path>& texture) {
  std::optional<std::pair<int, int>> size;
  if (!resolution.is_none()) size = resolutionFrom(resolution);
  std::shared_ptr<PagesHandle> pages;
  {
    py::gil_scoped_release release;
    pages = pagesHandle(
        mesh, placeMeshOnPages(*mesh, slot, texture.value_or(std::filesystem::path()), size));
  }
  return py::make_tuple(pages->mesh, pages);
}

/// The layout image argument, checked against the layout's size.
ImageArgument layoutImage(const PagesHandle& pages, const py::handle& image) {
  ImageArgument argument = imageFromArray(image, "image");
  const PageLayout& layout = pages.layout;
  if (argument.image.width != layout.width || argument.image.height != layout.height)
    throw InvalidInputError("image is " + std::to_string(argument.image.height) + " x " +
                            std::to_string(argument.image.width) + " (H x W) but the layout is " +
                            std::to_string(layout.height) + " x " + std::to_string(layout.width));
  return argument;
}

py::dict splitImage(const PagesHandle& pages, const py::handle& image, const py::object& dtype) {
  const ImageArgument argument = layoutImage(pages, image);
  const SampleType type = sampleTypeFrom(dtype, argument.sampleType);
  py::dict out;
  for (size_t p = 0; p < pages.layout.pages.size(); ++p)
    out[py::str(pages.layout.pages[p].name)] =
        arrayFromImage(pageImage(pages.layout, argument.image, p), type, argument.planar);
  return out;
}

py::list pageDicts(const PageLayout& layout) {
  py::list out;
  for (const TexturePage& page : layout.pages) {
    py::dict d;
    d["name"] = page.name;
    d["file"] = page.path.string();
    d["width"] = page.width;
    d["height"] = page.height;
    d["offset"] = page.offset;
    d["tile"] = py::make_tuple(page.tileU, page.tileV);
    d["faces"] = page.faces;
    out.append(d);
  }
  return out;
}

std::vector<std::string> outputPaths(const PagesHandle& pages, const std::filesystem::path& out) {
  std::vector<std::string> paths;
  for (size_t p = 0; p < pages.layout.pages.size(); ++p)
    paths.push_back(pageOutputPath(out, pages.layout, p).string());
  return paths;
}

/// Writes every page of `image` where the CLI's --out `out` puts it; returns the files written.
std::vector<std::string> writePages(const std::filesystem::path& out, const PagesHandle& pages,
                                    const py::handle& image,
                                    const std::optional<std::string>& bitDepth) {
  const ImageArgument argument = layoutImage(pages, image);  // its format: the array's dtype
  const std::optional<PixelFormat> requested =
      bitDepth ? std::optional<PixelFormat>(parsePixelFormat(*bitDepth)) : std::nullopt;
  WrittenTexturePages result;
  {
    py::gil_scoped_release release;
    result = writeMeshTexturePages(out, *pages.mesh, pages.layout, argument.image, requested);
  }
  for (const std::string& warning : result.warnings)
    if (PyErr_WarnEx(PyExc_UserWarning, warning.c_str(), 1) != 0) throw py::error_already_set();
  std::vector<std::string> written;
  for (const std::filesystem::path& file : result.files) written.push_back(file.string());
  return written;
}

}  // namespace

void registerPages(py::module_& m) {
  py::class_<PagesHandle, std::shared_ptr<PagesHandle>>(
      m, "PageLayout",
      "The pages of a texture (UDIM tiles, or one image per material) placed side by side in one "
      "texel lattice, the layout image (docs/architecture.md, Texture pages).")
      .def_property_readonly(
          "pages", [](const PagesHandle& p) { return pageDicts(p.layout); },
          "One dict per page, left to right: name (UDIM tile number or material / image name), "
          "file ('' if embedded), width, height, offset (first texel column in the layout), tile "
          "(k, l) and faces (how many lie on it).")
      .def_property_readonly(
          "udim", [](const PagesHandle& p) { return p.layout.udim; },
          "True if the pages are UDIM tiles.")
      .def_property_readonly(
          "slot", [](const PagesHandle& p) { return p.layout.slot; },
          "Texture slot the pages come from ('baseColor', ...).")
      .def_property_readonly(
          "width", [](const PagesHandle& p) { return p.layout.width; }, "Layout width in texels.")
      .def_property_readonly(
          "height", [](const PagesHandle& p) { return p.layout.height; },
          "Layout height in texels.")
      .def_property_readonly(
          "mesh", [](const PagesHandle& p) { return p.mesh; },
          "The mesh placed on the layout (UVs in the layout's UV space).")
      .def("split", &splitImage, py::arg("image"), py::kw_only(), py::arg("dtype") = py::none(),
           "The layout image (H x W [x C], the layout's size) cut into its pages: a dict page "
           "name -> array, in page order, of the input's dtype unless `dtype` says otherwise.")
      .def("output_paths", &outputPaths, py::arg("out"),
           "The file each page of an image output named `out` goes to, as the CLI names them: a "
           "UDIM token (<UDIM>, %04d) replaced by the tile, else the page name before the "
           "extension (out.wood.png); one page writes `out` itself.")
      .def("__len__", [](const PagesHandle& p) { return p.layout.pages.size(); })
      .def("__repr__", [](const PagesHandle& p) {
        return "<texgrad.PageLayout " + std::to_string(p.layout.pages.size()) +
               (p.layout.udim ? " UDIM tiles" : " pages") + ", " + std::to_string(p.layout.width) +
               " x " + std::to_string(p.layout.height) + ">";
      });

  m.def("_read_texture_pages", &readPages, py::arg("mesh"), py::arg("slot"), py::arg("texture"),
        py::arg("dtype"),
        "(placed mesh, layout image, PageLayout); texgrad.read_texture_pages wraps it.");

  m.def("place_on_pages", &placePages, py::arg("mesh"), py::arg("resolution") = py::none(),
        py::kw_only(), py::arg("slot") = "baseColor", py::arg("texture") = py::none(),
        "(placed mesh, PageLayout) without reading the images: the pages of the `slot` texture "
        "(or of `texture`) each `resolution` (N or (width, height)) for a texture an app makes "
        "(geodesic, lic, react, mask: pass resolution=(layout.width, layout.height) to it), or "
        "the sizes of the page images (headers only) when resolution is None. The CLI's "
        "geodesic, lic and react place a mesh so.");

  m.def("write_texture_pages", &writePages, py::arg("out"), py::arg("layout"), py::arg("image"),
        py::kw_only(), py::arg("bit_depth") = py::none(),
        "Writes the layout image `image` one image per page, named as the CLI's --out `out` "
        "names them (PageLayout.output_paths; all checked before the first is written), or, for "
        "a .gltf/.glb `out`, a copy of the mesh's glTF asset with each page's image replaced "
        "(UDIM tiles cannot be: UnsupportedError). bit_depth '8', '16', 'half' or 'float' "
        "(default: the array's dtype). Returns the files written; a source image the glTF copy "
        "leaves out is a UserWarning.");
}

}  // namespace texgrad::python
