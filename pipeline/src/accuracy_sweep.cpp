// The sweeps of `solo bench accuracy` (accuracy_sweep.h, docs/accuracy.md). Every point runs
// the library functions `solo night` runs, with one knob changed, and measures the result
// against the synthetic scene's exact ground truth.

#include <solo/pipeline/accuracy_sweep.h>
#include <solo/pipeline/night_conversion.h>
#include <solo/pipeline/night_presets.h>

#include <solo/core/error.h>
#include <solo/core/report.h>
#include <solo/geometry/depth_metrics.h>
#include <solo/geometry/depth_refinement.h>
#include <solo/geometry/mesh_cleanup.h>
#include <solo/geometry/mesh_metrics.h>
#include <solo/geometry/normal_metrics.h>
#include <solo/geometry/normals_from_depth.h>
#include <solo/geometry/surface_mesh.h>
#include <solo/geometry/view_mesh_distances.h>
#include <solo/lighting/light_stage.h>
#include <solo/post/exposure.h>
#include <solo/post/post_process.h>
#include <solo/render/night_scene.h>
#include <solo/render/path_tracer.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <sstream>
#include <stdexcept>

namespace solo {

double loadAverage1Min() {
  double load[1] = {-1};
  return ::getloadavg(load, 1) == 1 ? load[0] : -1;
}

AccuracySweepInput readAccuracySweepInput(const std::filesystem::path& manifest) {
  AccuracySweepInput in;
  in.manifest = manifest;
  in.truth_manifest = groundTruthManifest(manifest);
  Stopwatch clock;
  in.scene = loadScene(manifest);
  in.input_seconds = clock.seconds();
  in.truth = loadScene(in.truth_manifest);
  if (in.truth.depth_m.size() != in.scene.image.size() || in.truth.normals.size() != in.scene.image.size())
    throw InputError(in.truth_manifest, "its depth and normals must be of the image's size (" +
                                            std::to_string(in.scene.width()) + "x" +
                                            std::to_string(in.scene.height()) + ")");
  const std::filesystem::path truth_mesh_file = in.truth_manifest.parent_path() / "mesh.ply";
  std::error_code ec;
  if (std::filesystem::exists(truth_mesh_file, ec)) in.truth_mesh = readMesh(truth_mesh_file);
  return in;
}

std::size_t SweepTable::column(const std::string& name) const {
  const auto it = std::find(columns.begin(), columns.end(), name);
  if (it == columns.end()) throw std::out_of_range("table " + stage + " has no column " + name);
  return static_cast<std::size_t>(it - columns.begin());
}

std::string SweepTable::csv() const {
  std::ostringstream out;
  const auto line = [&](const std::vector<std::string>& cells) {
    for (std::size_t i = 0; i < cells.size(); ++i) out << (i ? "," : "") << cells[i];
    out << "\n";
  };
  line(columns);
  for (const auto& row : rows) line(row);
  return out.str();
}

namespace {

std::string num(double v) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.6g", v);
  return buffer;
}
std::string seconds(double v) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.4f", v);
  return buffer;
}
std::string integer(std::int64_t v) { return std::to_string(v); }
std::string boolean(bool v) { return v ? "true" : "false"; }

