// `solo eval depth|normals|mesh`: reads the inputs, computes the metrics (solo_geometry) and
// writes one record three ways: a table on the terminal, JSON on stdout (--json), and a row
// appended to a CSV file (--csv). Every record of a command has the same fields in the same
// order, so rows of a sweep line up under one header.

#include "commands.h"

#include <solo/geometry/depth_metrics.h>
#include <solo/geometry/error.h>
#include <solo/geometry/image_io.h>
#include <solo/geometry/mesh_metrics.h>
#include <solo/geometry/normal_metrics.h>
#include <solo/geometry/report.h>
#include <solo/geometry/triangle_mesh.h>

#include <nlohmann/json.hpp>

#include <fcntl.h>
#include <unistd.h>
#include <cerrno>
#include <charconv>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <type_traits>
#include <variant>

namespace fs = std::filesystem;

namespace solo::tools {
namespace {

/// monostate = no value (an option not given, a metric that does not apply): JSON null, an
/// empty CSV cell, "none" in the table (metrics without a value are left out of it).
using FieldValue = std::variant<std::monostate, bool, std::int64_t, double, std::string>;

struct Field {
  std::string key;    ///< JSON key and CSV column
  std::string label;  ///< table label
  FieldValue value;
  std::string unit;  ///< table unit ("m", "deg", ...), empty for none
};

struct EvalRecord {
  std::string command;  ///< "eval depth", ...
  std::vector<Field> inputs, options, metrics;
  double seconds = 0;
};

FieldValue optionalPath(const std::optional<fs::path>& p) {
  return p ? FieldValue(p->string()) : FieldValue(std::monostate{});
}
FieldValue optionalNumber(const std::optional<double>& v) { return v ? FieldValue(*v) : FieldValue(std::monostate{}); }
FieldValue scaleOption(double scale_m_per_unit) {
  return scale_m_per_unit > 0 ? FieldValue(scale_m_per_unit) : FieldValue(std::monostate{});
}

// ---- output: JSON ---------------------------------------------------------------------

nlohmann::ordered_json toJson(const FieldValue& v) {
  return std::visit(
      [](const auto& x) -> nlohmann::ordered_json {
        if constexpr (std::is_same_v<std::decay_t<decltype(x)>, std::monostate>)
          return nullptr;
        else
          return x;
      },
      v);
}

std::string recordToJson(const EvalRecord& r) {
  nlohmann::ordered_json j;
  j["command"] = r.command;
  for (const auto& [section, fields] :
       {std::pair{"inputs", &r.inputs}, {"options", &r.options}, {"metrics", &r.metrics}}) {
    auto& object = j[section] = nlohmann::ordered_json::object();
    for (const Field& f : *fields) object[f.key] = toJson(f.value);
  }
  j["seconds"] = r.seconds;
  return j.dump(2) + "\n";
}

// ---- output: table --------------------------------------------------------------------

std::string tableValue(const FieldValue& v) {
  if (std::holds_alternative<std::monostate>(v)) return "none";
  if (const bool* b = std::get_if<bool>(&v)) return *b ? "yes" : "no";
  if (const std::int64_t* i = std::get_if<std::int64_t>(&v)) return std::to_string(*i);
  if (const double* d = std::get_if<double>(&v)) {
    char text[32];
    std::snprintf(text, sizeof text, "%.6g", *d);
    return text;
  }
  return std::get<std::string>(v);
}

std::string recordToTable(const EvalRecord& r) {
  std::string out = "solo " + r.command + "\n";
  const auto add_rows = [&out](const std::vector<Field>& fields, bool skip_missing) {
    for (const Field& f : fields) {
      if (skip_missing && std::holds_alternative<std::monostate>(f.value)) continue;
      char label[64];
      std::snprintf(label, sizeof label, "  %-30s ", f.label.c_str());
      const bool has_unit = !f.unit.empty() && !std::holds_alternative<std::monostate>(f.value);
      out += label + tableValue(f.value) + (has_unit ? " " + f.unit : "") + "\n";
    }
  };
  add_rows(r.inputs, false);
  add_rows(r.options, false);
  out += "  ----\n";
  add_rows(r.metrics, true);
  char time[64];
  std::snprintf(time, sizeof time, "  %-30s %.3f s\n", "time", r.seconds);
  return out + time;
}

// ---- output: CSV ----------------------------------------------------------------------

std::string csvCell(const FieldValue& v) {
  if (std::holds_alternative<std::monostate>(v)) return "";
  if (const bool* b = std::get_if<bool>(&v)) return *b ? "true" : "false";
  if (const std::int64_t* i = std::get_if<std::int64_t>(&v)) return std::to_string(*i);
  if (const double* d = std::get_if<double>(&v)) {
    char text[32];  // shortest text that reads back as the same double
    const auto result = std::to_chars(text, text + sizeof text, *d);
    return std::string(text, result.ptr);
  }
  const std::string& s = std::get<std::string>(v);
  if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
  std::string quoted = "\"";
  for (const char c : s) quoted += c == '"' ? std::string("\"\"") : std::string(1, c);
  return quoted + "\"";
}

std::string csvLine(const EvalRecord& r, bool header) {
  std::string line;
  bool first = true;
  for (const std::vector<Field>* fields : {&r.inputs, &r.options, &r.metrics})
    for (const Field& f : *fields) {
      if (!first) line += ",";
      first = false;
      line += header ? f.key : csvCell(f.value);
    }
  return line + "\n";
}

/// Appends the record's row to `file`, with the header first when the file is new or empty.
/// An existing file must have this command's header. Row (and header) go out in one write(2)
/// on an O_APPEND descriptor, so rows of parallel runs never interleave.
void appendCsvRow(const fs::path& file, const EvalRecord& r) {
  const std::string header = csvLine(r, true);
  std::string text = csvLine(r, false);
  std::error_code ec;
  if (fs::exists(file, ec) && fs::file_size(file, ec) > 0) {
    std::ifstream in(file);
    std::string first_line;
    std::getline(in, first_line);
    if (first_line + "\n" != header)
      throw InputError(
          file, "its columns are not those of `solo " + r.command + "` (the first line differs); append to a new file");
  } else {
    text = header + text;
  }
  const int fd = ::open(file.c_str(), O_WRONLY | O_APPEND | O_CREAT | O_CLOEXEC, 0644);
  if (fd < 0) throw InputError(file, std::string("cannot open for appending: ") + std::strerror(errno));
  const ssize_t written = ::write(fd, text.data(), text.size());
  const int write_errno = errno;
  ::close(fd);
  if (written != static_cast<ssize_t>(text.size()))
    throw InputError(
        file, std::string("cannot append the row: ") + (written < 0 ? std::strerror(write_errno) : "short write"));
}

int emit(const EvalRecord& r, const EvalOutputOptions& output) {
  if (output.csv) appendCsvRow(*output.csv, r);
  std::cout << (output.json ? recordToJson(r) : recordToTable(r));
  return 0;
}

cv::Mat readMask(const std::optional<fs::path>& mask) { return mask ? readLabels(*mask) : cv::Mat(); }

}  // namespace

int runEvalDepth(const EvalDepthOptions& o) {
  Stopwatch clock;
  DepthEvaluationInput input;
  input.prediction_m = readDepth(o.prediction, o.prediction_scale_m_per_unit);
  input.ground_truth_m = readDepth(o.ground_truth, o.ground_truth_scale_m_per_unit);
  input.mask = readMask(o.mask);
  input.prediction_file = o.prediction;
  input.ground_truth_file = o.ground_truth;
  if (o.mask) input.mask_file = *o.mask;
  DepthMetricsOptions options;
  options.min_depth_m = o.min_depth_m;
  options.max_depth_m = o.max_depth_m;
  options.median_scaling = o.median_scaling;
  options.clamp_prediction = o.clamp_prediction;
  const DepthMetrics m = evaluateDepth(input, options);

  EvalRecord r;
  r.command = "eval depth";
  r.inputs = {{"prediction", "prediction", o.prediction.string(), ""},
              {"ground_truth", "ground truth", o.ground_truth.string(), ""},
              {"mask", "mask", optionalPath(o.mask), ""}};
  r.options = {
      {"min_depth_m", "min depth (gt >)", optionalNumber(o.min_depth_m), "m"},
      {"max_depth_m", "max depth (gt <)", optionalNumber(o.max_depth_m), "m"},
      {"median_scaling", "median scaling", o.median_scaling, ""},
      {"clamp_prediction", "clamp prediction", o.clamp_prediction, ""},
      {"prediction_scale_m_per_unit", "prediction file scale", scaleOption(o.prediction_scale_m_per_unit), "m/unit"},
      {"ground_truth_scale_m_per_unit", "ground-truth file scale", scaleOption(o.ground_truth_scale_m_per_unit),
       "m/unit"}};
  r.metrics = {{"pixels", "pixels", m.pixels, ""},
               {"masked_out", "  masked out", m.masked_out, ""},
               {"ground_truth_invalid", "  no ground truth", m.ground_truth_invalid, ""},
               {"outside_range", "  gt outside depth range", m.outside_range, ""},
               {"prediction_invalid", "  no prediction", m.prediction_invalid, ""},
               {"valid_pixels", "  valid (evaluated)", m.valid_pixels, ""},
               {"scale", "scale applied to prediction", m.scale, ""},
               {"abs_rel", "AbsRel", m.abs_rel, ""},
               {"sq_rel_m", "SqRel", m.sq_rel_m, "m"},
               {"rmse_m", "RMSE", m.rmse_m, "m"},
               {"rmse_log", "RMSElog", m.rmse_log, ""},
               {"delta1", "delta < 1.25", m.delta1, ""},
               {"delta2", "delta < 1.25^2", m.delta2, ""},
               {"delta3", "delta < 1.25^3", m.delta3, ""}};
  r.seconds = clock.seconds();
  return emit(r, o.output);
}

int runEvalNormals(const EvalNormalsOptions& o) {
  Stopwatch clock;
  NormalEvaluationInput input;
  input.prediction = readNormals(o.prediction);
  input.ground_truth = readNormals(o.ground_truth);
  input.mask = readMask(o.mask);
  input.prediction_file = o.prediction;
  input.ground_truth_file = o.ground_truth;
  if (o.mask) input.mask_file = *o.mask;
  const NormalMetrics m = evaluateNormals(input);

  EvalRecord r;
  r.command = "eval normals";
  r.inputs = {{"prediction", "prediction", o.prediction.string(), ""},
              {"ground_truth", "ground truth", o.ground_truth.string(), ""},
              {"mask", "mask", optionalPath(o.mask), ""}};
  r.metrics = {{"pixels", "pixels", m.pixels, ""},
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
    r.metrics.push_back({threshold_keys[t], threshold_labels[t], m.share_under[t], ""});
  r.seconds = clock.seconds();
  return emit(r, o.output);
}

int runEvalMesh(const EvalMeshOptions& o) {
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
    d = measureMeshDistances(mesh, reference, options, o.mesh, *o.reference);
  }
  const auto quality = [&m](double TriangleQuality::*field) {
    return m.quality ? FieldValue((*m.quality).*field) : FieldValue(std::monostate{});
  };
  const auto distance = [&d](auto MeshDistances::*field) {
    return d ? FieldValue((*d).*field) : FieldValue(std::monostate{});
  };

  EvalRecord r;
  r.command = "eval mesh";
  r.inputs = {{"mesh", "mesh", o.mesh.string(), ""}, {"reference", "reference", optionalPath(o.reference), ""}};
  r.options = {{"samples", "samples per direction", o.samples, ""},
               {"seed", "seed", static_cast<std::int64_t>(o.seed), ""}};
  r.metrics = {
      {"vertices", "vertices", m.vertices, ""},
      {"faces", "faces (triangles)", m.faces, ""},
      {"polygons_triangulated", "  polygons fan-split on read", read_stats.polygons_triangulated, ""},
      {"faces_dropped", "  faces dropped on read", read_stats.faces_dropped, ""},
      {"unreferenced_vertices", "unreferenced vertices", m.unreferenced_vertices, ""},
      {"degenerate_faces", "degenerate faces", m.degenerate_faces, ""},
      {"edges", "edges", m.edges, ""},
      {"euler_characteristic", "Euler characteristic V-E+F", m.euler_characteristic, ""},
      {"components", "connected components", m.components, ""},
      {"closed", "closed", m.closed, ""},
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
      {"ref_bbox_diagonal", "ref bounding-box diagonal", distance(&MeshDistances::reference_bbox_diagonal), ""},
      {"mesh_vertices_checked", "mesh vertices checked", distance(&MeshDistances::mesh_vertices_checked), ""},
      {"ref_vertices_checked", "ref vertices checked", distance(&MeshDistances::reference_vertices_checked), ""}};
  r.seconds = clock.seconds();
  return emit(r, o.output);
}

}  // namespace solo::tools
