// The evaluations of `solo eval depth|normals|mesh|scene`: the files read, the metrics of
// solo_geometry computed and laid out as the named fields of one record.

#include <solo/pipeline/evaluation.h>

#include <solo/core/error.h>
#include <solo/core/image_io.h>
#include <solo/core/option_checks.h>
#include <solo/core/report.h>
#include <solo/core/scene.h>
#include <solo/geometry/depth_mesh.h>
#include <solo/geometry/depth_metrics.h>
#include <solo/geometry/mesh_cleanup.h>
#include <solo/geometry/mesh_metrics.h>
#include <solo/geometry/normal_metrics.h>
#include <solo/geometry/spurious_faces.h>
#include <solo/geometry/triangle_mesh.h>
#include <solo/geometry/upsample_maps.h>
#include <solo/geometry/view_mesh_distances.h>

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cctype>
#include <fstream>
#include <map>
#include <string>
#include <vector>

namespace fs = std::filesystem;

namespace solo {
namespace {

using Field = EvaluationField;
using FieldValue = EvaluationValue;

FieldValue scaleOption(double scale_m_per_unit) {
  return scale_m_per_unit > 0 ? FieldValue(scale_m_per_unit) : FieldValue(std::monostate{});
}

cv::Mat readMask(const std::optional<fs::path>& mask) { return mask ? readLabels(*mask) : cv::Mat(); }

/// A record of several maps' metrics prefixes keys ("est_depth_") and table labels.
Field prefixed(const std::string& key_prefix, const std::string& label_prefix, Field f) {
  f.key = key_prefix + f.key;
  const std::size_t indent = f.label.find_first_not_of(' ');  // sub-rows stay indented
  f.label = f.label.substr(0, indent) + label_prefix + f.label.substr(indent);
  return f;
}

/// The fields of one depth evaluation; without `accounting`, only the scale and the metrics.
std::vector<Field> depthFields(const DepthMetrics& m, const std::string& key_prefix, const std::string& label_prefix,
                               bool accounting) {
  std::vector<Field> fields;
  if (accounting)
    fields = {{"pixels", "pixels", m.pixels, ""},
              {"masked_out", "  masked out", m.masked_out, ""},
              {"ground_truth_invalid", "  no ground truth", m.ground_truth_invalid, ""},
              {"outside_range", "  gt outside depth range", m.outside_range, ""},
              {"prediction_invalid", "  no prediction", m.prediction_invalid, ""},
              {"valid_pixels", "  valid (evaluated)", m.valid_pixels, ""}};
  const std::vector<Field> metrics = {{"scale", "scale applied to prediction", m.scale, ""},
                                      {"abs_rel", "AbsRel", m.abs_rel, ""},
                                      {"sq_rel_m", "SqRel", m.sq_rel_m, "m"},
                                      {"rmse_m", "RMSE", m.rmse_m, "m"},
                                      {"rmse_log", "RMSElog", m.rmse_log, ""},
                                      {"silog", "SILog", m.silog, ""},
                                      {"delta1", "delta < 1.25", m.delta1, ""},
                                      {"delta2", "delta < 1.25^2", m.delta2, ""},
                                      {"delta3", "delta < 1.25^3", m.delta3, ""}};
  fields.insert(fields.end(), metrics.begin(), metrics.end());
  for (Field& f : fields) f = prefixed(key_prefix, label_prefix, f);
  return fields;
}

std::vector<Field> normalFields(const NormalMetrics& m, const std::string& key_prefix,
                                const std::string& label_prefix) {
  std::vector<Field> fields = {{"pixels", "pixels", m.pixels, ""},
                               {"masked_out", "  masked out", m.masked_out, ""},
                               {"ground_truth_invalid", "  no ground truth", m.ground_truth_invalid, ""},
                               {"prediction_invalid", "  no prediction", m.prediction_invalid, ""},
                               {"valid_pixels", "  valid (evaluated)", m.valid_pixels, ""},
                               {"mean_deg", "mean angle", m.mean_deg, "deg"},
                               {"median_deg", "median angle", m.median_deg, "deg"},
                               {"rmse_deg", "RMSE angle", m.rmse_deg, "deg"}};
  const char* const threshold_keys[] = {"under_5_deg", "under_7_5_deg", "under_11_25_deg", "under_22_5_deg",
                                        "under_30_deg"};
  const char* const threshold_labels[] = {"share < 5 deg", "share < 7.5 deg", "share < 11.25 deg", "share < 22.5 deg",
                                          "share < 30 deg"};
  for (std::size_t t = 0; t < kNormalAngleThresholdsDeg.size(); ++t)
    fields.push_back({threshold_keys[t], threshold_labels[t], m.share_under[t], ""});
  for (Field& f : fields) f = prefixed(key_prefix, label_prefix, f);
  return fields;
}

std::vector<Field> meshFields(const MeshMetrics& m, const MeshReadStats& read_stats,
                              const std::optional<MeshDistances>& d, const std::string& key_prefix,
                              const std::string& label_prefix) {
  const auto quality = [&m](double TriangleQuality::*field) {
    return m.quality ? FieldValue((*m.quality).*field) : FieldValue(std::monostate{});
  };
  const auto distance = [&d](auto MeshDistances::*field) {
    return d ? FieldValue((*d).*field) : FieldValue(std::monostate{});
  };
  std::vector<Field> fields = {
      {"vertices", "vertices", m.vertices, ""},
      {"faces", "faces (triangles)", m.faces, ""},
      {"polygons_triangulated", "  polygons fan-split on read", read_stats.polygons_triangulated, ""},
      {"faces_dropped", "  faces dropped on read", read_stats.faces_dropped, ""},
      {"unreferenced_vertices", "unreferenced vertices", m.unreferenced_vertices, ""},
      {"degenerate_faces", "degenerate faces", m.degenerate_faces, ""},
      {"edges", "edges", m.edges, ""},
      {"euler_characteristic", "Euler characteristic V-E+F", m.euler_characteristic, ""},
      {"components", "connected components", m.components, ""},
      {"closed", "closed (watertight)", isWatertight(m), ""},
      {"open_because", "  what keeps it open", isWatertight(m) ? std::string("nothing") : watertightDefects(m), ""},
      {"no_boundary", "  no boundary edge", m.closed, ""},
      {"boundary_loops", "boundary loops", m.boundary_loops, ""},
      {"boundary_edges", "boundary edges", m.boundary_edges, ""},
      {"non_manifold_edges", "non-manifold edges", m.non_manifold_edges, ""},
      {"non_manifold_vertices", "non-manifold vertices", m.non_manifold_vertices, ""},
      {"self_intersecting_pairs", "self-intersecting face pairs", m.self_intersecting_pairs, ""},
      {"self_intersecting_faces", "self-intersecting faces", m.self_intersecting_faces, ""},
      {"self_intersection_check", "  checked as", std::string(selfIntersectionCheckName(m.self_intersection_check)),
       ""},
      {"min_angle_deg", "minimum angle", quality(&TriangleQuality::min_angle_deg), "deg"},
      {"aspect_ratio_min", "aspect ratio min", quality(&TriangleQuality::aspect_ratio_min), ""},
      {"aspect_ratio_median", "aspect ratio median", quality(&TriangleQuality::aspect_ratio_median), ""},
      {"aspect_ratio_p95", "aspect ratio p95", quality(&TriangleQuality::aspect_ratio_p95), ""},
      {"aspect_ratio_max", "aspect ratio max", quality(&TriangleQuality::aspect_ratio_max), ""},
      {"hausdorff_to_ref", "Hausdorff mesh -> ref", distance(&MeshDistances::hausdorff_to_reference), ""},
      {"hausdorff_from_ref", "Hausdorff ref -> mesh", distance(&MeshDistances::hausdorff_from_reference), ""},
      {"hausdorff", "Hausdorff (symmetric)", distance(&MeshDistances::hausdorff), ""},
      {"mean_to_ref", "mean distance mesh -> ref", distance(&MeshDistances::mean_to_reference), ""},
      {"mean_from_ref", "mean distance ref -> mesh", distance(&MeshDistances::mean_from_reference), ""},
      {"chamfer", "Chamfer", distance(&MeshDistances::chamfer), ""},
      {"fscore_tau", "F-score threshold tau", distance(&MeshDistances::tau), ""},
      {"fscore_tau_relative", "  tau / ref bounding-box diagonal",
       d ? FieldValue(d->tau / d->reference_bbox_diagonal) : FieldValue(std::monostate{}), ""},
      {"precision", "precision (mesh within tau of ref)", distance(&MeshDistances::precision), ""},
      {"recall", "recall (ref within tau of mesh)", distance(&MeshDistances::recall), ""},
      {"fscore", "F-score", distance(&MeshDistances::f_score), ""},
      {"ref_bbox_diagonal", "ref bounding-box diagonal", distance(&MeshDistances::reference_bbox_diagonal), ""},
      {"mesh_vertices_checked", "mesh vertices checked", distance(&MeshDistances::mesh_vertices_checked), ""},
      {"ref_vertices_checked", "ref vertices checked", distance(&MeshDistances::reference_vertices_checked), ""}};
  for (Field& f : fields) f = prefixed(key_prefix, label_prefix, f);
  return fields;
}

/// The view-based split of a depth mesh's distance to the true surfaces (view_mesh_distances.h):
/// relative distance, area and distance per depth band, and the true visible surface covered.
std::vector<Field> viewMeshFields(const std::optional<ViewMeshDistances>& d) {
  const std::vector<double> edges = ViewMeshDistanceOptions{}.depth_band_edges_m;
  auto value = [&](auto get) -> FieldValue { return d ? FieldValue(get(*d)) : FieldValue(std::monostate{}); };
  std::vector<Field> fields = {
      {"mesh_area_m2", "mesh area", value([](const ViewMeshDistances& v) { return v.area_m2; }), "m^2"},
      {"mesh_mean_relative_to_ref", "mesh mean distance mesh -> ref / depth",
       value([](const ViewMeshDistances& v) { return v.mean_relative_to_truth; }), ""},
      {"mesh_truth_mean_relative_to_mesh", "mesh mean distance true pixel -> mesh / depth",
       value([](const ViewMeshDistances& v) { return v.truth_mean_relative_to_mesh; }), ""},
      {"mesh_truth_covered", "mesh true pixels covered (within 5 % of depth)",
       value([](const ViewMeshDistances& v) { return v.truth_covered; }), ""}};
  for (std::size_t b = 0; b <= edges.size(); ++b) {
    const std::string lo = b == 0 ? "0" : std::to_string(static_cast<int>(edges[b - 1]));
    const std::string hi = b == edges.size() ? "up" : std::to_string(static_cast<int>(edges[b]));
    const std::string key = "mesh_z_" + lo + "_" + hi + "_";
    const std::string label = "  depth " + lo + (b == edges.size() ? " m and beyond" : "-" + hi + " m") + ": ";
    fields.push_back({key + "area_share", label + "mesh area share",
                      value([b](const ViewMeshDistances& v) { return v.by_depth[b].area_share; }), ""});
    fields.push_back({key + "mean_to_ref", label + "mean distance mesh -> ref",
                      value([b](const ViewMeshDistances& v) { return v.by_depth[b].mean_m; }), ""});
    fields.push_back({key + "contribution_to_mean", label + "share of the mean distance",
                      value([b](const ViewMeshDistances& v) { return v.by_depth[b].contribution_m; }), ""});
    fields.push_back({key + "truth_covered", label + "true pixels covered",
                      value([b](const ViewMeshDistances& v) { return v.truth_covered_by_depth[b]; }), ""});
  }
  return fields;
}

/// The same fields without values: a part of a record that did not run keeps its columns.
std::vector<Field> blanked(std::vector<Field> fields) {
  for (Field& f : fields) f.value = std::monostate{};
  return fields;
}

}  // namespace

void validateDepthFilesEvaluationOptions(const DepthFilesEvaluationOptions& o) {
  if (o.list && (!o.prediction.empty() || !o.ground_truth.empty()))
    throw InputError("--list", "replaces --pred and --gt: give either the list or both of them");
  if (!o.list && o.prediction.empty()) throw InputError("--pred", "required (or --list)");
  if (!o.list && o.ground_truth.empty()) throw InputError("--gt", "required (or --list)");
  if (o.min_depth_m) requireOptionInRange(*o.min_depth_m, 0, 1e9, "--min-depth");
  if (o.max_depth_m) requireOptionInRange(*o.max_depth_m, 0, 1e9, "--max-depth");
  if (o.min_depth_m && o.max_depth_m && !(*o.min_depth_m < *o.max_depth_m))
    throw InputError("--min-depth", "must be below --max-depth, got " + std::to_string(*o.min_depth_m) + " and " +
                                        std::to_string(*o.max_depth_m) + " m");
  requireOptionInRange(o.prediction_scale_m_per_unit, 0, 1e6, "--pred-scale");
  requireOptionInRange(o.ground_truth_scale_m_per_unit, 0, 1e6, "--gt-scale");
}

namespace {

/// The metrics of one prediction file against one ground-truth file, with the options' range,
/// scaling and file scales.
DepthMetrics measureDepthFiles(const DepthFilesEvaluationOptions& o, const fs::path& prediction,
                               const fs::path& ground_truth, const std::optional<fs::path>& mask) {
  DepthEvaluationInput input;
  input.prediction_m = readDepth(prediction, o.prediction_scale_m_per_unit);
  input.ground_truth_m = readDepth(ground_truth, o.ground_truth_scale_m_per_unit);
  input.mask = readMask(mask);
  input.prediction_file = prediction;
  input.ground_truth_file = ground_truth;
  if (mask) input.mask_file = *mask;
  DepthMetricsOptions options;
  options.min_depth_m = o.min_depth_m;
  options.max_depth_m = o.max_depth_m;
  options.median_scaling = o.median_scaling;
  options.clamp_prediction = o.clamp_prediction;
  return evaluateDepth(input, options);
}

/// The option fields of a depth evaluation, single or dataset.
std::vector<Field> depthOptionFields(const DepthFilesEvaluationOptions& o) {
  return {
      {"min_depth_m", "min depth (gt >)", optionalNumberValue(o.min_depth_m), "m"},
      {"max_depth_m", "max depth (gt <)", optionalNumberValue(o.max_depth_m), "m"},
      {"median_scaling", "median scaling", o.median_scaling, ""},
      {"clamp_prediction", "clamp prediction", o.clamp_prediction, ""},
      {"prediction_scale_m_per_unit", "prediction file scale", scaleOption(o.prediction_scale_m_per_unit), "m/unit"},
      {"ground_truth_scale_m_per_unit", "ground-truth file scale", scaleOption(o.ground_truth_scale_m_per_unit),
       "m/unit"}};
}

}  // namespace

EvaluationRecord evaluateDepthFiles(const DepthFilesEvaluationOptions& o) {
  validateDepthFilesEvaluationOptions(o);
  Stopwatch clock;
  const DepthMetrics m = measureDepthFiles(o, o.prediction, o.ground_truth, o.mask);
  EvaluationRecord r;
  r.command = "eval depth";
  r.inputs = {{"prediction", "prediction", o.prediction.string(), ""},
              {"ground_truth", "ground truth", o.ground_truth.string(), ""},
              {"mask", "mask", optionalPathValue(o.mask), ""}};
  r.options = depthOptionFields(o);
  r.metrics = depthFields(m, "", "", true);
  r.seconds = clock.seconds();
  return r;
}

// ---- a depth dataset: two folders or a list of pairs ----------------------------------------

namespace {

/// One image of a dataset: its files, or why they could not be paired.
struct DepthPair {
  std::string image;  ///< the ground truth's stem (folders) or LIST:LINE (list)
  fs::path prediction, ground_truth;
  std::optional<fs::path> mask;
  std::string problem;  ///< "<file>: <problem>" when the pair cannot be evaluated; empty otherwise
};

bool isDepthFileName(const fs::path& file) {
  std::string ext = file.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext == ".png" || ext == ".exr" || ext == ".tif" || ext == ".tiff" || ext == ".pfm" || ext == ".npy";
}

/// A folder's depth files (.png .exr .tif .tiff .pfm .npy) by stem, each stem's files sorted.
std::map<std::string, std::vector<fs::path>> depthFilesByStem(const fs::path& folder) {
  std::map<std::string, std::vector<fs::path>> files;
  for (const fs::directory_entry& entry : fs::directory_iterator(folder))
    if (entry.is_regular_file() && isDepthFileName(entry.path()))
      files[entry.path().stem().string()].push_back(entry.path());
  for (auto& [stem, paths] : files) std::sort(paths.begin(), paths.end());
  return files;
}

/// The one file of `stem` in `files` (of `folder`), or none with `problem` set.
std::optional<fs::path> fileOfStem(const std::map<std::string, std::vector<fs::path>>& files, const std::string& stem,
                                   const fs::path& folder, const char* what, const fs::path& for_file,
                                   std::string& problem) {
  const auto found = files.find(stem);
  if (found == files.end()) {
    if (problem.empty()) problem = for_file.string() + ": no " + what + " named " + stem + ".* in " + folder.string();
    return std::nullopt;
  }
  if (found->second.size() > 1) {
    if (problem.empty())
      problem = found->second[0].string() + ": " + found->second[1].string() + " has the same stem (which " + what +
                " is meant?)";
    return std::nullopt;
  }
  return found->second[0];
}

/// Pairs from a prediction and a ground-truth folder, matched by stem; every ground-truth file
/// is an image. Counts the predictions no ground truth has.
std::vector<DepthPair> pairsFromFolders(const DepthFilesEvaluationOptions& o, std::int64_t& unpaired_predictions) {
  std::error_code ec;
  if (!fs::is_directory(o.ground_truth, ec))
    throw InputError(o.ground_truth, "not a folder, and --pred " + o.prediction.string() + " is one");
  const auto predictions = depthFilesByStem(o.prediction);
  const auto truths = depthFilesByStem(o.ground_truth);
  if (truths.empty()) throw InputError(o.ground_truth, "no depth file (.png .exr .tif .tiff .pfm .npy) in the folder");
  const bool mask_folder = o.mask && fs::is_directory(*o.mask, ec);
  const auto masks = mask_folder ? depthFilesByStem(*o.mask) : std::map<std::string, std::vector<fs::path>>{};
  std::vector<DepthPair> pairs;
  for (const auto& [stem, files] : truths) {
    DepthPair pair;
    pair.image = stem;
    pair.ground_truth = files[0];
    if (files.size() > 1)
      pair.problem = files[0].string() + ": " + files[1].string() + " has the same stem (which ground truth is meant?)";
    pair.prediction =
        fileOfStem(predictions, stem, o.prediction, "prediction", files[0], pair.problem).value_or(o.prediction / stem);
    pair.mask = mask_folder ? fileOfStem(masks, stem, *o.mask, "mask", files[0], pair.problem) : o.mask;
    pairs.push_back(pair);
  }
  unpaired_predictions = 0;
  for (const auto& [stem, files] : predictions) unpaired_predictions += truths.count(stem) ? 0 : 1;
  return pairs;
}

/// A list line's fields: split at tabs when it holds one (paths with spaces), else at spaces.
std::vector<std::string> listFields(const std::string& line) {
  const char* separators = line.find('\t') != std::string::npos ? "\t\r" : " \t\r";
  std::vector<std::string> fields;
  for (std::size_t begin = line.find_first_not_of(separators); begin != std::string::npos;) {
    const std::size_t end = line.find_first_of(separators, begin);
    const std::string field = line.substr(begin, end == std::string::npos ? std::string::npos : end - begin);
    const std::size_t first = field.find_first_not_of(' '), last = field.find_last_not_of(' ');
    if (first != std::string::npos) fields.push_back(field.substr(first, last - first + 1));
    begin = end == std::string::npos ? end : line.find_first_not_of(separators, end);
  }
  return fields;
}

/// Pairs from a list file: a line "PREDICTION GROUND_TRUTH [MASK]" per image, relative paths
/// taken from the list's folder, blank lines and lines starting with # skipped. A line with
/// another number of fields is an InputError naming the list and the line.
std::vector<DepthPair> pairsFromList(const fs::path& list, const std::optional<fs::path>& mask) {
  std::ifstream in(list);
  if (!in) throw InputError(list, "list of depth pairs not found");
  const auto resolved = [&list](const std::string& path) {
    const fs::path p = path;
    return p.is_absolute() ? p : list.parent_path() / p;
  };
  std::vector<DepthPair> pairs;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    const std::vector<std::string> fields = listFields(line);
    if (fields.empty() || fields[0][0] == '#') continue;
    if (fields.size() < 2 || fields.size() > 3)
      throw InputError(list, "line " + std::to_string(number) + " has " + std::to_string(fields.size()) +
                                 " fields, expected PREDICTION GROUND_TRUTH [MASK]");
    DepthPair pair;
    pair.image = list.string() + ":" + std::to_string(number);
    pair.prediction = resolved(fields[0]);
    pair.ground_truth = resolved(fields[1]);
    pair.mask = fields.size() == 3 ? std::optional<fs::path>(resolved(fields[2])) : mask;
    pairs.push_back(pair);
  }
  if (pairs.empty()) throw InputError(list, "the list names no pair");
  return pairs;
}

/// The summary's inputs: the folders or the list, and the mask.
std::vector<Field> datasetInputFields(const DepthFilesEvaluationOptions& o) {
  const auto given = [](const fs::path& p) {
    return p.empty() ? FieldValue(std::monostate{}) : FieldValue(p.string());
  };
  return {{"prediction", "prediction folder", given(o.prediction), ""},
          {"ground_truth", "ground-truth folder", given(o.ground_truth), ""},
          {"list", "list of pairs", optionalPathValue(o.list), ""},
          {"mask", "mask", optionalPathValue(o.mask), ""}};
}

/// The summary's metrics: counts, the summed pixel accounting, the mean per image and the
/// pooled metrics (none when no image was evaluated).
std::vector<Field> datasetMetricFields(const std::vector<DepthMetrics>& evaluated, std::int64_t pairs,
                                       std::int64_t unpaired_predictions) {
  const auto count = static_cast<std::int64_t>(evaluated.size());
  std::vector<Field> fields = {{"images", "images (pairs)", pairs, ""},
                               {"evaluated", "  evaluated", count, ""},
                               {"failed", "  failed", pairs - count, ""},
                               {"unpaired_predictions", "predictions without ground truth", unpaired_predictions, ""}};
  const DepthDatasetMetrics d = evaluated.empty() ? DepthDatasetMetrics{} : combineDepthMetrics(evaluated);
  std::vector<Field> accounting = depthFields(d.pooled, "", "", true);
  accounting.resize(6);  // the pixel counts, before the metrics
  std::vector<Field> metrics = accounting;
  const std::vector<Field> mean = depthFields(d.mean_per_image, "mean_", "mean per image: ", false);
  const std::vector<Field> pooled = depthFields(d.pooled, "pooled_", "pooled over pixels: ", false);
  metrics.insert(metrics.end(), mean.begin(), mean.end());
  metrics.insert(metrics.end(), pooled.begin(), pooled.end());
  if (evaluated.empty()) metrics = blanked(metrics);
  fields.insert(fields.end(), metrics.begin(), metrics.end());
  return fields;
}

/// One image's record: its files, the options, and its metrics or the error that stopped it.
EvaluationRecord imageRecord(const DepthFilesEvaluationOptions& o, const DepthPair& pair,
                             const std::optional<DepthMetrics>& m, const std::string& error) {
  EvaluationRecord r;
  r.command = "eval depth";
  r.inputs = {{"image", "image", pair.image, ""},
              {"prediction", "prediction", pair.prediction.string(), ""},
              {"ground_truth", "ground truth", pair.ground_truth.string(), ""},
              {"mask", "mask", optionalPathValue(pair.mask), ""}};
  r.options = depthOptionFields(o);
  r.metrics = {{"error", "error", error.empty() ? FieldValue(std::monostate{}) : FieldValue(error), ""}};
  const std::vector<Field> metrics =
      m ? depthFields(*m, "", "", true) : blanked(depthFields(DepthMetrics{}, "", "", true));
  r.metrics.insert(r.metrics.end(), metrics.begin(), metrics.end());
  return r;
}

}  // namespace

