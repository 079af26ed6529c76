// Shared helpers of the Python module: numpy <-> Image and index conversions, solver keyword
// arguments, and the registration function of each part of the module.
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <memory>
#include <string>
#include <utility>

#include "texgrad/apps/geodesic_source.h"
#include "texgrad/apps/system_solver.h"
#include "texgrad/apps/texel_domain.h"
#include "texgrad/io/image.h"
#include "texgrad/io/textured_mesh.h"

namespace texgrad::python {

namespace py = pybind11;

/// Sample type of a numpy image; the output of an app has the input's unless asked otherwise.
enum class SampleType { UInt8, UInt16, Float32, Float64 };

/// An image argument converted to texel order, with what is needed to convert the result back.
struct ImageArgument {
  Image image;
  SampleType sampleType = SampleType::Float32;
  bool planar = false;  ///< given as H x W (one channel, no channel axis)
};

/// Converts a numpy image (H x W or H x W x C with C in 1..4; uint8, uint16, float32 or float64;
/// any strides; row 0 = top of the picture, as image files and matplotlib) into an Image in texel
/// order (row 0 = bottom). Integer samples are normalised to [0, 1]. Throws InvalidInputError
/// naming `name` for a wrong shape, an empty or non-finite image, or TypeError for a wrong dtype.
ImageArgument imageFromArray(const py::handle& array, const std::string& name);

/// The image as a new numpy array (H x W x C, or H x W if `planar`) of `type`; integer types are
/// quantised as image files are (round(clamp(v, 0, 1) * max), NaN as 0). `image` is freed on
/// return, so a caller that moved its only copy in holds one image less while the array lives.
py::array arrayFromImage(Image&& image, SampleType type, bool planar);

/// str(object) of a Python object, for messages.
inline std::string textOf(py::handle object) {
  return py::str(object).cast<std::string>();
}

/// The sample type named by an app's `dtype=` keyword (None: `fallback`).
SampleType sampleTypeFrom(const py::object& dtype, SampleType fallback);

/// Pixel format an image of `type` is written in by default (float for float64 too).
PixelFormat formatOf(SampleType type);
/// Sample type a file's pixel format is returned as (float32 for half and float).
SampleType sampleTypeOf(PixelFormat format);

/// (width, height) from N or (width, height); TypeError or InvalidInputError otherwise.
std::pair<int, int> resolutionFrom(const py::handle& resolution);

/// A float64 matrix (rows x cols; cols < 0: any) from an array-like; throws InvalidInputError
/// naming `name` on a wrong shape or a non-finite value.
Eigen::MatrixXd matrixFromArray(const py::handle& array, const std::string& name,
                                Eigen::Index cols);
/// A (rows x cols) float64 numpy array copied from `m`.
py::array_t<double> arrayFromMatrix(const Eigen::MatrixXd& m);

/// A sparse matrix as (data, indices, indptr, shape) of its CSR form.
py::tuple csrTuple(const Eigen::SparseMatrix<double>& m);

/// Applies the solver keywords that are not None (solver, precision, cycles, max_iterations,
/// tolerance, levels, sweeps, line_ratio, weak_row_reach, threads: the CLI's solver flags) to
/// `settings` and validates them.
void applySolverKeywords(const py::dict& keywords, SolverSettings& settings);

/// The mesh object of the module: shared so a TexelDomain can keep the mesh it was built from.
using MeshHandle = std::shared_ptr<const TexturedMesh>;

/// The domain an app runs on: `target` if it is a TexelDomain (checked against width x height),
/// else a new one built from the Mesh `target` with `options` (GIL released while building).
std::shared_ptr<TexelDomain> domainFor(const py::handle& target, int width, int height,
                                       const OperatorOptions& options, const py::object& progress);

/// Geodesic sources from the keyword lists source_vertices, source_uvs, source_points; vertex
/// indices are checked against `vertexCount`.
std::vector<GeodesicSource> geodesicSourcesFrom(const py::object& vertices, const py::object& uvs,
                                                const py::object& points, size_t vertexCount);

void registerErrors(py::module_& m);
void registerMesh(py::module_& m);
void registerDomain(py::module_& m);
void registerApps(py::module_& m);
void registerPages(py::module_& m);
void registerInteractive(py::module_& m);

}  // namespace texgrad::python
