// texgrad.TexelDomain: a mesh's atlas, texel grid and operators at one resolution, with the grid
// as arrays, gather/scatter between images and unknowns, and the operators as CSR matrices.
#include <pybind11/stl.h>

#include <string>

#include "bindings.h"
#include "progress.h"
#include "texgrad/apps/texel_signal.h"
#include "texgrad/core/error.h"

namespace texgrad::python {
namespace {

OperatorOptions operatorOptions(const std::string& basis, double seamWeight,
                                bool keepPieceIntegrals) {
  OperatorOptions options;
  if (basis == "bilinear")
    options.basis = fem::BasisKind::Bilinear;
  else if (basis != "continuous")
    throw InvalidInputError("basis must be 'continuous' or 'bilinear', got '" + basis + "'");
  options.seamContinuityWeight = seamWeight;
  options.keepPieceIntegrals = keepPieceIntegrals;
  options.validate();
  return options;
}

std::shared_ptr<TexelDomain> buildDomain(const TexturedMesh& mesh, int width, int height,
                                         const OperatorOptions& options,
                                         const py::object& progress) {
  if (width < 1 || height < 1)
    throw InvalidInputError("width and height must be positive, got " + std::to_string(width) +
                            " x " + std::to_string(height));
  return withProgress(progress, [&](const ProgressCallback& callback) {
    return std::make_shared<TexelDomain>(mesh, width, height, options, callback);
  });
}

/// A per-texel grid array over the image (H x W, row 0 = top) of valueOf(t) at each grid texel t.
template <typename T, typename ValueOf>
py::array_t<T> imageGridArray(const TexelGrid& grid, const ValueOf& valueOf, T outside) {
  py::array_t<T> out(
      {static_cast<py::ssize_t>(grid.imageHeight), static_cast<py::ssize_t>(grid.imageWidth)});
  auto view = out.template mutable_unchecked<2>();
  for (int j = 0; j < grid.imageHeight; ++j)
    for (int i = 0; i < grid.imageWidth; ++i) {
      const int x = i - grid.x0, y = j - grid.y0;
      const bool inGrid = x >= 0 && y >= 0 && x < grid.nx && y < grid.ny;
      view(grid.imageHeight - 1 - j, i) =
          inGrid ? static_cast<T>(valueOf(static_cast<size_t>(grid.texelIndex(x, y)))) : outside;
    }
  return out;
}

/// Per unknown: (row, column) of its texel in the H x W image (row 0 = top); may lie outside
/// the image for texels past its border.
py::array_t<int64_t> unknownPixels(const TexelGrid& grid) {
  py::array_t<int64_t> out({static_cast<py::ssize_t>(grid.unknownCount()), py::ssize_t{2}});
  auto view = out.mutable_unchecked<2>();
  for (int u = 0; u < grid.unknownCount(); ++u) {
    const int texel = grid.texelOfUnknown[static_cast<size_t>(u)];
    const int i = texel % grid.nx + grid.x0, j = texel / grid.nx + grid.y0;
    view(u, 0) = grid.imageHeight - 1 - j;
    view(u, 1) = i;
  }
  return out;
}

void requireSize(const TexelDomain& domain, const Image& image, const std::string& name) {
  const TexelGrid& grid = domain.grid();
  if (image.width != grid.imageWidth || image.height != grid.imageHeight)
    throw InvalidInputError(name + " is " + std::to_string(image.height) + " x " +
                            std::to_string(image.width) + " (H x W) but the domain is " +
                            std::to_string(grid.imageHeight) + " x " +
                            std::to_string(grid.imageWidth));
}

/// Writes `source` back into the numpy array `target` (same shape), quantising as files do.
void copyInto(const py::handle& target, const Image& source, SampleType type) {
  const py::array converted = arrayFromImage(Image(source), type, false);
  py::module_::import("numpy").attr("copyto")(
      target, converted.attr("reshape")(py::reinterpret_borrow<py::array>(target).attr("shape")));
}

}  // namespace

std::shared_ptr<TexelDomain> domainFor(const py::handle& target, int width, int height,
                                       const OperatorOptions& options, const py::object& progress) {
  if (py::isinstance<TexelDomain>(target)) {
    auto domain = target.cast<std::shared_ptr<TexelDomain>>();
    if (domain->grid().imageWidth != width || domain->grid().imageHeight != height)
      throw InvalidInputError("the TexelDomain is " + std::to_string(domain->grid().imageWidth) +
                              " x " + std::to_string(domain->grid().imageHeight) +
                              " (W x H) but the image is " + std::to_string(width) + " x " +
                              std::to_string(height));
    return domain;
  }
  if (!py::isinstance<TexturedMesh>(target))
    throw py::type_error("mesh must be a texgrad.Mesh or a texgrad.TexelDomain, got " +
                         textOf(py::type::of(target)));
  return buildDomain(target.cast<const TexturedMesh&>(), width, height, options, progress);
}

void registerDomain(py::module_& m) {
  py::class_<TexelDomain, std::shared_ptr<TexelDomain>>(
      m, "TexelDomain",
      "A mesh's atlas, texel grid and operators at one texture resolution (built once, shared "
      "by the apps). Unknowns are the active texels, numbered in row-major texel order from the "
      "bottom row (texgrad's texel order).")
      .def(py::init([](const TexturedMesh& mesh, int width, int height, const std::string& basis,
                       double seamWeight, bool keepPieceIntegrals, const py::object& progress) {
             return buildDomain(mesh, width, height,
                                operatorOptions(basis, seamWeight, keepPieceIntegrals), progress);
           }),
           py::arg("mesh"), py::arg("width"), py::arg("height"), py::kw_only(),
           py::arg("basis") = "continuous", py::arg("seam_weight") = 0.0,
           py::arg("keep_piece_integrals") = true, py::arg("progress") = py::none(),
           "Builds atlas, texel grid (width x height) and operators. basis 'continuous' (the "
           "paper's seam-continuous basis) or 'bilinear' (with seam_weight, paper Sec. 4.2); "
           "keep_piece_integrals=False frees memory when no beta map or metric change follows.")
      .def_property_readonly("width", [](const TexelDomain& d) { return d.grid().imageWidth; })
      .def_property_readonly("height", [](const TexelDomain& d) { return d.grid().imageHeight; })
      .def_property_readonly("unknowns", &TexelDomain::unknowns,
                             "Number of unknowns (active texels), n.")
      .def_property_readonly(
          "mesh", [](const TexelDomain& d) { return std::make_shared<TexturedMesh>(d.mesh()); },
          "A copy of the domain's mesh.")
      .def_property_readonly(
          "texel_class",
          [](const TexelDomain& d) {
            const TexelGrid& g = d.grid();
            return imageGridArray<uint8_t>(g, [&g](size_t t) { return g.texelClass[t]; }, 0);
          },
          "H x W uint8 (row 0 = top): 0 inactive, 1 interior, 2 boundary texel.")
      .def_property_readonly(
          "texel_chart",
          [](const TexelDomain& d) {
            const TexelGrid& g = d.grid();
            return imageGridArray<int32_t>(g, [&g](size_t t) { return g.chartOfTexel(t); }, -1);
          },
          "H x W int32: chart owning each texel, -1 if inactive.")
      .def_property_readonly(
          "unknown_index",
          [](const TexelDomain& d) {
            const TexelGrid& g = d.grid();
            return imageGridArray<int32_t>(g, [&g](size_t t) { return g.unknownOfTexel[t]; }, -1);
          },
          "H x W int32: unknown index of each texel, -1 if inactive.")
      .def_property_readonly(
          "unknown_pixels", [](const TexelDomain& d) { return unknownPixels(d.grid()); },
          "n x 2 int64: (row, column) of each unknown's texel (row 0 = top); active texels "
          "past the image border have coordinates outside it.")
      .def_property_readonly(
          "charts", [](const TexelDomain& d) { return d.atlas().charts.size(); },
          "Number of charts.")
      .def_property_readonly(
          "chart_of_face", [](const TexelDomain& d) { return d.atlas().chartOfFace; },
          "Chart index of each face.")
      .def_property_readonly(
          "surface_area",
          [](const TexelDomain& d) { return d.operators().report().metric.surfaceArea; },
          "3-D area of the part of the mesh inside the atlas (model units squared); the "
          "operators are built for the surface scaled to unit area.")
      .def(
          "gather",
          [](const TexelDomain& d, const py::handle& image) {
            const ImageArgument argument = imageFromArray(image, "image");
            requireSize(d, argument.image, "image");
            return arrayFromMatrix(gatherTexels(d.grid(), argument.image));
          },
          py::arg("image"),
          "Values of an H x W x C image at the unknowns (n x C float64; integer images "
          "normalised to [0, 1]); texels past the border take the nearest image texel.")
      .def(
          "scatter",
          [](const TexelDomain& d, const py::handle& values, const py::handle& image) {
            if (!py::isinstance<py::array>(image))
              throw py::type_error("image must be a numpy array (it is written in place)");
            const auto target = py::reinterpret_borrow<py::array>(image);
            if (!target.writeable())
              throw InvalidInputError("image is read-only; scatter writes into it");
            ImageArgument argument = imageFromArray(image, "image");
            requireSize(d, argument.image, "image");
            const Eigen::MatrixXd v = matrixFromArray(values, "values", argument.image.channels);
            if (v.rows() != d.unknowns())
              throw InvalidInputError("values has " + std::to_string(v.rows()) +
                                      " rows; the domain has " + std::to_string(d.unknowns()) +
                                      " unknowns");
            scatterTexels(d.grid(), v, argument.image);
            copyInto(image, argument.image, argument.sampleType);
            return image;
          },
          py::arg("values"), py::arg("image"),
          "Writes n x C values into the active texels of `image` (in place; integer images are "
          "quantised as image files are) and returns it; other texels are left as they are.")
      .def("_mass", [](const TexelDomain& d) { return csrTuple(d.operators().mass()); })
      .def("_stiffness",
           [](const TexelDomain& d) {
             return csrTuple(Eigen::SparseMatrix<double>(d.operators().stiffness()));
           })
      .def("_differential",
           [](const TexelDomain& d) { return csrTuple(d.operators().differential()); })
      .def("_hodge_star1",
           [](const TexelDomain& d) {
             py::gil_scoped_release release;
             Eigen::SparseMatrix<double> star = d.operators().hodgeStar1();
             py::gil_scoped_acquire acquire;
             return csrTuple(star);
           })
      .def("__repr__", [](const TexelDomain& d) {
        return "<texgrad.TexelDomain " + std::to_string(d.grid().imageWidth) + "x" +
               std::to_string(d.grid().imageHeight) + ", " + std::to_string(d.unknowns()) +
               " unknowns, " + std::to_string(d.atlas().charts.size()) + " charts>";
      });
}

}  // namespace texgrad::python