bool isDepthDataset(const DepthFilesEvaluationOptions& o) {
  std::error_code ec;
  return o.list.has_value() || fs::is_directory(o.prediction, ec);
}

DepthDatasetEvaluation evaluateDepthDataset(const DepthFilesEvaluationOptions& o) {
  validateDepthFilesEvaluationOptions(o);
  Stopwatch clock;
  std::int64_t unpaired_predictions = 0;
  const std::vector<DepthPair> pairs =
      o.list ? pairsFromList(*o.list, o.mask) : pairsFromFolders(o, unpaired_predictions);
  DepthDatasetEvaluation result;
  std::vector<DepthMetrics> evaluated;
  for (const DepthPair& pair : pairs) {
    Stopwatch image_clock;
    std::optional<DepthMetrics> m;
    std::string error = pair.problem;
    if (error.empty()) {
      try {
        m = measureDepthFiles(o, pair.prediction, pair.ground_truth, pair.mask);
        evaluated.push_back(*m);
      } catch (const InputError& e) {
        error = e.what();
      } catch (const fs::filesystem_error& e) {
        error = (e.path1().empty() ? std::string() : e.path1().string() + ": ") + e.code().message();
      }
    }
    if (!error.empty()) result.failures.push_back(error);
    result.images.push_back(imageRecord(o, pair, m, error));
    result.images.back().seconds = image_clock.seconds();
  }
  result.summary.command = "eval depth dataset";
  result.summary.inputs = datasetInputFields(o);
  result.summary.options = depthOptionFields(o);
  result.summary.metrics =
      datasetMetricFields(evaluated, static_cast<std::int64_t>(pairs.size()), unpaired_predictions);
  result.summary.seconds = clock.seconds();
  return result;
}