std::int64_t metricInt(const StageReport& report, const std::string& name) {
  const MetricValue* v = report.find(name);
  if (!v) return 0;
  if (const auto* i = std::get_if<std::int64_t>(v)) return *i;
  if (const auto* d = std::get_if<double>(v)) return static_cast<std::int64_t>(*d);
  return 0;
}
double metricDouble(const StageReport& report, const std::string& name) {
  const MetricValue* v = report.find(name);
  if (!v) return 0;
  if (const auto* d = std::get_if<double>(v)) return *d;
  if (const auto* i = std::get_if<std::int64_t>(v)) return static_cast<double>(*i);
  return 0;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/// Runs `run` once, and again (up to `repeats` runs in all) while one run is cheaper than
/// `cheap_s`: the median wall time and the number of runs. The runs are deterministic, so the
/// result of the last one stands for all.
template <class Run>
std::pair<double, int> timed(Run&& run, int repeats, double cheap_s) {
  std::vector<double> times;
  do {
    Stopwatch clock;
    run();
    times.push_back(clock.seconds());
  } while (static_cast<int>(times.size()) < repeats && times.front() < cheap_s);
  return {median(times), static_cast<int>(times.size())};
}


/// Error of a render's luminance Y against a reference over the pixels that show no emitter in
/// either image (lamps are exact in both and would flatter the figure). The main figure clips
/// both at a white metered on the reference (its street's 95th percentile at 80 %,
/// meteredSensorWhite), as a final image clips: without clipping, one firefly (a rare path to a lamp of 10^3 cd/m^2)
/// in either image outweighs every other pixel and the error stays near 1 whatever the samples.
struct RadianceError {
  double white = 0;                    ///< the clipping level, render units (cd/m^2)
  double relative_rmse = 0;            ///< sqrt(sum (y' - r')^2 / sum r'^2), y' = min(y, white)
  /// sqrt(sum var_ref / sum r'^2): var_ref is the given per-pixel variance of the clipped
  /// reference, or else se_ref^2 over the reference's unclipped pixels
  double reference_noise = 0;
  double noise_corrected = 0;          ///< sqrt(max(0, sum (y' - r')^2 - sum var_ref) / sum r'^2)
  double relative_rmse_unclipped = 0;  ///< sqrt(sum (y - r)^2 / sum r^2)
  double luminance_ratio = 0;          ///< sum y' / sum r': a bias (brighter > 1, darker < 1)
  std::int64_t pixels = 0;
};

RadianceError radianceError(const RenderOutput& image, const RenderOutput& reference,
                            const cv::Mat& reference_variance = cv::Mat()) {
  CV_Assert(image.radiance.size() == reference.radiance.size());
  RadianceError e;
  e.white = meteredSensorWhite(reference.radiance, reference.emitter_coverage);
  double squared = 0, norm = 0, variance = 0, squared_raw = 0, norm_raw = 0, sum = 0, sum_ref = 0;
  for (int y = 0; y < reference.radiance.rows; ++y)
    for (int x = 0; x < reference.radiance.cols; ++x) {
      // Pixels that see an emitter, also where it covers a sliver of the pixel, are left out.
      if (reference.emitter_coverage.at<float>(y, x) > 0.f || image.light_id.at<int>(y, x) != 0) continue;
      const double r = reference.radiance.at<cv::Vec3f>(y, x)[1], v = image.radiance.at<cv::Vec3f>(y, x)[1];
      const double rc = std::min(r, e.white), vc = std::min(v, e.white);
      const double se = reference.std_error.at<float>(y, x);
      squared += (vc - rc) * (vc - rc);
      sum += vc, sum_ref += rc;
      norm += rc * rc;
      if (!reference_variance.empty())
        variance += reference_variance.at<float>(y, x);
      else if (r < e.white)
        variance += se * se;
      squared_raw += (v - r) * (v - r);
      norm_raw += r * r;
      ++e.pixels;
    }
  if (norm > 0) {
    e.relative_rmse = std::sqrt(squared / norm);
    e.reference_noise = std::sqrt(variance / norm);
    e.noise_corrected = std::sqrt(std::max(0.0, squared - variance) / norm);
  }
  if (sum_ref > 0) e.luminance_ratio = sum / sum_ref;
  if (norm_raw > 0) e.relative_rmse_unclipped = std::sqrt(squared_raw / norm_raw);
  return e;
}

/// A reference rendered as two independent halves: their average, and the per-pixel variance of
/// that average clipped at the white metered on it, ((min(a, W) - min(b, W)) / 2)^2. Unbiased for
/// the noise of pixels below W, and a firefly in either half adds at most W^2 / 4: the tracer's
/// own standard error is unclipped, and one firefly in a tile inflates its pooled estimate for
/// the whole tile.
struct SplitReference {
  RenderOutput image;
  cv::Mat clipped_variance;  ///< CV_32F
};

SplitReference fromHalves(const RenderOutput& a, const RenderOutput& b) {
  SplitReference ref{a, cv::Mat()};
  RenderOutput& m = ref.image;
  m.radiance = 0.5 * (a.radiance + b.radiance);
  m.emitter_coverage = 0.5 * (a.emitter_coverage + b.emitter_coverage);
  m.samples = a.samples + b.samples;
  cv::Mat se_a, se_b;
  cv::multiply(a.std_error, a.std_error, se_a);
  cv::multiply(b.std_error, b.std_error, se_b);
  cv::sqrt(0.25 * (se_a + se_b), m.std_error);
  const double white = meteredSensorWhite(m.radiance, m.emitter_coverage);
  ref.clipped_variance.create(m.radiance.size(), CV_32F);
  for (int y = 0; y < m.radiance.rows; ++y)
    for (int x = 0; x < m.radiance.cols; ++x) {
      const double d = 0.5 * (std::min<double>(a.radiance.at<cv::Vec3f>(y, x)[1], white) -
                              std::min<double>(b.radiance.at<cv::Vec3f>(y, x)[1], white));
      ref.clipped_variance.at<float>(y, x) = static_cast<float>(d * d);
    }
  return ref;
}

/// One setting of the whole pipeline: the night conversion's options (a preset applied).
struct PipelineSetting {
  std::string name;
  NightConversionOptions night;
};

/// A quality preset of `solo night` (night_presets.h) as a pipeline setting.
PipelineSetting presetSetting(const std::string& preset) {
  return PipelineSetting{preset, nightPreset(preset)};
}

}  // namespace

struct AccuracySweep::Impl {
  Scene scene, truth;
  Scene refine_scene;  ///< scene as the refinement sees it (sceneForRefinement)
  TriangleMesh truth_mesh;
  AccuracySweepOptions o;

  // Shared products, made on first use.
  std::optional<DepthRefinementResult> prefix;  ///< upsample + filter + uncertain, no optimisation
  double prefix_seconds = 0;
  int prefix_repeats = 0;
  std::optional<DepthRefinementResult> refined;  ///< the default refinement
  std::optional<DepthMesh> mesh;                 ///< the default mesh of the default refinement
  std::optional<NightScene> night;               ///< with the default lights

  void say(const std::string& line) const {
    if (o.progress) o.progress(line);
  }

