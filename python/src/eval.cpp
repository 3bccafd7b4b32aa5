// The evaluations of `solo eval depth|normals|mesh|scene|night` (docs/evaluation.md): on files,
// the library's records as the dicts `--json` prints; depth and normals also on arrays.

#include "bindings.h"

#include <solo/core/error.h>
#include <solo/core/image_io.h>
#include <solo/geometry/depth_metrics.h>
#include <solo/geometry/normal_metrics.h>
#include <solo/pipeline/evaluation.h>
#include <solo/pipeline/night_evaluation.h>

#include <pybind11/stl.h>

#include <atomic>
#include <unistd.h>

namespace solo::python {

namespace {

bool isPath(const py::handle& value) { return py::isinstance<py::str>(value) || py::hasattr(value, "__fspath__"); }

/// A map argument: a file read by `read` (kept in `held`), or an array viewed as `dtype`.
template <typename Read>
cv::Mat mapArgument(const py::handle& value, const py::dtype& dtype, const std::string& what,
                    std::vector<py::object>& held, Read read) {
  if (isPath(value)) return read(toPath(value, what));
  const py::array array = asArray(value, dtype);
  held.push_back(array);
  return arrayToMat(array, what);
}

std::string fileName(const py::handle& value, const std::string& fallback) {
  return isPath(value) ? toPath(value, fallback).string() : fallback;
}

py::dict depthMetricsDict(const DepthMetrics& m) {
  py::dict d;
  d["pixels"] = m.pixels;
  d["masked_out"] = m.masked_out;
  d["ground_truth_invalid"] = m.ground_truth_invalid;
  d["outside_range"] = m.outside_range;
  d["prediction_invalid"] = m.prediction_invalid;
  d["valid_pixels"] = m.valid_pixels;
  d["scale"] = m.scale;
  d["abs_rel"] = m.abs_rel;
  d["sq_rel_m"] = m.sq_rel_m;
  d["rmse_m"] = m.rmse_m;
  d["rmse_log"] = m.rmse_log;
  d["delta1"] = m.delta1;
  d["delta2"] = m.delta2;
  d["delta3"] = m.delta3;
  return d;
}

py::dict normalMetricsDict(const NormalMetrics& m) {
  py::dict d;
  d["pixels"] = m.pixels;
  d["masked_out"] = m.masked_out;
  d["ground_truth_invalid"] = m.ground_truth_invalid;
  d["prediction_invalid"] = m.prediction_invalid;
  d["valid_pixels"] = m.valid_pixels;
  d["mean_deg"] = m.mean_deg;
  d["median_deg"] = m.median_deg;
  d["rmse_deg"] = m.rmse_deg;
  const char* const keys[] = {"under_5_deg", "under_7_5_deg", "under_11_25_deg", "under_22_5_deg", "under_30_deg"};
  for (std::size_t t = 0; t < kNormalAngleThresholdsDeg.size(); ++t) d[keys[t]] = m.share_under[t];
  return d;
}

py::dict evalDepth(const py::object& pred, const py::object& gt, const py::object& mask,
                   std::optional<double> min_depth, std::optional<double> max_depth, bool median_scale,
                   bool clamp_pred, double pred_scale, double gt_scale) {
  DepthFilesEvaluationOptions files;
  files.min_depth_m = min_depth;
  files.max_depth_m = max_depth;
  files.median_scaling = median_scale;
  files.clamp_prediction = clamp_pred;
  files.prediction_scale_m_per_unit = pred_scale;
  files.ground_truth_scale_m_per_unit = gt_scale;
  if (isPath(pred) && isPath(gt) && (mask.is_none() || isPath(mask))) {
    files.prediction = toPath(pred, "pred");
    files.ground_truth = toPath(gt, "gt");
    files.mask = toOptionalPath(mask, "mask");
    EvaluationRecord record;
    {
      const py::gil_scoped_release release;
      record = evaluateDepthFiles(files);
    }
    return recordToDict(record);
  }
  files.prediction = fileName(pred, "pred");  // the arrays' names: the ranges are checked as for files
  files.ground_truth = fileName(gt, "gt");
  validateDepthFilesEvaluationOptions(files);
  std::vector<py::object> held;
  DepthEvaluationInput input;
  input.prediction_m = mapArgument(pred, py::dtype::of<float>(), "pred", held,
                                   [&](const std::filesystem::path& f) { return readDepth(f, pred_scale); });
  input.ground_truth_m = mapArgument(gt, py::dtype::of<float>(), "gt", held,
                                     [&](const std::filesystem::path& f) { return readDepth(f, gt_scale); });
  if (!mask.is_none())
    input.mask = mapArgument(mask, py::dtype::of<std::uint8_t>(), "mask", held,
                             [](const std::filesystem::path& f) { return readLabels(f); });
  input.prediction_file = fileName(pred, "pred");
  input.ground_truth_file = fileName(gt, "gt");
  input.mask_file = fileName(mask, "mask");
  DepthMetricsOptions options;
  options.min_depth_m = min_depth;
  options.max_depth_m = max_depth;
  options.median_scaling = median_scale;
  options.clamp_prediction = clamp_pred;
  DepthMetrics metrics;
  {
    const py::gil_scoped_release release;
    metrics = evaluateDepth(input, options);
  }
  py::dict out;
  out["command"] = "eval depth";
  out["metrics"] = depthMetricsDict(metrics);
  return out;
}

py::dict evalNormals(const py::object& pred, const py::object& gt, const py::object& mask) {
  if (isPath(pred) && isPath(gt) && (mask.is_none() || isPath(mask))) {
    NormalFilesEvaluationOptions files;
    files.prediction = toPath(pred, "pred");
    files.ground_truth = toPath(gt, "gt");
    files.mask = toOptionalPath(mask, "mask");
    EvaluationRecord record;
    {
      const py::gil_scoped_release release;
      record = evaluateNormalFiles(files);
    }
    return recordToDict(record);
  }
  std::vector<py::object> held;
  const auto read = [](const std::filesystem::path& f) { return readNormals(f); };
  NormalEvaluationInput input;
  input.prediction = mapArgument(pred, py::dtype::of<float>(), "pred", held, read);
  input.ground_truth = mapArgument(gt, py::dtype::of<float>(), "gt", held, read);
  if (!mask.is_none())
    input.mask = mapArgument(mask, py::dtype::of<std::uint8_t>(), "mask", held,
                             [](const std::filesystem::path& f) { return readLabels(f); });
  input.prediction_file = fileName(pred, "pred");
  input.ground_truth_file = fileName(gt, "gt");
  input.mask_file = fileName(mask, "mask");
  NormalMetrics metrics;
  {
    const py::gil_scoped_release release;
    metrics = evaluateNormals(input);
  }
  py::dict out;
  out["command"] = "eval normals";
  out["metrics"] = normalMetricsDict(metrics);
  return out;
}

/// A mesh argument as a file: a path as given, or (vertices, faces) written to a temporary PLY
/// (removed when this goes) so that the record is the one `solo eval mesh` makes.
class MeshFile {
 public:
  MeshFile(const py::handle& value, const std::string& what) {
    if (isPath(value)) {
      path_ = toPath(value, what);
      return;
    }
    const py::tuple pair = py::reinterpret_borrow<py::object>(value).cast<py::tuple>();
    if (pair.size() != 2) throw py::type_error(what + ": expected a path or (vertices, faces)");
    static std::atomic<int> counter{0};
    path_ = std::filesystem::temp_directory_path() /
            ("solo-" + what + "-" + std::to_string(::getpid()) + "-" + std::to_string(counter++) + ".ply");
    writeMesh(path_, arraysToMesh(pair[0], pair[1]));
    temporary_ = true;
  }
  ~MeshFile() {
    std::error_code ec;
    if (temporary_) std::filesystem::remove(path_, ec);
  }
  MeshFile(const MeshFile&) = delete;
  MeshFile& operator=(const MeshFile&) = delete;
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
  bool temporary_ = false;
};

py::dict evalMesh(const py::object& mesh, const py::object& ref, std::int64_t samples, std::uint64_t seed) {
  const MeshFile mesh_file(mesh, "mesh");
  std::optional<MeshFile> ref_file;
  if (!ref.is_none()) ref_file.emplace(ref, "ref");
  MeshFileEvaluationOptions options;
  options.mesh = mesh_file.path();
  if (ref_file) options.reference = ref_file->path();
  options.samples = samples;
  options.seed = seed;
  if (samples < 1 || samples > 100000000) throw InputError("--samples", "must be within [1, 100000000]");
  EvaluationRecord record;
  {
    const py::gil_scoped_release release;
    record = evaluateMeshFile(options);
  }
  return recordToDict(record);
}

py::dict evalScene(const py::object& scene_dir, const py::object& refined, const py::object& mesh,
                   std::int64_t samples, std::uint64_t seed) {
  SceneFolderEvaluationOptions options;
  options.scene_dir = toPath(scene_dir, "scene_dir");
  options.refined = toOptionalPath(refined, "refined");
  options.mesh = toOptionalPath(mesh, "mesh");
  options.samples = samples;
  options.seed = seed;
  if (samples < 1 || samples > 100000000) throw InputError("--samples", "must be within [1, 100000000]");
  EvaluationRecord record;
  {
    const py::gil_scoped_release release;
    record = evaluateSceneFolder(options);
  }
  return recordToDict(record);
}

py::object optionalNumber(const std::optional<double>& v) { return v ? py::cast(*v) : py::none(); }

/// A statistic as `solo eval night --json` writes it: the blob count a whole number.
py::object statisticValue(const std::string& key, const std::optional<double>& v) {
  if (key == "halo_blobs" && v) return py::cast(static_cast<std::int64_t>(*v));
  return optionalNumber(v);
}

/// The dict `solo eval night --json` prints.
py::dict evalNight(const std::vector<py::object>& images, const py::object& reference) {
  NightEvaluationOptions options;
  for (const py::object& image : images) options.images.push_back(toPath(image, "images"));
  if (options.images.empty()) throw InputError("IMAGE", "no image to evaluate");
  options.reference = toOptionalPath(reference, "reference");
  NightEvaluation run;
  {
    const py::gil_scoped_release release;
    run = evaluateNightImages(options);
  }
  const std::vector<NamedNightStatistic> keys = namedNightStatistics(NightStatistics{});
  py::dict out;
  out["command"] = "eval night";
  out["reference"] = py::none();
  if (!run.ranges.empty()) {
    py::dict ref;
    ref["source"] = run.reference->string();
    py::list files;
    for (const auto& f : run.reference_files) files.append(f.string());
    ref["images"] = files;
    for (const auto& [name, field] : {std::pair{"median", &NightReferenceRange::median},
                                      {"min", &NightReferenceRange::min}, {"max", &NightReferenceRange::max}}) {
      py::dict values;
      for (std::size_t k = 0; k < keys.size(); ++k)
        values[py::str(keys[k].key)] = statisticValue(keys[k].key, run.ranges[k].*field);
      ref[name] = values;
    }
    out["reference"] = ref;
  }
  py::list list;
  for (std::size_t i = 0; i < run.files.size(); ++i) {
    const NightStatistics& s = run.statistics[i];
    py::dict image;
    image["file"] = run.files[i].string();
    image["width_px"] = s.source_width_px;
    image["height_px"] = s.source_height_px;
    py::dict statistics;
    for (const NamedNightStatistic& n : namedNightStatistics(s)) statistics[py::str(n.key)] = statisticValue(n.key, n.value);
    image["statistics"] = statistics;
    image["outside_reference"] =
        run.ranges.empty() ? py::object(py::none()) : py::cast(nightStatisticsOutsideRange(s, run.ranges));
    list.append(image);
  }
  out["images"] = list;
  out["seconds"] = run.seconds;
  return out;
}

}  // namespace

void bindEval(py::module_& m) {
  m.def("eval_depth", &evalDepth, py::arg("pred"), py::arg("gt"), py::kw_only(), py::arg("mask") = py::none(),
        py::arg("min_depth") = py::none(), py::arg("max_depth") = py::none(), py::arg("median_scale") = false,
        py::arg("clamp_pred") = false, py::arg("pred_scale") = 0.0, py::arg("gt_scale") = 0.0,
        "`solo eval depth`: AbsRel, SqRel, RMSE (m), RMSElog, delta < 1.25^k. Files: the record `--json` prints; "
        "arrays (metres): {command, metrics} with the same metric keys.");
  m.def("eval_normals", &evalNormals, py::arg("pred"), py::arg("gt"), py::kw_only(), py::arg("mask") = py::none(),
        "`solo eval normals`: angular errors (degrees) and shares under 5 ... 30 degrees. Files: the record; "
        "arrays: {command, metrics}.");
  m.def("eval_mesh", &evalMesh, py::arg("mesh"), py::kw_only(), py::arg("ref") = py::none(),
        py::arg("samples") = 100000, py::arg("seed") = 0,
        "`solo eval mesh`: topology, defects, triangle quality and with a reference the distances. A mesh is a "
        "file or (vertices, faces).");
  m.def("eval_scene", &evalScene, py::arg("scene_dir"), py::kw_only(), py::arg("refined") = py::none(),
        py::arg("mesh") = py::none(), py::arg("samples") = 100000, py::arg("seed") = 0,
        "`solo eval scene`: a `solo synth` folder's maps and outputs against its ground truth.");
  m.def("eval_night", &evalNight, py::arg("images"), py::kw_only(), py::arg("reference") = py::none(),
        "`solo eval night`: realism statistics of night image files, with a reference set its range.");
}

}  // namespace solo::python