EvaluationRecord evaluateNormalFiles(const NormalFilesEvaluationOptions& o) {
  Stopwatch clock;
  NormalEvaluationInput input;
  input.prediction = readNormals(o.prediction);
  input.ground_truth = readNormals(o.ground_truth);
  input.mask = readMask(o.mask);
  input.prediction_file = o.prediction;
  input.ground_truth_file = o.ground_truth;
  if (o.mask) input.mask_file = *o.mask;
  const NormalMetrics m = evaluateNormals(input);

  EvaluationRecord r;
  r.command = "eval normals";
  r.inputs = {{"prediction", "prediction", o.prediction.string(), ""},
              {"ground_truth", "ground truth", o.ground_truth.string(), ""},
              {"mask", "mask", optionalPathValue(o.mask), ""}};
  r.metrics = normalFields(m, "", "");
  r.seconds = clock.seconds();
  return r;
}

EvaluationRecord evaluateMeshFile(const MeshFileEvaluationOptions& o) {
  if (o.tau_m) requireOptionAboveAndAtMost(*o.tau_m, 0, 1e9, "--tau");
  Stopwatch clock;
  MeshReadStats read_stats;
  const TriangleMesh mesh = readMesh(o.mesh, &read_stats);
  const MeshMetrics m = evaluateMesh(mesh);
  std::optional<MeshDistances> d;
  if (o.reference) {
    const TriangleMesh reference = readMesh(*o.reference);
    MeshDistanceOptions options;
    options.samples = o.samples;
    options.seed = o.seed;
    options.tau = o.tau_m;
    d = measureMeshDistances(mesh, reference, options, o.mesh, *o.reference);
  }
  EvaluationRecord r;
  r.command = "eval mesh";
  r.inputs = {{"mesh", "mesh", o.mesh.string(), ""}, {"reference", "reference", optionalPathValue(o.reference), ""}};
  r.options = {{"samples", "samples per direction", o.samples, ""},
               {"seed", "seed", static_cast<std::int64_t>(o.seed), ""},
               {"tau_m", "F-score tau (given)", optionalNumberValue(o.tau_m), "m"}};
  r.metrics = meshFields(m, read_stats, d, "", "");
  r.seconds = clock.seconds();
  return r;
}