  std::vector<std::string> head() const {
    return {integer(static_cast<std::int64_t>(o.seed)), integer(scene.width()), integer(scene.height())};
  }

  const DepthRefinementResult& refinementPrefix() {
    if (!prefix) {
      DepthRefinementOptions options;
      options.optimize = false;
      const auto [s, n] = timed([&] { prefix = refineDepth(refine_scene, options); }, o.repeats, o.cheap_seconds);
      prefix_seconds = s, prefix_repeats = n;
    }
    return *prefix;
  }

  const DepthRefinementResult& defaultRefinement() {
    if (!refined) {
      say("default refinement (for the mesh and render sweeps) ...");
      refined = refineDepth(refine_scene, DepthRefinementOptions{});
    }
    return *refined;
  }

  DepthMeshCleanupOptions meshOptions(bool fill_holes, int max_fair_vertices, bool solids) const {
    DepthMeshCleanupOptions m;
    m.fill_holes = fill_holes;
    m.hole_filling.max_fair_vertices = max_fair_vertices;
    m.close_solids = solids;
    m.evaluate = false;  // as `solo night`: the quality counts cost more than the stage
    return m;
  }

  const DepthMesh& defaultMesh() {
    if (!mesh) {
      const DepthRefinementResult& r = defaultRefinement();
      say("default mesh (for the render sweep) ...");
      StageReport report;
      mesh = meshFromScene(r.depth_m, scene.camera, r.maps.instances, r.uncertain,
                           meshOptions(true, HoleFillOptions{}.max_fair_vertices, true), report);
    }
    return *mesh;
  }

  LightStageOptions lightOptions() const {
    LightStageOptions l;
    l.instantiation.seed = o.seed;
    l.illuminant_table = o.illuminant_table;
    return l;
  }

  const NightScene& defaultNight() {
    if (!night) {
      const DepthRefinementResult& r = defaultRefinement();
      const DepthMesh& m = defaultMesh();
      const LightStageResult lights = runLightStage(scene, r.depth_m, lightOptions());
      night = buildNightScene(m, r.maps.albedo, r.maps.roughness, scene.image, lights.record, {}, r.normals);
    }
    return *night;
  }

  /// Samples per pixel of a reference rendered in halves: reference_spp rounded to an even count.
  int splitReferenceSpp() const { return 2 * std::max(1, o.reference_spp / 2); }

  /// A sweep's reference: reference_spp samples in two independent halves (seeds seed +
  /// kReferenceSeedOffset and seed + 2 kReferenceSeedOffset), so that its own noise is measured
  /// on the clipped image the errors are taken on (SplitReference).
  SplitReference splitReference(const RenderScene& render_scene, double& seconds_out) {
    PathTracerOptions t;
    t.min_samples = t.max_samples = splitReferenceSpp() / 2;
    t.light_sampler = LightSamplerKind::Power;
    t.near_field_lights = false;  // as solo night's presets render
    t.progress = false;
    Stopwatch clock;
    t.seed = o.seed + kReferenceSeedOffset;
    const RenderOutput a = renderPathTraced(render_scene, t);
    t.seed = o.seed + 2 * kReferenceSeedOffset;
    const RenderOutput b = renderPathTraced(render_scene, t);
    seconds_out = clock.seconds();
    return fromHalves(a, b);
  }

  // ---- refine -------------------------------------------------------------------------------

  struct DepthAccuracy {
    double abs_rel = 0, rmse_m = 0, normal_mean_deg = 0, normal_median_deg = 0;
  };
  DepthAccuracy depthAccuracy(const cv::Mat& depth_m) const {
    DepthEvaluationInput d;
    d.prediction_m = depth_m;
    d.ground_truth_m = truth.depth_m;
    const DepthMetrics dm = evaluateDepth(d);
    NormalEvaluationInput n;
    n.prediction = normalsFromDepth(depth_m, scene.camera);
    n.ground_truth = truth.normals;
    const NormalMetrics nm = evaluateNormals(n);
    return {dm.abs_rel, dm.rmse_m, nm.mean_deg, nm.median_deg};
  }

