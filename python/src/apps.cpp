// Every app as a function on numpy images: filter, stitch, seams, dilate, geodesic, lic, react,
// mask. Keywords mirror the CLI's flags and defaults; the options structs validate them.
#include <pybind11/stl.h>

#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "bindings.h"
#include "progress.h"
#include "texgrad/apps/dilate.h"
#include "texgrad/apps/filter.h"
#include "texgrad/apps/geodesic.h"
#include "texgrad/apps/lic.h"
#include "texgrad/apps/reaction_diffusion.h"
#include "texgrad/apps/seams.h"
#include "texgrad/apps/stitch.h"
#include "texgrad/apps/texel_signal.h"
#include "texgrad/apps/vector_field.h"
#include "texgrad/atlas/image_coverage.h"
#include "texgrad/atlas/texel_mask.h"
#include "texgrad/core/error.h"
#include "texgrad/io/mesh_texture.h"

namespace texgrad::python {
namespace {

/// Resolution when neither the call nor the mesh's texture gives one (`texgrad geodesic`'s).
constexpr int kDefaultGeodesicResolution = 1024;

/// The domain's size if `target` is a TexelDomain, else `resolution` (N or (W, H)).
std::pair<int, int> sizeFor(const py::handle& target, const py::handle& resolution,
                            std::pair<int, int> fallback) {
  if (py::isinstance<TexelDomain>(target)) {
    const TexelGrid& grid = target.cast<const TexelDomain&>().grid();
    return {grid.imageWidth, grid.imageHeight};
  }
  return resolution.is_none() ? fallback : resolutionFrom(resolution);
}

/// Solver settings from `defaults` and the call's solver keywords.
SolverSettings solverFrom(SolverSettings defaults, const py::kwargs& keywords) {
  applySolverKeywords(keywords, defaults);
  return defaults;
}

py::array filter(const py::handle& target, const py::handle& texture, double alpha, double beta,
                 const py::object& betaMap, std::pair<double, double> betaRange, bool normalMap,
                 const std::string& basis, double seamWeight, bool raw, const py::object& dtype,
                 const py::object& progress, const py::kwargs& solver) {
  FilterOptions options;
  options.alpha = alpha;
  options.beta = beta;
  options.normalMap = normalMap;
  options.rawSolution = raw;
  options.solver = solverFrom(options.solver, solver);
  options.validate();
  ImageArgument input = imageFromArray(texture, "image");
  std::optional<ImageArgument> map;
  if (!betaMap.is_none()) map = imageFromArray(betaMap, "beta_map");
  OperatorOptions operatorOptions;
  operatorOptions.keepPieceIntegrals = map.has_value();  // only a beta map re-assembles S
  if (basis == "bilinear") {
    operatorOptions.basis = fem::BasisKind::Bilinear;
    operatorOptions.seamContinuityWeight = seamWeight;
  } else if (basis != "continuous") {
    throw InvalidInputError("basis must be 'continuous' or 'bilinear', got '" + basis + "'");
  } else if (seamWeight != 0.0) {
    throw InvalidInputError("seam_weight applies to basis='bilinear' only");
  }
  const auto domain =
      domainFor(target, input.image.width, input.image.height, operatorOptions, progress);
  if (map)
    options.betaPerCell =
        cellValuesFromMap(domain->grid(), map->image, betaRange.first, betaRange.second);
  Image output = withProgress(progress, [&](const ProgressCallback& callback) {
    // The module's copy of the array is handed over: filterTexture writes the result into it.
    return filterTexture(*domain, std::move(input.image), options, callback).image;
  });
  return arrayFromImage(std::move(output), sampleTypeFrom(dtype, input.sampleType), input.planar);
}

std::vector<Image> imageList(const py::object& list, const std::string& name) {
  std::vector<Image> images;
  if (list.is_none()) return images;
  size_t k = 0;
  for (const py::handle item : list)
    images.push_back(imageFromArray(item, name + "[" + std::to_string(k++) + "]").image);
  if (images.empty()) throw InvalidInputError(name + " is empty");
  return images;
}

py::array stitch(const py::handle& target, const py::object& composite, const py::object& segments,
                 const py::object& partials, const py::object& confidences, const py::object& lock,
                 double alpha, bool gainCompensation, bool illumination, bool raw,
                 const py::object& dtype, const py::object& progress, const py::kwargs& solver) {
  StitchOptions options;
  options.alpha = alpha;
  options.rawSolution = raw;
  options.compensateGains = gainCompensation;
  options.compensateIllumination = illumination;
  // `texgrad stitch`'s solver defaults: 10 V-cycles, or 200 CG iterations.
  SolverSettings defaults;
  defaults.cycles = 10;
  defaults.maxIterations = 200;
  options.solver = solverFrom(defaults, solver);
  options.validate();
  const bool compositeMode = !composite.is_none();
  if (compositeMode == !partials.is_none())
    throw InvalidInputError("give either composite with segments, or partials with confidences");
  ImageArgument first;
  Image segmentImage;
  std::vector<Image> partialImages, confidenceImages;
  if (compositeMode) {
    if (segments.is_none()) throw InvalidInputError("segments is None; composite needs it");
    first = imageFromArray(composite, "composite");
    segmentImage = imageFromArray(segments, "segments").image;
  } else {
    if (confidences.is_none()) throw InvalidInputError("confidences is None; partials need it");
    partialImages = imageList(partials, "partials");
    confidenceImages = imageList(confidences, "confidences");
    first = imageFromArray(py::list(partials)[0], "partials[0]");
  }
  if (!lock.is_none()) options.lock = imageFromArray(lock, "lock").image;
  const auto domain = domainFor(target, first.image.width, first.image.height, {}, progress);
  Image output = withProgress(progress, [&](const ProgressCallback& callback) {
    return compositeMode
               ? stitchComposite(*domain, first.image, segmentImage, options, callback).image
               : stitchPartials(*domain, partialImages, confidenceImages, options, callback).image;
  });
  return arrayFromImage(std::move(output), sampleTypeFrom(dtype, first.sampleType), first.planar);
}

py::array seams(const py::handle& target, const py::handle& texture, const py::object& mask,
                bool raw, const py::object& dtype, const py::object& progress) {
  SeamsOptions options;
  options.rawSolution = raw;
  ImageArgument input = imageFromArray(texture, "image");
  const Image maskImage = mask.is_none() ? Image() : imageFromArray(mask, "mask").image;
  const auto domain = domainFor(target, input.image.width, input.image.height,
                                OperatorOptions::assembledOnce(), progress);
  Image output = withProgress(progress, [&](const ProgressCallback& callback) {
    return smoothSeams(*domain, std::move(input.image), maskImage, options, callback).image;
  });
  return arrayFromImage(std::move(output), sampleTypeFrom(dtype, input.sampleType), input.planar);
}

/// Runs `body(mesh, atlas, grid)`, with the GIL released, on the texel grid of `target` at
/// width x height: a TexelDomain's own, or one built for a Mesh without operators (the apps that
/// need only the grid: dilate, mask).
template <typename Body>
Image onTexelGrid(const py::handle& target, int width, int height, Body&& body) {
  if (py::isinstance<TexelDomain>(target)) {
    const auto domain = domainFor(target, width, height, {}, py::none());
    py::gil_scoped_release release;
    return body(domain->mesh(), domain->atlas(), domain->grid());
  }
  if (!py::isinstance<TexturedMesh>(target))
    throw py::type_error("mesh must be a texgrad.Mesh or a texgrad.TexelDomain");
  const auto& mesh = target.cast<const TexturedMesh&>();
  py::gil_scoped_release release;
  requireUvsInImage(mesh);
  const Atlas atlas = buildAtlas(mesh);
  return body(mesh, atlas, buildTexelGrid(mesh, atlas, width, height));
}

py::array dilate(const py::handle& target, const py::handle& texture, int radius, bool infinite,
                 const py::object& dtype) {
  DilateOptions options;
  options.radius = radius;
  options.infinite = infinite;
  options.validate();
  ImageArgument input = imageFromArray(texture, "image");
  Image output =
      onTexelGrid(target, input.image.width, input.image.height,
                  [&](const TexturedMesh& mesh, const Atlas& atlas, const TexelGrid& grid) {
                    return dilateGutters(mesh, atlas, grid, input.image, options);
                  });
  return arrayFromImage(std::move(output), sampleTypeFrom(dtype, input.sampleType), input.planar);
}

py::array mask(const py::handle& target, const py::object& resolution, const std::string& kind) {
  const MaskKind maskKind = parseMaskKind(kind);
  const auto [width, height] = sizeFor(target, resolution, {0, 0});
  if (width == 0) throw InvalidInputError("resolution is None; give N or (width, height)");
  Image output = onTexelGrid(target, width, height,
                             [&](const TexturedMesh&, const Atlas&, const TexelGrid& grid) {
                               return texelMask(grid, maskKind);
                             });
  return arrayFromImage(std::move(output), SampleType::UInt8, false);
}

}  // namespace

std::pair<int, int> resolutionFrom(const py::handle& resolution) {
  std::pair<int, int> size;
  if (py::isinstance<py::int_>(resolution)) {
    const int n = resolution.cast<int>();
    size = {n, n};
  } else {
    try {
      size = resolution.cast<std::pair<int, int>>();
    } catch (const py::cast_error&) {
      throw py::type_error("resolution must be N or (width, height)");
    }
  }
  if (size.first < 1 || size.second < 1)
    throw InvalidInputError("resolution must be positive, got " + std::to_string(size.first) +
                            " x " + std::to_string(size.second));
  return size;
}

namespace {

/// One point (a 1-D array) as a 1 x k array; other arrays as they are.
py::object atLeast2d(const py::object& points) {
  return py::module_::import("numpy").attr("atleast_2d")(points);
}

}  // namespace

std::vector<GeodesicSource> geodesicSourcesFrom(const py::object& vertices, const py::object& uvs,
                                                const py::object& points, size_t vertexCount) {
  std::vector<GeodesicSource> sources;
  if (!vertices.is_none()) {
    const Eigen::MatrixXd v =
        matrixFromArray(py::array::ensure(vertices).attr("reshape")(-1), "source_vertices", 1);
    for (Eigen::Index k = 0; k < v.rows(); ++k) {
      if (v(k, 0) != std::floor(v(k, 0)))
        throw InvalidInputError("source_vertices[" + std::to_string(k) + "] is not an integer");
      // Checked here, before any operator is built (as `texgrad geodesic --source-vertex`).
      if (v(k, 0) < 0 || v(k, 0) >= static_cast<double>(vertexCount))
        throw InvalidInputError("source_vertices[" + std::to_string(k) +
                                "] = " + std::to_string(static_cast<int64_t>(v(k, 0))) +
                                " is out of range; the mesh has " + std::to_string(vertexCount) +
                                " vertices (0-based)");
      sources.push_back(GeodesicSource::atVertex(static_cast<int64_t>(v(k, 0))));
    }
  }
  if (!uvs.is_none()) {
    const Eigen::MatrixXd uv = matrixFromArray(atLeast2d(uvs), "source_uvs", 2);
    for (Eigen::Index k = 0; k < uv.rows(); ++k)
      sources.push_back(GeodesicSource::atUv(uv.row(k).transpose()));
  }
  if (!points.is_none()) {
    const Eigen::MatrixXd p = matrixFromArray(atLeast2d(points), "source_points", 3);
    for (Eigen::Index k = 0; k < p.rows(); ++k)
      sources.push_back(GeodesicSource::atPoint(p.row(k).transpose()));
  }
  if (sources.empty())
    throw InvalidInputError("no source given; pass source_vertices, source_uvs or source_points");
  return sources;
}

namespace {

/// Per-unknown values as an H x W float32 image (gutters filled as the CLI's outputs if `pad`).
py::array unknownImage(const TexelDomain& domain, const Eigen::VectorXd& values, bool pad) {
  Image image(domain.grid().imageWidth, domain.grid().imageHeight, 1, PixelFormat::Float);
  scatterTexels(domain.grid(), values, image);
  if (pad) image = dilateGutters(domain.mesh(), domain.atlas(), domain.grid(), image);
  return arrayFromImage(std::move(image), SampleType::Float32, true);
}

py::object geodesic(const py::handle& target, const py::object& sourceVertices,
                    const py::object& sourceUvs, const py::object& sourcePoints,
                    const py::object& resolution, double alpha, const std::string& offset,
                    const std::string& boundary, bool pad, bool details, const py::object& progress,
                    const py::kwargs& solver) {
  GeodesicOptions options;
  options.alpha = alpha;
  options.offset = parseGeodesicOffset(offset);
  options.boundary = parseGeodesicBoundary(boundary);
  options.solver = solverFrom(options.solver, solver);
  options.validate();
  if (!py::isinstance<TexelDomain>(target) && !py::isinstance<TexturedMesh>(target))
    throw py::type_error("mesh must be a texgrad.Mesh or a texgrad.TexelDomain");
  const size_t vertexCount = py::isinstance<TexelDomain>(target)
                                 ? target.cast<const TexelDomain&>().mesh().positions.size()
                                 : target.cast<const TexturedMesh&>().positions.size();
  const std::vector<GeodesicSource> sources =
      geodesicSourcesFrom(sourceVertices, sourceUvs, sourcePoints, vertexCount);
  std::pair<int, int> fallback{kDefaultGeodesicResolution, kDefaultGeodesicResolution};
  if (resolution.is_none() && py::isinstance<TexturedMesh>(target)) {
    // As `texgrad geodesic`: the size of the mesh's base-colour texture if it names one.
    const auto& mesh = target.cast<const TexturedMesh&>();
    if (mesh.texture("baseColor")) {
      py::gil_scoped_release release;
      if (const std::optional<Image> texture = readMeshTexture(mesh))
        fallback = {texture->width, texture->height};
    }
  }
  const auto [width, height] = sizeFor(target, resolution, fallback);
  const auto domain = domainFor(target, width, height, OperatorOptions::assembledOnce(), progress);
  GeodesicResult result = withProgress(progress, [&](const ProgressCallback& callback) {
    reportProgress(callback, "geodesic", 0.0);
    GeodesicResult r = geodesicDistance(*domain, sources, options, callback);
    reportProgress(callback, "geodesic", 1.0);
    return r;
  });
  py::array image = unknownImage(*domain, result.distances, pad);
  if (!details) return image;
  py::dict info;
  info["distances"] = arrayFromMatrix(result.distances);
  info["max_distance"] = result.maxDistance;
  info["unreachable_texels"] = result.unreachableTexels;
  info["farthest_uv"] = arrayFromMatrix(result.farthestUv.transpose());
  info["farthest_position"] = arrayFromMatrix(result.farthestPosition.transpose());
  py::list resolved;
  for (const ResolvedSource& s : result.sources) {
    py::dict d;
    d["uv"] = arrayFromMatrix(s.uv.transpose());
    d["position"] = arrayFromMatrix(s.position.transpose());
    d["face"] = s.point.face;
    d["snap_distance"] = s.snapDistance;
    resolved.append(d);
  }
  info["sources"] = resolved;
  return py::make_tuple(image, info);
}

FaceVectorField fieldFrom(const TexturedMesh& mesh, const py::object& field,
                          const std::string& curvature, int smoothing) {
  if (field.is_none()) {
    if (curvature != "max" && curvature != "min")
      throw InvalidInputError("curvature must be 'max' or 'min', got '" + curvature + "'");
    CurvatureOptions options;
    options.smoothingRounds = smoothing;
    options.validate();
    py::gil_scoped_release release;
    return curvatureField(
        mesh, curvature == "min" ? CurvatureDirection::Minor : CurvatureDirection::Major, options);
  }
  const Eigen::MatrixXd v = matrixFromArray(field, "field", -1);
  if ((v.cols() != 2 && v.cols() != 3) || v.rows() != static_cast<Eigen::Index>(mesh.faceCount()))
    throw InvalidInputError(
        "field must be m x 2 (intrinsic) or m x 3 (3-D vectors) with one row "
        "per face (" +
        std::to_string(mesh.faceCount()) + "), got " + std::to_string(v.rows()) + " x " +
        std::to_string(v.cols()));
  FaceVectorField result;
  result.basis = v.cols() == 2 ? FieldBasis::Intrinsic : FieldBasis::Extrinsic;
  for (Eigen::Index f = 0; f < v.rows(); ++f)
    result.vectors.emplace_back(v(f, 0), v(f, 1), v.cols() == 3 ? v(f, 2) : 0.0);
  return result;
}

py::array lic(const py::handle& target, const py::object& resolution, const py::object& field,
              const std::string& curvature, int smoothing, uint64_t seed, double epsilon,
              double alpha, double sharpen, double sharpenAlpha, double contrast, bool colour,
              bool pad, const py::object& dtype, const py::object& progress,
              const py::kwargs& solver) {
  LicOptions options;
  options.epsilon = epsilon;
  options.alpha = alpha;
  options.sharpenBeta = sharpen;
  options.sharpenAlpha = sharpenAlpha;
  options.contrast = contrast;
  options.channels = colour ? 3 : 1;
  options.seed = seed;
  options.solver = solverFrom(options.solver, solver);
  options.validate();
  const auto [width, height] = sizeFor(target, resolution, {512, 512});
  const auto domain = domainFor(target, width, height, {}, progress);
  const FaceVectorField faceField = fieldFrom(domain->mesh(), field, curvature, smoothing);
  Image output = withProgress(progress, [&](const ProgressCallback& callback) {
    const auto texel = fieldInTexelCoordinates(domain->mesh(), domain->grid(), faceField);
    Image image = lineIntegralConvolution(*domain, texel, options, callback).image;
    return pad ? dilateGutters(domain->mesh(), domain->atlas(), domain->grid(), image) : image;
  });
  return arrayFromImage(std::move(output), sampleTypeFrom(dtype, SampleType::Float32), !colour);
}

py::array react(const py::handle& target, const py::object& resolution, const std::string& preset,
                int steps, double timeStep, double scale, uint64_t seed, int seedSpots, bool pad,
                const py::object& dtype, const py::object& progress, const py::kwargs& solver) {
  ReactionDiffusionOptions options;
  const GrayScottRates rates = presetRates(parseReactionPreset(preset));
  options.feed = rates.feed;
  options.kill = rates.kill;
  options.timeStep = timeStep;
  options.seed = seed;
  options.seedSpots = seedSpots;
  // As `texgrad react --scale`: features scale with sqrt(D), so both rates by scale^2.
  options.diffusionU *= scale * scale;
  options.diffusionV *= scale * scale;
  options.seedRadius *= scale;
  options.solver = solverFrom(options.solver, solver);
  options.validate();
  if (steps < 0) throw InvalidInputError("steps must be >= 0, got " + std::to_string(steps));
  const auto [width, height] = sizeFor(target, resolution, {512, 512});
  const auto domain = domainFor(target, width, height, OperatorOptions::assembledOnce(), progress);
  Image output = withProgress(progress, [&](const ProgressCallback& callback) {
    Image image = reactionDiffusion(*domain, options, steps, callback).image;
    return pad ? dilateGutters(domain->mesh(), domain->atlas(), domain->grid(), image) : image;
  });
  return arrayFromImage(std::move(output), sampleTypeFrom(dtype, SampleType::Float32), true);
}

}  // namespace

void registerApps(py::module_& m) {
  using py::arg;
  const auto none = py::none();
  m.def("filter", &filter, arg("mesh"), arg("image"), py::kw_only(), arg("alpha") = 1e4,
        arg("beta") = 1.0, arg("beta_map") = none, arg("beta_range") = std::pair(0.0, 2.0),
        arg("normal_map") = false, arg("basis") = "continuous", arg("seam_weight") = 0.0,
        arg("raw") = false, arg("dtype") = none, arg("progress") = none,
        "Smooths (beta < 1) or sharpens (beta > 1) an H x W x C image on the surface: "
        "(alpha M + S) x = (alpha M + beta S) x0 (paper Sec. 7.1). `mesh` is a Mesh or a "
        "TexelDomain of the image's size. beta_map: an image (any size) whose brightness sets "
        "beta per cell over beta_range. raw: keep the exact solution at barely covered texels "
        "(by default clamped into their input's and neighbours' range, as `texgrad filter`). "
        "Solver keywords as `texgrad filter`'s flags: solver "
        "('multigrid', 'cg', 'direct'), precision, cycles, max_iterations, tolerance, levels, "
        "sweeps, line_ratio, weak_row_reach, threads. Returns the image in its dtype (or dtype).");
  m.def("stitch", &stitch, arg("mesh"), py::kw_only(), arg("composite") = none,
        arg("segments") = none, arg("partials") = none, arg("confidences") = none,
        arg("lock") = none, arg("alpha") = 1e2, arg("gain_compensation") = true,
        arg("illumination") = true, arg("raw") = false, arg("dtype") = none, arg("progress") = none,
        "Stitches textures from several sources (paper Sec. 7.2): a composite with a segments "
        "image (one colour per source, black = none), or lists of partials and confidences "
        "(channel 0 in [0, 1]); lock: texels (channel 0 > 0.5) kept exactly; raw as filter's. "
        "Solver keywords as "
        "`texgrad stitch`'s (10 cycles, 200 CG iterations by default).");
  m.def("seams", &seams, arg("mesh"), arg("image"), py::kw_only(), arg("mask") = none,
        arg("raw") = false, arg("dtype") = none, arg("progress") = none,
        "Re-solves the texels along chart boundaries (or under mask, channel 0 > 0.5) for the "
        "smoothest values given all others (`texgrad seams`); raw as filter's.");
  m.def("dilate", &dilate, arg("mesh"), arg("image"), py::kw_only(), arg("radius") = 4,
        arg("infinite") = false, arg("dtype") = none,
        "Fills `radius` rings of gutter texels around the charts (all with infinite=True); "
        "active texels are returned unchanged (`texgrad dilate`).");
  m.def("mask", &mask, arg("mesh"), arg("resolution") = none, py::kw_only(), arg("kind") = "active",
        "The texel classification at a resolution as a uint8 image: kind 'active', 'boundary', "
        "'interior' (H x W x 1), 'chart' or 'coverage' (H x W x 3) (`texgrad mask`).");
  m.def("geodesic", &geodesic, arg("mesh"), py::kw_only(), arg("source_vertices") = none,
        arg("source_uvs") = none, arg("source_points") = none, arg("resolution") = none,
        arg("alpha") = 1e3, arg("offset") = "near-field", arg("boundary") = "average",
        arg("dilate") = true, arg("details") = false, arg("progress") = none,
        "Heat-method geodesic distance (paper Sec. 7.3) from vertices (indices), UV points "
        "(k x 2) or 3-D points (k x 3), in model units, as an H x W float32 image (row 0 = top; "
        "gutters filled as `texgrad geodesic`'s EXR unless dilate=False, then 0 there). "
        "resolution: N or (W, H); default the mesh texture's size, else 1024. With details=True "
        "returns (image, dict) with per-unknown distances, sources and the farthest point.");
  m.def("lic", &lic, arg("mesh"), arg("resolution") = none, py::kw_only(), arg("field") = none,
        arg("curvature") = "max", arg("curvature_smoothing") = CurvatureOptions{}.smoothingRounds,
        arg("seed") = 1, arg("epsilon") = 1e-4, arg("alpha") = 1e4, arg("sharpen") = 100.0,
        arg("sharpen_alpha") = 1e4, arg("contrast") = 0.2, arg("colour") = false,
        arg("dilate") = true, arg("dtype") = none, arg("progress") = none,
        "Line integral convolution (paper Sec. 7.4) of a per-face field (m x 2 intrinsic "
        "coefficients or m x 3 vectors) or of principal curvature directions ('max'/'min'), at "
        "resolution N or (W, H) (default 512). Returns H x W (or H x W x 3 with colour) float32 "
        "in [0, 1], gutters filled as `texgrad lic` writes them.");
  m.def("react", &react, arg("mesh"), arg("resolution") = none, py::kw_only(),
        arg("preset") = "stripes", arg("steps") = 3000, arg("time_step") = 1.0, arg("scale") = 1.0,
        arg("seed") = 1, arg("seed_spots") = 40, arg("dilate") = true, arg("dtype") = none,
        arg("progress") = none,
        "Gray-Scott reaction-diffusion pattern ('stripes' or 'dots') grown on the surface for "
        "`steps` steps (`texgrad react`), as an H x W float32 image in [0, 1].");
}

}  // namespace texgrad::python
