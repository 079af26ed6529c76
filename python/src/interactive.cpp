// The stateful solvers for interactive use: InteractiveFilter (new parameters, then steps) and
// GeodesicSolver (new sources, then updates); each keeps its TexelDomain alive.
#include <pybind11/stl.h>

#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "bindings.h"
#include "progress.h"
#include "texgrad/apps/dilate.h"
#include "texgrad/apps/filter.h"
#include "texgrad/apps/geodesic.h"
#include "texgrad/apps/texel_signal.h"
#include "texgrad/core/error.h"

namespace texgrad::python {

namespace {

py::dict reportDict(const SolveReport& report) {
  py::dict d;
  d["iterations"] = report.iterations;
  d["converged"] = report.converged;
  d["residuals"] = report.residuals;
  d["rms_change"] = report.rmsChange;
  return d;
}

std::shared_ptr<TexelDomain> requireDomain(const py::handle& domain) {
  if (!py::isinstance<TexelDomain>(domain))
    throw py::type_error("domain must be a texgrad.TexelDomain");
  return domain.cast<std::shared_ptr<TexelDomain>>();
}

/// InteractiveFilter with the domain it refers to and the input's array layout.
struct PyInteractiveFilter {
  /// Held by every method while it uses the solver, taken after releasing the GIL (so a holder
  /// never waits for the GIL): calls from several Python threads take turns instead of racing.
  std::mutex busy;
  std::shared_ptr<TexelDomain> domain;
  std::unique_ptr<InteractiveFilter> filter;
  SampleType sampleType = SampleType::Float32;
  bool planar = false;
};

std::vector<double> betaCells(const TexelDomain& domain, const py::object& betaMap,
                              std::pair<double, double> range) {
  if (betaMap.is_none()) return {};
  const Image map = imageFromArray(betaMap, "beta_map").image;
  return cellValuesFromMap(domain.grid(), map, range.first, range.second);
}

std::unique_ptr<PyInteractiveFilter> makeFilter(const py::handle& domainObject,
                                                const py::handle& texture, double alpha,
                                                double beta, const py::object& betaMap,
                                                std::pair<double, double> betaRange, bool normalMap,
                                                const py::object& progress,
                                                const py::kwargs& solver) {
  auto result = std::make_unique<PyInteractiveFilter>();
  result->domain = requireDomain(domainObject);
  FilterOptions options;
  options.alpha = alpha;
  options.beta = beta;
  options.normalMap = normalMap;
  applySolverKeywords(solver, options.solver);
  ImageArgument input = imageFromArray(texture, "image");
  if (input.image.width != result->domain->grid().imageWidth ||
      input.image.height != result->domain->grid().imageHeight)
    throw InvalidInputError("image is not the domain's size");
  options.betaPerCell = betaCells(*result->domain, betaMap, betaRange);
  options.validate();
  result->sampleType = input.sampleType;
  result->planar = input.planar;
  result->filter = withProgress(progress, [&](const ProgressCallback& callback) {
    return std::make_unique<InteractiveFilter>(*result->domain, input.image, options, callback);
  });
  return result;
}

/// GeodesicSolver with the domain it refers to.
struct PyGeodesicSolver {
  std::mutex busy;  ///< as PyInteractiveFilter::busy
  std::shared_ptr<TexelDomain> domain;
  std::unique_ptr<GeodesicSolver> solver;
};

std::unique_ptr<PyGeodesicSolver> makeGeodesic(const py::handle& domainObject, double alpha,
                                               const std::string& offset,
                                               const std::string& boundary, bool interactive,
                                               const py::object& progress,
                                               const py::kwargs& solver) {
  auto result = std::make_unique<PyGeodesicSolver>();
  result->domain = requireDomain(domainObject);
  GeodesicOptions options = interactive ? GeodesicOptions::interactive() : GeodesicOptions();
  options.alpha = alpha;
  options.offset = parseGeodesicOffset(offset);
  options.boundary = parseGeodesicBoundary(boundary);
  applySolverKeywords(solver, options.solver);
  options.validate();
  result->solver = withProgress(progress, [&](const ProgressCallback& callback) {
    return std::make_unique<GeodesicSolver>(*result->domain, options, callback);
  });
  return result;
}

}  // namespace

void registerInteractive(py::module_& m) {
  using py::arg;
  py::class_<PyInteractiveFilter>(
      m, "InteractiveFilter",
      "The filter as a stateful solver (a notebook slider, a brush): set_parameters redoes only "
      "the numeric update, step() one V-cycle (or an exact solve with solver='direct').")
      .def(py::init(&makeFilter), arg("domain"), arg("image"), py::kw_only(), arg("alpha") = 1e4,
           arg("beta") = 1.0, arg("beta_map") = py::none(), arg("beta_range") = std::pair(0.0, 2.0),
           arg("normal_map") = false, arg("progress") = py::none(),
           "Sets up the solver for `image` (H x W x C, the domain's size) on a TexelDomain built "
           "with keep_piece_integrals=True if beta maps will be used. Solver keywords as "
           "texgrad.filter's.")
      .def(
          "set_parameters",
          [](PyInteractiveFilter& self, double alpha, double beta, const py::object& betaMap,
             std::pair<double, double> betaRange) {
            std::vector<double> cells = betaCells(*self.domain, betaMap, betaRange);
            py::gil_scoped_release release;
            const std::lock_guard lock(self.busy);
            self.filter->setParameters(alpha, beta, std::move(cells));
          },
          arg("alpha"), arg("beta"), arg("beta_map") = py::none(),
          arg("beta_range") = std::pair(0.0, 2.0),
          "New alpha, beta and optional beta map (replaces beta): numeric update only.")
      .def(
          "step",
          [](PyInteractiveFilter& self, const py::object& progress) {
            const SolveReport report =
                withProgress(progress, [&](const ProgressCallback& callback) {
                  const std::lock_guard lock(self.busy);
                  return self.filter->step(callback);
                });
            return reportDict(report);
          },
          py::kw_only(), arg("progress") = py::none(),
          "One V-cycle (or an exact solve) towards the current target; returns its report.")
      .def(
          "solve",
          [](PyInteractiveFilter& self, const py::object& progress) {
            const SolveReport report =
                withProgress(progress, [&](const ProgressCallback& callback) {
                  const std::lock_guard lock(self.busy);
                  return self.filter->solve(callback);
                });
            return reportDict(report);
          },
          py::kw_only(), arg("progress") = py::none(),
          "The configured number of cycles (or the direct solve); returns its report.")
      .def(
          "image",
          [](PyInteractiveFilter& self, const py::object& dtype) {
            Image image;
            {
              py::gil_scoped_release release;
              const std::lock_guard lock(self.busy);
              image = self.filter->image();
            }
            return arrayFromImage(std::move(image), sampleTypeFrom(dtype, self.sampleType),
                                  self.planar);
          },
          py::kw_only(), arg("dtype") = py::none(),
          "The current solution as an image (the input's shape and dtype unless dtype).");

  py::class_<PyGeodesicSolver>(
      m, "GeodesicSolver",
      "Heat-method distances as a stateful solver (paper Sec. 7.3): set_sources resets, "
      "update() refines by one cycle per system (cheap, for display), solve() solves fully.")
      .def(py::init(&makeGeodesic), arg("domain"), py::kw_only(), arg("alpha") = 1e3,
           arg("offset") = "near-field", arg("boundary") = "average", arg("interactive") = false,
           arg("progress") = py::none(),
           "Sets up both systems on a TexelDomain. interactive=True starts from the "
           "frame-by-frame defaults (GeodesicOptions::interactive). Solver keywords as "
           "texgrad.geodesic's.")
      .def(
          "set_sources",
          [](PyGeodesicSolver& self, const py::object& vertices, const py::object& uvs,
             const py::object& points) {
            const std::vector<GeodesicSource> sources =
                geodesicSourcesFrom(vertices, uvs, points, self.domain->mesh().positions.size());
            py::gil_scoped_release release;
            const std::lock_guard lock(self.busy);
            self.solver->setSources(sources);
          },
          py::kw_only(), arg("source_vertices") = py::none(), arg("source_uvs") = py::none(),
          arg("source_points") = py::none(), "Replaces the sources and resets the iterates.")
      .def(
          "set_alpha",
          [](PyGeodesicSolver& self, double alpha) {
            py::gil_scoped_release release;
            const std::lock_guard lock(self.busy);
            self.solver->setAlpha(alpha);
          },
          arg("alpha"), "New screening weight: numeric update only; keeps the sources.")
      .def(
          "update",
          [](PyGeodesicSolver& self) {
            py::gil_scoped_release release;
            const std::lock_guard lock(self.busy);
            self.solver->update();
          },
          "One refinement (one V-cycle per system, or exact solves with solver='direct').")
      .def(
          "solve",
          [](PyGeodesicSolver& self, const py::object& progress) {
            withProgress(progress, [&](const ProgressCallback& callback) {
              const std::lock_guard lock(self.busy);
              self.solver->solve(callback);
            });
          },
          py::kw_only(), arg("progress") = py::none(), "Full solves of both systems.")
      .def(
          "residual",
          [](PyGeodesicSolver& self) {
            py::gil_scoped_release release;
            const std::lock_guard lock(self.busy);
            return self.solver->residual();
          },
          "Largest relative residual of the current heat and distance iterates.")
      .def_property_readonly("heat_settled",
                             [](PyGeodesicSolver& self) {
                               py::gil_scoped_release release;
                               const std::lock_guard lock(self.busy);
                               return self.solver->heatSettled();
                             })
      .def_property_readonly(
          "distances",
          [](PyGeodesicSolver& self) {
            Eigen::MatrixXd distances;
            {
              py::gil_scoped_release release;
              const std::lock_guard lock(self.busy);
              distances = self.solver->distances();
            }
            return arrayFromMatrix(distances).attr("reshape")(-1);
          },
          "Current distance per unknown (model units; inf where no source reaches).")
      .def(
          "distance_image",
          [](PyGeodesicSolver& self, bool pad) {
            const TexelDomain& domain = *self.domain;
            Image image(domain.grid().imageWidth, domain.grid().imageHeight, 1, PixelFormat::Float);
            {
              py::gil_scoped_release release;
              const std::lock_guard lock(self.busy);
              scatterTexels(domain.grid(), self.solver->distances(), image);
              if (pad) image = dilateGutters(domain.mesh(), domain.atlas(), domain.grid(), image);
            }
            return arrayFromImage(std::move(image), SampleType::Float32, true);
          },
          py::kw_only(), arg("dilate") = true,
          "Current distances as an H x W float32 image (gutters filled unless dilate=False).");
}

}  // namespace texgrad::python