  SweepTable refineSweep() {
    SweepTable t;
    t.stage = "refine";
    t.columns = {"seed", "width", "height", "method", "max_iterations", "function_tolerance", "iterations_run",
                 "repeats", "seconds", "optimize_seconds", "objective", "abs_rel", "rmse_m", "normal_mean_deg",
                 "normal_median_deg", "load_1min"};
    const auto add = [&](const std::string& method, const std::string& max_iterations, const std::string& tolerance,
                         const std::string& iterations_run, int repeats, double total_s, const std::string& optimize_s,
                         const std::string& objective, const cv::Mat& depth_m) {
      const DepthAccuracy a = depthAccuracy(depth_m);
      std::vector<std::string> row = head();
      row.insert(row.end(), {method, max_iterations, tolerance, iterations_run, integer(repeats), seconds(total_s),
                             optimize_s, objective, num(a.abs_rel), num(a.rmse_m), num(a.normal_mean_deg),
                             num(a.normal_median_deg), num(loadAverage1Min())});
      t.rows.push_back(row);
      say("[refine] " + method + (max_iterations.empty() ? "" : " " + max_iterations + " it") +
          (tolerance.empty() ? "" : " tol " + tolerance) + ": " + seconds(total_s) + " s, AbsRel " + num(a.abs_rel) +
          ", normals " + num(a.normal_mean_deg) + " deg mean");
    };

    {  // upsampling alone: `solo night --no-refine`
      DepthRefinementOptions options;
      options.filter = options.uncertain_regions = options.optimize = false;
      DepthRefinementResult r;
      const auto [s, n] = timed([&] { r = refineDepth(refine_scene, options); }, o.repeats, o.cheap_seconds);
      add("upsample_only", "", "", "", n, s, "", "", r.depth_m);
    }
    const DepthRefinementResult& p = refinementPrefix();
    add("filter_only", "0", "", "0", prefix_repeats, prefix_seconds, "0", "", p.depth_m);

    const auto ceres = [&](const std::string& method, int max_iterations, double tolerance) {
      NormalGuidedOptimizationOptions options;
      options.max_iterations = max_iterations;
      options.function_tolerance = tolerance;
      NormalGuidedOptimizationResult r;
      const auto [s, n] = timed(
          [&] { r = optimizeDepthWithNormals(p.filtered_depth_m, p.normals, p.uncertain, p.maps.instances, scene.camera,
                                             options); },
          o.repeats, o.cheap_seconds);
      add(method, integer(max_iterations), num(tolerance), integer(metricInt(r.report, "iterations")), n,
          prefix_seconds + s, seconds(s), num(r.final.total), r.depth_m);
    };
    const std::vector<int> iterations = o.quick ? std::vector<int>{1, 3, 10} : std::vector<int>{1, 2, 3, 5, 10, 20, 40};
    for (int k : iterations) ceres("ceres_lbfgs", k, NormalGuidedOptimizationOptions{}.function_tolerance);
    const std::vector<double> tolerances = o.quick ? std::vector<double>{1e-2} : std::vector<double>{1e-2, 1e-3, 1e-4};
    for (double tol : tolerances) ceres("ceres_lbfgs_tolerance", o.quick ? 30 : 100, tol);

    const std::vector<int> adam_iterations = o.quick ? std::vector<int>{10} : std::vector<int>{10, 100};
    for (int k : adam_iterations) {
      AdamOptions options;
      options.iterations = k;
      NormalGuidedOptimizationResult r;
      const auto [s, n] = timed(
          [&] { r = optimizeDepthWithAdam(p.filtered_depth_m, p.normals, p.uncertain, p.maps.instances, scene.camera,
                                          options); },
          o.repeats, o.cheap_seconds);
      add("adam", integer(k), "", integer(k), n, prefix_seconds + s, seconds(s), num(r.final.total), r.depth_m);
    }
    t.notes.push_back("seconds = upsample + filter + uncertain regions (" + seconds(prefix_seconds) +
                      " s, median of " + integer(prefix_repeats) +
                      ") + the optimisation; normals are those of each depth (normalsFromDepth) against the true normals");
    return t;
  }

  // ---- mesh ---------------------------------------------------------------------------------

  /// One setting of the mesh stage.
  struct MeshPoint {
    std::string name;
    bool fill;
    int max_fair;
    bool solids;
  };

  std::vector<MeshPoint> meshPoints() const {
    const int fair = HoleFillOptions{}.max_fair_vertices;
    return o.quick ? std::vector<MeshPoint>{{"default", true, fair, true}, {"no_fairing", true, 0, true},
                                            {"no_fill_no_solids", false, fair, false}}
                   : std::vector<MeshPoint>{{"default", true, fair, true},  {"fair_up_to_1000", true, 1000, true},
                                            {"no_fairing", true, 0, true},  {"no_solids", true, fair, false},
                                            {"no_fill", false, fair, true}, {"no_fill_no_solids", false, fair, false}};
  }

  /// The distance cells of a mesh row (mean_to_ref_m to truth_covered) and, in `distance_text`,
  /// their summary for the progress line; empty cells without a true mesh.
  std::vector<std::string> meshDistanceCells(const DepthMesh& m, const TriangleMesh& soup,
                                             std::string& distance_text) const {
    if (truth_mesh.faces.empty()) return {"", "", "", "", "", "", "", "", "", ""};
    MeshDistanceOptions distance_options;
    distance_options.samples = o.distance_samples;
    distance_options.seed = o.seed;
    const MeshDistances d = measureMeshDistances(soup, truth_mesh, distance_options);
    std::vector<std::string> cells = {num(d.mean_to_reference), num(d.hausdorff_to_reference),
                                      num(d.mean_from_reference), num(d.chamfer)};
    // Where the mean comes from (docs/accuracy.md): face origin, the far bands, relative
    // distance and the true pixels the mesh covers.
    ViewMeshDistanceOptions view_options;
    view_options.samples = o.distance_samples;
    view_options.seed = o.seed;
    const ViewMeshDistances v =
        measureViewMeshDistances(soup, faceOrigins(m.mesh), truth_mesh, truth.depth_m, truth.camera, view_options);
    double far_share = 0, far_contribution = 0;
    for (std::size_t b = 1; b < v.by_depth.size(); ++b)
      if (view_options.depth_band_edges_m[b - 1] >= 80) {
        far_share += v.by_depth[b].area_share;
        far_contribution += v.by_depth[b].contribution_m;
      }
    auto originMean = [&](FaceOrigin origin) {
      const DistancePart& part = v.by_origin[static_cast<std::size_t>(origin)];
      return part.samples > 0 ? num(part.mean_m) : std::string();
    };
    cells.insert(cells.end(), {originMean(FaceOrigin::DepthSurface), originMean(FaceOrigin::HoleFill),
                               originMean(FaceOrigin::Solid), num(far_share), num(far_contribution),
                               num(v.mean_relative_to_truth), num(v.truth_covered)});
    distance_text = ", " + num(d.mean_to_reference) + " m mean to the true surfaces (" + num(far_contribution) +
                    " m of it beyond 80 m), " + num(v.mean_relative_to_truth) + " of the depth";
    return cells;
  }