// ---- a scene folder against its ground truth --------------------------------------------

namespace {

/// <folder>/<stem>.<what><extension>: the files `solo depth` writes beside its output.
fs::path besideOutput(const fs::path& output, const std::string& what, const std::string& extension) {
  return output.parent_path() / (output.stem().string() + "." + what + extension);
}

/// A file the caller names (it must exist: the reader says so otherwise), or the default when it
/// exists; none with `reason` set otherwise.
std::optional<fs::path> locate(const std::optional<fs::path>& given, const fs::path& fallback,
                               const std::string& how_to_make_it, std::string& reason) {
  if (given) return given;
  std::error_code ec;
  if (fs::exists(fallback, ec)) return fallback;
  reason = fallback.string() + " not found (" + how_to_make_it + ")";
  return std::nullopt;
}

/// A map of the image's size: as is, or resized by nearest neighbour (label maps).
cv::Mat nearestTo(const cv::Mat& map, cv::Size size) {
  if (map.empty() || map.size() == size) return map;
  cv::Mat out;
  cv::resize(map, out, size, 0, 0, cv::INTER_NEAREST);
  return out;
}

void append(std::vector<Field>& to, const std::vector<Field>& fields) {
  to.insert(to.end(), fields.begin(), fields.end());
}

FieldValue reasonValue(const std::string& reason) {
  return reason.empty() ? FieldValue(std::monostate{}) : FieldValue(reason);
}

/// A scene folder's estimated inputs and ground truth, checked: the truth at the image's size.
struct SceneUnderTest {
  fs::path manifest, truth_manifest;
  Scene scene, truth;
  cv::Size size;                ///< the image's: everything is compared at it
  std::string no_true_normals;  ///< why no normal can be scored; empty when they can
};

SceneUnderTest loadSceneUnderTest(const fs::path& scene_dir) {
  std::error_code ec;
  if (!fs::is_directory(scene_dir, ec)) throw InputError(scene_dir, "folder not found");
  SceneUnderTest t;
  t.manifest = scene_dir / "scene.json";
  if (!fs::exists(t.manifest, ec))
    throw InputError(t.manifest, "file not found: not a scene folder (`solo synth -o DIR` writes one)");
  t.scene = loadScene(t.manifest);
  t.truth_manifest = groundTruthManifest(t.manifest);
  if (!fs::exists(t.truth_manifest, ec))
    throw InputError(t.truth_manifest, "file not found (the ground truth " + t.manifest.string() + " names)");
  t.truth = loadScene(t.truth_manifest);

  // Everything is compared at the image resolution, the ground truth's.
  t.size = t.scene.image.size();
  if (t.truth.depth_m.size() != t.size)
    throw InputError(t.truth.manifest.depth, "ground-truth depth is " + std::to_string(t.truth.depth_m.cols) + "x" +
                                                 std::to_string(t.truth.depth_m.rows) + ", the image " +
                                                 std::to_string(t.size.width) + "x" + std::to_string(t.size.height));
  const bool truth_has_normals = !t.truth.normals.empty();
  if (truth_has_normals && t.truth.normals.size() != t.size)
    throw InputError(*t.truth.manifest.normals, "ground-truth normals are not of the image's size");
  t.no_true_normals = truth_has_normals ? "" : "the ground truth has no normals";
  return t;
}

/// The outputs written into a scene folder, each with the reason it is missing (empty when found).
struct SceneOutputs {
  std::optional<fs::path> refined, refined_normals, uncertain, mesh;
  std::string refined_reason, refined_normals_reason, uncertain_reason, mesh_reason, distance_reason;
  fs::path reference_mesh;  ///< the scene's exact mesh, gt/mesh.ply
  bool has_reference = false;
};

SceneOutputs locateSceneOutputs(const SceneFolderEvaluationOptions& o, const std::string& no_true_normals) {
  std::error_code ec;
  SceneOutputs s;
  s.refined = locate(o.refined, o.scene_dir / "refined.exr", "solo depth SCENE_DIR/scene.json -o SCENE_DIR/refined.exr",
                     s.refined_reason);
  if (s.refined) {
    const fs::path normals_file = besideOutput(*s.refined, "normals", s.refined->extension().string());
    if (fs::exists(normals_file, ec)) s.refined_normals = normals_file;
    else s.refined_normals_reason = normals_file.string() + " not found";
    const fs::path uncertain_file = besideOutput(*s.refined, "uncertain", ".png");
    if (fs::exists(uncertain_file, ec)) s.uncertain = uncertain_file;
    else s.uncertain_reason = uncertain_file.string() + " not found: uncertain criterion not applied";
  } else {
    s.refined_normals_reason = "no refined depth";
    s.uncertain_reason = "no refined depth: uncertain criterion not applied";
  }
  if (s.refined_normals_reason.empty() && !no_true_normals.empty()) s.refined_normals_reason = no_true_normals;
  s.mesh = locate(o.mesh, o.scene_dir / "mesh.ply", "solo mesh from-depth SCENE_DIR/scene.json -o SCENE_DIR/mesh.ply",
                  s.mesh_reason);
  s.reference_mesh = o.scene_dir / "gt" / "mesh.ply";
  s.has_reference = fs::exists(s.reference_mesh, ec);
  if (!s.mesh) s.distance_reason = "no mesh";
  else if (!s.has_reference) s.distance_reason = s.reference_mesh.string() + " not found";
  return s;
}

/// The record's inputs and options, and its first metrics: the image's size.
EvaluationRecord sceneRecord(const SceneFolderEvaluationOptions& o, const SceneUnderTest& t, const SceneOutputs& s) {
  EvaluationRecord r;
  r.command = "eval scene";
  r.inputs = {{"scene_dir", "scene folder", o.scene_dir.string(), ""},
              {"manifest", "estimated inputs", t.manifest.string(), ""},
              {"ground_truth", "ground truth", t.truth_manifest.string(), ""},
              {"refined", "refined depth", optionalPathValue(s.refined), ""},
              {"refined_normals", "refined normals", optionalPathValue(s.refined_normals), ""},
              {"uncertain", "uncertain mask", optionalPathValue(s.uncertain), ""},
              {"mesh", "mesh", optionalPathValue(s.mesh), ""},
              {"reference_mesh", "reference mesh",
               s.mesh && s.has_reference ? FieldValue(s.reference_mesh.string()) : FieldValue(std::monostate{}), ""}};
  r.options = {{"samples", "samples per direction", o.samples, ""},
               {"seed", "seed", static_cast<std::int64_t>(o.seed), ""}};
  r.metrics = {{"width", "image width", std::int64_t{t.size.width}, "px"},
               {"height", "image height", std::int64_t{t.size.height}, "px"}};
  return r;
}

/// Scores depth and normal maps against the ground truth into a record's metrics; a map that
/// is missing keeps its columns, without values.
struct MapScorer {
  const Scene& truth;
  std::vector<Field>& metrics;