  SweepTable meshSweep() {
    SweepTable t;
    t.stage = "mesh";
    t.columns = {"seed", "width", "height", "setting", "fill_holes", "max_fair_vertices", "close_solids", "repeats",
                 "seconds", "hole_filling_seconds", "faces", "holes_filled", "holes_left_open", "solids",
                 "mean_to_ref_m", "hausdorff_to_ref_m", "mean_from_ref_m", "chamfer_m",
                 "depth_surface_mean_to_ref_m", "hole_fill_mean_to_ref_m", "solid_mean_to_ref_m",
                 "beyond_80m_area_share", "beyond_80m_contribution_m", "mean_relative_to_ref", "truth_covered",
                 "load_1min"};
    const DepthRefinementResult& r = defaultRefinement();
    for (const MeshPoint& pt : meshPoints()) {
      StageReport report;
      std::optional<DepthMesh> m;
      const auto [s, n] = timed(
          [&] {
            report = StageReport{};
            m = meshFromScene(r.depth_m, scene.camera, r.maps.instances, r.uncertain,
                              meshOptions(pt.fill, pt.max_fair, pt.solids), report);
          },
          o.repeats, o.cheap_seconds);
      const TriangleMesh soup = toTriangleMesh(m->mesh);
      std::vector<std::string> row = head();
      row.insert(row.end(), {pt.name, boolean(pt.fill), integer(pt.max_fair), boolean(pt.solids), integer(n),
                             seconds(s), seconds(metricDouble(report, "seconds_hole_filling")),
                             integer(static_cast<std::int64_t>(soup.faces.size())),
                             pt.fill ? integer(metricInt(report, "holes_filled")) : "0",
                             pt.fill ? integer(metricInt(report, "holes_left_open"))
                                     : integer(metricInt(report, "found_inner_holes") +
                                               metricInt(report, "found_frame_holes")),
                             integer(metricInt(report, "foreground_solids"))});
      std::string distance_text;
      const std::vector<std::string> distances = meshDistanceCells(*m, soup, distance_text);
      row.insert(row.end(), distances.begin(), distances.end());
      row.push_back(num(loadAverage1Min()));
      t.rows.push_back(row);
      say("[mesh] " + pt.name + ": " + seconds(s) + " s, " + row[t.column("holes_left_open")] + " holes open" +
          distance_text);
    }
    if (truth_mesh.faces.empty()) t.notes.push_back("no true mesh (gt/mesh.ply): no distances measured");
    t.notes.push_back("the mesh of the default refined depth; distances: " + integer(o.distance_samples) +
                      " random surface points per direction (seed " + integer(static_cast<std::int64_t>(o.seed)) +
                      "), mean_to_ref and hausdorff_to_ref are the meaningful ones (the true mesh also has the "
                      "surfaces the camera does not see, which the from_ref and Chamfer distances count); "
                      "by face origin (depth_surface, hole_fill, solid: mean over the samples on those faces), the "
                      "area share and mean contribution of the faces beyond 80 m, the mean distance relative to "
                      "depth, and truth_covered: the fraction of true pixels within 5 % of their depth from the mesh "
                      "(measureViewMeshDistances)");
    t.notes.push_back("holes_left_open: holes the filling could not close, or every hole found when filling is off");
    return t;
  }
  // ---- render -------------------------------------------------------------------------------

  SweepTable renderSweep() {
    SweepTable t;
    t.stage = "render";
    t.columns = {"seed", "width", "height", "mode", "light_sampler", "near_field", "min_spp", "max_spp", "relative_error_target",
                 "noise_factor", "shadow_roulette", "mean_spp", "repeats", "seconds", "rays", "relative_rmse",
                 "relative_rmse_noise_corrected", "relative_rmse_unclipped", "luminance_ratio", "white_cd_m2",
                 "reference_spp", "reference_relative_noise", "load_1min"};
    const NightScene& n = defaultNight();
    const int reference_spp = splitReferenceSpp();
    say("[render] reference: " + integer(reference_spp) + " spp in two halves, power sampler ...");
    double reference_s = 0;
    const SplitReference split = splitReference(n.scene, reference_s);
    const RenderOutput& ref = split.image;
    const RadianceError self = radianceError(ref, ref, split.clipped_variance);
    say("[render] reference: " + seconds(reference_s) + " s");

    // The noise-matched target's sensor noise, at the reference's auto-exposure white (solo
    // night meters its own on a preview).
    const auto sensor_sigma = renderNoiseSigma(self.white);
    const double kNoiseFactor = NightConversionOptions{}.render.noise_factor;  // the default preset's
    // roulette < 0: a relative-error target (or none); >= 0: the noise-matched target with
    // that shadow-ray roulette fraction.
    const auto point = [&](const std::string& mode, LightSamplerKind kind, int min_spp, int max_spp, double target,
                           double roulette = -1, bool near_field = false) {
      PathTracerOptions options;
      options.light_sampler = kind;
      options.near_field_lights = near_field;
      options.min_samples = min_spp;
      options.max_samples = max_spp;
      if (target > 0) options.relative_error = target;
      if (roulette >= 0) {
        options.noise_sigma = sensor_sigma;
        options.noise_factor = kNoiseFactor;
        options.relative_error = 0;
        options.shadow_roulette = roulette;
      }
      options.seed = o.seed;
      options.progress = false;
      RenderOutput out;
      const auto [s, repeats] = timed([&] { out = renderPathTraced(n.scene, options); }, o.repeats, o.cheap_seconds);
      const RadianceError e = radianceError(out, ref, split.clipped_variance);
      std::vector<std::string> row = head();
      row.insert(row.end(), {mode, lightSamplerName(kind), near_field ? "on" : "off", integer(min_spp), integer(max_spp),
                             target > 0 ? num(target) : "", roulette >= 0 ? num(kNoiseFactor) : "",
                             roulette >= 0 ? num(roulette) : "", num(metricDouble(out.report, "samples_per_pixel_mean")),
                             integer(repeats), seconds(s), num(metricDouble(out.report, "rays")), num(e.relative_rmse),
                             num(e.noise_corrected),
                             num(e.relative_rmse_unclipped), num(e.luminance_ratio), num(e.white), integer(reference_spp),
                             num(self.reference_noise), num(loadAverage1Min())});
      t.rows.push_back(row);
      say("[render] " + mode + " " + lightSamplerName(kind) + (near_field ? " with near field" : "") + " " +
          integer(min_spp) + "-" + integer(max_spp) +
          " spp" + (target > 0 ? " target " + num(target) : "") +
          (roulette >= 0 ? " noise target, shadow roulette " + num(roulette) : "") + ": " + seconds(s) +
          " s, relative RMSE " +
          num(e.relative_rmse));
    };
    const std::vector<int> power_spp = o.quick ? std::vector<int>{1, 4, 16} : std::vector<int>{1, 2, 4, 8, 16};
    for (int spp : power_spp) point("fixed", LightSamplerKind::Power, spp, spp, 0);
    const std::vector<int> other_spp = o.quick ? std::vector<int>{4} : std::vector<int>{4, 16};
    for (LightSamplerKind kind : {LightSamplerKind::Uniform, LightSamplerKind::Hierarchy})
      for (int spp : other_spp) point("fixed", kind, spp, spp, 0);
    struct Adaptive {
      int min_spp, max_spp;
      double target;
    };
    const std::vector<Adaptive> adaptive = o.quick ? std::vector<Adaptive>{{4, 16, 0.1}}
                                                   : std::vector<Adaptive>{{2, 8, 0.2}, {4, 16, 0.1}, {8, 32, 0.05}};
    for (const Adaptive& a : adaptive) point("adaptive", LightSamplerKind::Power, a.min_spp, a.max_spp, a.target);
    // A noise-matched target at 2-8 spp (the default preset stops at 4: docs/presets.md), shadow-ray
    // roulette off and on.
    const double preset_roulette = NightConversionOptions{}.render.shadow_roulette;
    const std::vector<double> roulettes = o.quick ? std::vector<double>{0, preset_roulette}
                                                  : std::vector<double>{0, 0.1, preset_roulette, 1};
    for (double roulette : roulettes) point("noise_target", LightSamplerKind::Power, 2, 8, 0, roulette);
    // With near-field light selection (PathTracerOptions::near_field_lights; off in solo night's
    // presets, whose settings the rows above are), what it buys.
    for (LightSamplerKind kind : {LightSamplerKind::Power, LightSamplerKind::Hierarchy}) {
      if (o.quick && kind == LightSamplerKind::Hierarchy) continue;
      for (int spp : other_spp) point("fixed", kind, spp, spp, 0, -1, true);
    }
    if (!o.quick) point("noise_target", LightSamplerKind::Power, 2, 8, 0, preset_roulette, true);
    t.notes.push_back("the night scene of the default refinement, mesh and lights (seed " +
                      integer(static_cast<std::int64_t>(o.seed)) + "); reference: " + integer(reference_spp) +
                      " spp, power sampler, the average of two independent halves (seeds " +
                      integer(static_cast<std::int64_t>(o.seed + kReferenceSeedOffset)) + " and " +
                      integer(static_cast<std::int64_t>(o.seed + 2 * kReferenceSeedOffset)) + "), " +
                      seconds(reference_s) + " s, its own relative noise " + num(self.reference_noise) +
                      " (of the clipped reference, from the halves' difference)");
    t.notes.push_back("relative_rmse: of the luminance Y over the " + integer(self.pixels) +
                      " non-emitting pixels, both images clipped at the reference's auto-exposure white (" +
                      num(self.white) + " cd/m2, what the final image maps to white); relative_rmse_noise_corrected "
                      "removes the clipped reference's own variance (per pixel ((min(a, W) - min(b, W)) / 2)^2 of its "
                      "halves a and b) from the squared error; relative_rmse_unclipped is dominated by fireflies");
    t.notes.push_back("adaptive rows: a relative-error target alone, which the tracer meets with its image-error "
                      "rule (AdaptiveRule::ImageError); noise_target rows: the sensor-noise target at the default "
                      "preset's noise_factor");
    return t;
  }