  /// The metrics as given and median-scaled.
  void depth(const cv::Mat& prediction, const fs::path& prediction_file, const std::string& key,
             const std::string& label) {
    DepthEvaluationInput input;
    input.prediction_m = prediction;
    input.ground_truth_m = truth.depth_m;
    input.prediction_file = prediction_file;
    input.ground_truth_file = truth.manifest.depth;
    DepthMetricsOptions scaled;
    scaled.median_scaling = true;
    append(metrics, depthFields(evaluateDepth(input), key, label, true));
    append(metrics, depthFields(evaluateDepth(input, scaled), key + "median_scaled_", label + "median-scaled ", false));
  }
  void skipDepth(const std::string& key, const std::string& label) {
    append(metrics, blanked(depthFields(DepthMetrics{}, key, label, true)));
    append(metrics, blanked(depthFields(DepthMetrics{}, key + "median_scaled_", label + "median-scaled ", false)));
  }
  void normals(const cv::Mat& prediction, const fs::path& prediction_file, const std::string& key,
               const std::string& label) {
    NormalEvaluationInput input;
    input.prediction = prediction;
    input.ground_truth = truth.normals;
    input.prediction_file = prediction_file;
    input.ground_truth_file = *truth.manifest.normals;
    append(metrics, normalFields(evaluateNormals(input), key, label));
  }
  void skipNormals(const std::string& key, const std::string& label) {
    append(metrics, blanked(normalFields(NormalMetrics{}, key, label)));
  }
};

/// (a) The estimated maps, upsampled to the image resolution as depth refinement's first step
/// does; returns the upsampled depth.
cv::Mat appendEstimatedMaps(const SceneUnderTest& t, EvaluationRecord& r) {
  MapScorer score{t.truth, r.metrics};
  cv::Mat estimated_depth = resizeValidBilinear(t.scene.depth_m, t.size);
  score.depth(estimated_depth, t.scene.manifest.depth, "est_depth_", "est. depth ");
  std::string est_normals_reason = t.scene.normals.empty() ? "the manifest names no normals" : t.no_true_normals;
  r.metrics.push_back({"est_normals_skipped", "est. normals skipped", reasonValue(est_normals_reason), ""});
  if (est_normals_reason.empty())
    score.normals(resizeNormalsBilinear(t.scene.normals, t.size), *t.scene.manifest.normals, "est_normals_",
                  "est. normals ");
  else
    score.skipNormals("est_normals_", "est. normals ");
  return estimated_depth;
}

/// (b) The refined depth and the normals of it that `solo depth` wrote; returns the refined
/// depth (empty when there is none).
cv::Mat appendRefinedMaps(const SceneUnderTest& t, const SceneOutputs& s, EvaluationRecord& r) {
  MapScorer score{t.truth, r.metrics};
  cv::Mat refined_depth;
  r.metrics.push_back({"refined_skipped", "refined depth skipped", reasonValue(s.refined_reason), ""});
  if (s.refined) {
    refined_depth = readDepth(*s.refined, 0);
    score.depth(refined_depth, *s.refined, "refined_depth_", "refined depth ");
  } else {
    score.skipDepth("refined_depth_", "refined depth ");
  }
  r.metrics.push_back(
      {"refined_normals_skipped", "refined normals skipped", reasonValue(s.refined_normals_reason), ""});
  if (s.refined_normals_reason.empty())
    score.normals(readNormals(*s.refined_normals), *s.refined_normals, "refined_normals_", "refined normals ");
  else
    score.skipNormals("refined_normals_", "refined normals ");
  return refined_depth;
}

/// The spurious-face fields of the mesh of `depth` (at the image's size), scored against the
/// faces the exact depth and normals call spurious; without true normals, no values.
std::vector<Field> spuriousFaceFields(const SceneUnderTest& t, const cv::Mat& depth,
                                      const std::optional<fs::path>& uncertain) {
  DetectionScore occlusion_score, all_score;
  SpuriousFaceResult found;
  std::int64_t truth_faces = 0;
  if (t.no_true_normals.empty()) {
    const cv::Mat instances = nearestTo(t.scene.instances, t.size);
    cv::Mat uncertain_mask;
    if (uncertain) {
      readLabels(*uncertain).convertTo(uncertain_mask, CV_8U);
      uncertain_mask = nearestTo(uncertain_mask, t.size);
    }
    const DepthMesh mesh = meshFromDepth(depth, t.scene.camera, instances);
    found = findSpuriousFaces(mesh, depth, instances, uncertain_mask);
    const std::vector<std::uint8_t> truth_flags = spuriousFacesFromGroundTruth(mesh, t.truth.depth_m, t.truth.normals);
    std::vector<std::uint8_t> occlusion(found.criteria.size());
    for (std::size_t i = 0; i < occlusion.size(); ++i) occlusion[i] = (found.criteria[i] & kOcclusionCriteria) != 0;
    occlusion_score = scoreDetection(occlusion, truth_flags);
    all_score = scoreDetection(found.spurious, truth_flags);
    truth_faces = occlusion_score.true_positives + occlusion_score.false_negatives;
  }
  std::vector<Field> fields = {
      {"spurious_mesh_faces", "  depth-mesh faces", found.faces_checked, ""},
      {"spurious_truth_faces", "  spurious by ground truth", truth_faces, ""},
      {"spurious_removed", "  removed (all criteria)", found.removed, ""},
      {"spurious_by_depth_jump", "    by depth jump", found.by_depth_jump, ""},
      {"spurious_by_uncertain_mask", "    by uncertain mask", found.by_uncertain, ""},
      {"spurious_by_instance_boundary", "    by instance boundary", found.by_instance_boundary, ""},
      {"spurious_true_positives", "  true positives", occlusion_score.true_positives, ""},
      {"spurious_false_positives", "  false positives", occlusion_score.false_positives, ""},
      {"spurious_false_negatives", "  false negatives", occlusion_score.false_negatives, ""},
      {"spurious_precision", "spurious-face precision", occlusion_score.precision, ""},
      {"spurious_recall", "spurious-face recall", occlusion_score.recall, ""},
      {"removal_precision_with_instance_cut", "  precision with instance cut", all_score.precision, ""},
      {"removal_recall_with_instance_cut", "  recall with instance cut", all_score.recall, ""}};
  return t.no_true_normals.empty() ? fields : blanked(fields);
}

/// (c) Spurious faces of the depth mesh (refined depth, else the upsampled estimate), scored
/// against the faces the exact depth and normals call spurious, as `solo mesh from-depth --truth`.
void appendSpuriousFaces(const SceneUnderTest& t, const SceneOutputs& s, const cv::Mat& estimated_depth,
                         const cv::Mat& refined_depth, EvaluationRecord& r) {
  const bool from_refined = !refined_depth.empty();
  r.metrics.push_back({"spurious_skipped", "spurious faces skipped", reasonValue(t.no_true_normals), ""});
  r.metrics.push_back({"spurious_depth", "spurious faces: mesh of",
                       t.no_true_normals.empty()
                           ? FieldValue(std::string(from_refined ? "refined" : "estimated (upsampled)"))
                           : FieldValue(std::monostate{}),
                       ""});
  r.metrics.push_back({"spurious_uncertain_skipped", "  uncertain mask skipped", reasonValue(s.uncertain_reason), ""});
  const cv::Mat& depth = from_refined ? refined_depth : estimated_depth;
  const fs::path& depth_file = from_refined ? *s.refined : t.scene.manifest.depth;
  if (depth.size() != t.size)
    throw InputError(depth_file, "depth is " + std::to_string(depth.cols) + "x" + std::to_string(depth.rows) +
                                     ", the image " + std::to_string(t.size.width) + "x" +
                                     std::to_string(t.size.height));
  append(r.metrics, spuriousFaceFields(t, depth, s.uncertain));
}

/// (d) The mesh written into the folder, and its distances to the scene's exact mesh.
void appendMesh(const SceneFolderEvaluationOptions& o, const SceneUnderTest& t, const SceneOutputs& s,
                EvaluationRecord& r) {
  r.metrics.push_back({"mesh_skipped", "mesh skipped", reasonValue(s.mesh_reason), ""});
  r.metrics.push_back({"mesh_distances_skipped", "mesh distances skipped", reasonValue(s.distance_reason), ""});
  std::optional<ViewMeshDistances> view;
  if (s.mesh) {
    MeshReadStats read_stats;
    const TriangleMesh mesh = readMesh(*s.mesh, &read_stats);
    std::optional<MeshDistances> d;
    if (s.has_reference) {
      MeshDistanceOptions options;
      options.samples = o.samples;
      options.seed = o.seed;
      const TriangleMesh reference = readMesh(s.reference_mesh);
      d = measureMeshDistances(mesh, reference, options, *s.mesh, s.reference_mesh);
      ViewMeshDistanceOptions view_options;
      view_options.samples = o.samples;
      view_options.seed = o.seed;
      view = measureViewMeshDistances(mesh, {}, reference, t.truth.depth_m, t.truth.camera, view_options);
    }
    append(r.metrics, meshFields(evaluateMesh(mesh), read_stats, d, "mesh_", "mesh "));
  } else {
    append(r.metrics, blanked(meshFields(MeshMetrics{}, MeshReadStats{}, std::nullopt, "mesh_", "mesh ")));
  }
  append(r.metrics, viewMeshFields(view));
}

}  // namespace

EvaluationRecord evaluateSceneFolder(const SceneFolderEvaluationOptions& o) {
  Stopwatch clock;
  const SceneUnderTest t = loadSceneUnderTest(o.scene_dir);
  const SceneOutputs s = locateSceneOutputs(o, t.no_true_normals);
  EvaluationRecord r = sceneRecord(o, t, s);
  const cv::Mat estimated_depth = appendEstimatedMaps(t, r);
  const cv::Mat refined_depth = appendRefinedMaps(t, s, r);
  appendSpuriousFaces(t, s, estimated_depth, refined_depth, r);
  appendMesh(o, t, s, r);
  r.seconds = clock.seconds();
  return r;
}

}  // namespace solo