  // ---- end to end ---------------------------------------------------------------------------

  /// The converged render the end-to-end settings are measured against.
  struct EndToEndReference {
    SplitReference split;  ///< the image, and its clipped variance from its two halves
    RadianceError self;    ///< of the image against itself: its clipping white and own noise
    double seconds = 0;
  };

  /// The reference: the exact depth and instances for the mesh and the lights' geometry, the
  /// same material maps and light draws as the pipeline (so that the error is what geometry and
  /// rendering settings cause), rendered to convergence.
  EndToEndReference endToEndReference() {
    say("[end_to_end] reference from the exact depth ...");
    const DepthRefinementResult& p = refinementPrefix();
    StageReport ignored;
    const DepthMesh truth_depth_mesh = meshFromScene(truth.depth_m, truth.camera, truth.instances, cv::Mat(),
                                                     meshOptions(true, HoleFillOptions{}.max_fair_vertices, true), ignored);
    const LightStageResult truth_lights = runLightStage(scene, truth.depth_m, lightOptions());
    const NightScene truth_night =
        buildNightScene(truth_depth_mesh, p.maps.albedo, p.maps.roughness, scene.image, truth_lights.record, {},
                        truth.normals);
    EndToEndReference ref;
    ref.split = splitReference(truth_night.scene, ref.seconds);
    ref.self = radianceError(ref.split.image, ref.split.image, ref.split.clipped_variance);
    say("[end_to_end] reference: " + seconds(ref.seconds) + " s (" + integer(splitReferenceSpp()) + " spp in two halves)");
    return ref;
  }

  /// The presets of `solo night` (draft, default, final); where the default reduces the image's
  /// size, default at the full size and with bilinear upsampling; default with one stage or
  /// technique off.
  std::vector<PipelineSetting> endToEndSettings() const {
    std::vector<PipelineSetting> settings;
    for (const std::string& preset : nightPresetNames())
      if (!o.quick || preset != "final") settings.push_back(presetSetting(preset));
    const PipelineSetting standard = presetSetting("default");
    // Above a megapixel the default meshes and renders at a reduced size: the full size's row
    // is what that costs.
    if (resolveDownsample(standard.night.render_downsample, scene.width(), scene.height()) > 1 ||
        resolveDownsample(standard.night.mesh_downsample, scene.width(), scene.height()) > 1) {
      PipelineSetting full_size = standard;
      full_size.name = "default_full_size";
      full_size.night.mesh_downsample = full_size.night.render_downsample = 1;
      settings.push_back(full_size);
      PipelineSetting bilinear = standard;
      bilinear.name = "default_bilinear_upsampling";
      bilinear.night.upsample.texture = false;
      settings.push_back(bilinear);
    }
    if (!o.quick) {
      PipelineSetting no_refine = standard;
      no_refine.name = "default_no_refine";
      no_refine.night.refine = false;
      settings.push_back(no_refine);
      PipelineSetting no_solids = standard;
      no_solids.name = "default_no_solids";
      no_solids.night.mesh.close_solids = false;
      settings.push_back(no_solids);
      PipelineSetting by_face = standard;
      by_face.name = "default_no_pixel_texture";
      by_face.night.render.pixel_texture = false;
      settings.push_back(by_face);
    }
    return settings;
  }

  /// Seconds of the stages of one pipeline run; the render's include the exposure preview of
  /// the noise-matched target.
  struct StageSeconds {
    double pipeline = 0, refine = 0, mesh = 0, lights = 0, scene = 0, render = 0, post = 0;
  };
  static StageSeconds stageSeconds(const NightConversionResult& r, double pipeline_s) {
    StageSeconds out;
    out.pipeline = pipeline_s;
    for (const StageReport& step : r.refined.steps) out.refine += step.seconds;
    for (const StageReport& stage : r.stages) {
      if (stage.name == "mesh") out.mesh = stage.seconds;
      if (stage.name == "lights") out.lights = stage.seconds;
      if (stage.name == "scene") out.scene = stage.seconds;
      if (stage.name == "post") out.post = stage.seconds;
    }
    out.render = std::max(0.0, pipeline_s - out.refine - out.mesh - out.lights - out.scene - out.post);
    return out;
  }

  /// Runs the pipeline at setting `s` (the sweep's seed and illuminant table set): its row.
  std::vector<std::string> endToEndRow(PipelineSetting& s, const EndToEndReference& ref) {
    say("[end_to_end] " + s.name + " ...");
    s.night.seed = o.seed;
    s.night.lights.illuminant_table = o.illuminant_table;
    Stopwatch clock;
    NightConversionCallbacks quiet;
    quiet.render_progress = false;
    const NightConversionResult r = runNightConversion(scene, s.night, quiet);
    const StageSeconds time_s = stageSeconds(r, clock.seconds());
    const double total_s = o.input_seconds + time_s.pipeline;
    const RadianceError e = radianceError(r.rendered, ref.split.image, ref.split.clipped_variance);
    DepthEvaluationInput d;
    d.prediction_m = r.refined.depth_m;
    d.ground_truth_m = truth.depth_m;
    const DepthMetrics dm = evaluateDepth(d);

    const NightConversionOptions& n = s.night;
    const bool optimized = n.refine && n.refinement.optimize;
    std::vector<std::string> row = head();
    row.insert(row.end(),
               {s.name, boolean(n.refine), integer(optimized ? n.refinement.optimization.max_iterations : 0),
                num(n.refinement.optimization.function_tolerance), boolean(n.mesh.fill_holes),
                integer(n.mesh.hole_filling.max_fair_vertices), boolean(n.mesh.close_solids),
                lightSamplerName(n.render.light_sampler), integer(n.render.min_samples),
                integer(n.render.max_samples), num(n.render.relative_error), boolean(n.noise_target),
                num(n.render.noise_factor), integer(resolveDownsample(n.mesh_downsample, scene.width(), scene.height())),
                integer(resolveDownsample(n.render_downsample, scene.width(), scene.height())), seconds(total_s), seconds(o.input_seconds), seconds(time_s.refine),
                seconds(time_s.mesh), seconds(time_s.lights), seconds(time_s.scene), seconds(time_s.render),
                seconds(time_s.post), num(metricDouble(r.rendered.report, "samples_per_pixel_mean")),
                num(dm.abs_rel), num(e.relative_rmse), num(e.noise_corrected), num(e.relative_rmse_unclipped),
                num(e.luminance_ratio), num(e.white), integer(splitReferenceSpp()), num(ref.self.reference_noise),
                num(loadAverage1Min())});
    say("[end_to_end] " + s.name + ": " + seconds(total_s) + " s (refine " + seconds(time_s.refine) + ", mesh " +
        seconds(time_s.mesh) + ", render " + seconds(time_s.render) + "), relative RMSE " + num(e.relative_rmse));
    return row;
  }

  SweepTable endToEndSweep() {
    SweepTable t;
    t.stage = "end_to_end";
    t.columns = {"seed",           "width",           "height",          "setting",
                 "refine",         "refine_iterations", "refine_tolerance", "fill_holes",
                 "max_fair_vertices", "close_solids",  "light_sampler",   "min_spp",
                 "max_spp",        "relative_error_target", "noise_target", "noise_factor",
                 "mesh_downsample", "render_downsample", "seconds", "input_seconds",
                 "refine_seconds", "mesh_seconds",    "lights_seconds",  "scene_seconds",
                 "render_seconds", "post_seconds",    "mean_spp",        "depth_abs_rel",
                 "relative_rmse",  "relative_rmse_noise_corrected", "relative_rmse_unclipped", "luminance_ratio",
                 "white_cd_m2",    "reference_spp",   "reference_relative_noise", "load_1min"};
    const EndToEndReference ref = endToEndReference();
    for (PipelineSetting& s : endToEndSettings()) t.rows.push_back(endToEndRow(s, ref));
    t.notes.push_back(
        "each setting runs refine -> mesh -> lights -> night scene -> render -> post once, as solo night does "
        "(the scene read once, its time added as input_seconds); the error is the relative RMSE of the linear render's "
        "luminance over the pixels that show no emitter, against a reference made from the exact depth and instances "
        "(mesh and light geometry) with the same material maps and light draws, rendered at " +
        integer(splitReferenceSpp()) + " spp as two independent halves (power sampler, seeds " +
        integer(static_cast<std::int64_t>(o.seed + kReferenceSeedOffset)) + " and " +
        integer(static_cast<std::int64_t>(o.seed + 2 * kReferenceSeedOffset)) + ", " + seconds(ref.seconds) +
        " s, its own relative noise " + num(ref.self.reference_noise) + " (of the clipped reference, from the halves' difference))");
    return t;
  }
};

AccuracySweep::AccuracySweep(Scene scene, Scene truth, TriangleMesh truth_mesh, AccuracySweepOptions options)
    : impl_(std::make_unique<Impl>()) {
  impl_->scene = std::move(scene);
  impl_->refine_scene = sceneForRefinement(impl_->scene);
  impl_->truth = std::move(truth);
  impl_->truth_mesh = std::move(truth_mesh);
  impl_->o = std::move(options);
}
AccuracySweep::~AccuracySweep() = default;

SweepTable AccuracySweep::refine() { return impl_->refineSweep(); }
SweepTable AccuracySweep::mesh() { return impl_->meshSweep(); }
SweepTable AccuracySweep::render() { return impl_->renderSweep(); }
SweepTable AccuracySweep::endToEnd() { return impl_->endToEndSweep(); }

}  // namespace solo
