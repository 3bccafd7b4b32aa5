// `solo eval depth|normals|mesh|scene`: the record of the library's evaluation
// (pipeline/evaluation.h) written three ways: a table on the terminal, JSON on stdout (--json),
// and a row appended to a CSV file (--csv). `solo eval depth` over a dataset prints its summary
// and appends a CSV row per image. `solo eval night` measures several images at once
// (pipeline/night_evaluation.h): a table row, a JSON object and a CSV row per image.

#include "commands.h"

#include <solo/core/error.h>
#include <solo/pipeline/evaluation.h>
#include <solo/pipeline/night_evaluation.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdio>
#include <iostream>
#include <type_traits>
#include <utility>

namespace fs = std::filesystem;

namespace solo::tools {
namespace {

// ---- output: JSON ---------------------------------------------------------------------

nlohmann::ordered_json toJson(const EvaluationValue& v) {
  return std::visit(
      [](const auto& x) -> nlohmann::ordered_json {
        if constexpr (std::is_same_v<std::decay_t<decltype(x)>, std::monostate>)
          return nullptr;
        else
          return x;
      },
      v);
}

nlohmann::ordered_json recordJson(const EvaluationRecord& r) {
  nlohmann::ordered_json j;
  j["command"] = r.command;
  for (const auto& [section, fields] :
       {std::pair{"inputs", &r.inputs}, {"options", &r.options}, {"metrics", &r.metrics}}) {
    auto& object = j[section] = nlohmann::ordered_json::object();
    for (const EvaluationField& f : *fields) object[f.key] = toJson(f.value);
  }
  j["seconds"] = r.seconds;
  return j;
}

std::string recordToJson(const EvaluationRecord& r) { return recordJson(r).dump(2) + "\n"; }

// ---- output: table --------------------------------------------------------------------

std::string tableValue(const EvaluationValue& v) {
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

// "  label" padded with spaces to `width` characters, then a space: a table row's start.
std::string paddedLabel(const std::string& label, int width) {
  return "  " + label + std::string(std::max(0, width - static_cast<int>(label.size())), ' ') + " ";
}

std::string recordToTable(const EvaluationRecord& r) {
  std::string out = "solo " + r.command + "\n";
  int width = 30;  // labels are padded to the longest one
  for (const std::vector<EvaluationField>* fields : {&r.inputs, &r.options, &r.metrics})
    for (const EvaluationField& f : *fields) width = std::max(width, static_cast<int>(f.label.size()));
  const auto add_rows = [&out, width](const std::vector<EvaluationField>& fields, bool skip_missing) {
    for (const EvaluationField& f : fields) {
      if (skip_missing && std::holds_alternative<std::monostate>(f.value)) continue;
      const bool has_unit = !f.unit.empty() && !std::holds_alternative<std::monostate>(f.value);
      out += paddedLabel(f.label, width) + tableValue(f.value) + (has_unit ? " " + f.unit : "") + "\n";
    }
  };
  add_rows(r.inputs, false);
  add_rows(r.options, false);
  out += "  ----\n";
  add_rows(r.metrics, true);
  char seconds[32];
  std::snprintf(seconds, sizeof seconds, "%.3f s\n", r.seconds);
  return out + paddedLabel("time", width) + seconds;
}


/// The record on stdout (JSON or the table), its row appended to the CSV file when one is given.
int emit(const EvaluationRecord& r, const EvalOutputOptions& output) {
  if (output.csv) appendEvaluationCsvRow(*output.csv, r);
  std::cout << (output.json ? recordToJson(r) : recordToTable(r));
  return 0;
}

}  // namespace

namespace {

/// A dataset as JSON: the summary record's sections, then "images" (one record's sections per
/// image) and "failures".
std::string datasetToJson(const DepthDatasetEvaluation& d) {
  nlohmann::ordered_json j = recordJson(d.summary);
  j.erase("seconds");
  j["images"] = nlohmann::ordered_json::array();
  for (const EvaluationRecord& image : d.images) {
    nlohmann::ordered_json object = recordJson(image);
    object.erase("command");
    object.erase("options");  // the summary's
    j["images"].push_back(object);
  }
  j["failures"] = d.failures;
  j["seconds"] = d.summary.seconds;
  return j.dump(2) + "\n";
}

/// `solo eval depth` over a dataset: a CSV row per image, the summary on stdout, each failure
/// named on stderr; exit 2 when an image failed (bad input), 0 otherwise.
int runEvalDepthDataset(const EvalDepthOptions& o) {
  const DepthDatasetEvaluation d = evaluateDepthDataset(o);
  if (o.output.csv)
    for (const EvaluationRecord& image : d.images) appendEvaluationCsvRow(*o.output.csv, image);
  std::cout << (o.output.json ? datasetToJson(d) : recordToTable(d.summary));
  for (const std::string& failure : d.failures) std::cerr << "solo: error: " << failure << "\n";
  if (d.failures.empty()) return 0;
  std::cerr << "solo: error: " << d.failures.size() << " of " << d.images.size() << " images failed\n";
  return 2;
}

}  // namespace

int runEvalDepth(const EvalDepthOptions& o) {
  return isDepthDataset(o) ? runEvalDepthDataset(o) : emit(evaluateDepthFiles(o), o.output);
}

int runEvalNormals(const EvalNormalsOptions& o) { return emit(evaluateNormalFiles(o), o.output); }

int runEvalMesh(const EvalMeshOptions& o) { return emit(evaluateMeshFile(o), o.output); }

int runEvalScene(const EvalSceneOptions& o) { return emit(evaluateSceneFolder(o), o.output); }

// ---- eval night -----------------------------------------------------------------------

namespace {

std::string joined(const std::vector<std::string>& words, const std::string& separator) {
  std::string out;
  for (const std::string& w : words) out += (out.empty() ? "" : separator) + w;
  return out;
}

/// One table cell of a statistic: luma to 0.1, shares to 1e-4, sigmas to 0.01, "-" for none.
std::string nightCell(const std::string& key, const std::optional<double>& value) {
  if (!value) return "-";
  const char* format = "%.1f";
  if (key == "clipped" || key == "bright") format = "%.4f";
  else if (key == "noise" || key == "chroma_noise") format = "%.2f";
  else if (key == "cast_cb" || key == "cast_cr") format = "%+.1f";
  else if (key == "halo_blobs") format = "%.0f";
  char text[32];
  std::snprintf(text, sizeof text, format, *value);
  return text;
}

/// The reference's rows (table) and objects (JSON): its median, minimum and maximum.
const std::pair<const char*, std::optional<double> NightReferenceRange::*> kRangeRows[] = {
    {"median", &NightReferenceRange::median}, {"min", &NightReferenceRange::min}, {"max", &NightReferenceRange::max}};

/// One line of the night table: the label padded to `width` (longer labels keep their end),
/// then the cells, right-aligned (the blob count narrower), then `tail`.
std::string nightTableLine(std::string label, int width, const std::vector<std::string>& cells,
                           const std::string& tail) {
  if (static_cast<int>(label.size()) > width) label = "..." + label.substr(label.size() - (width - 3));
  std::string line = "  " + label + std::string(width - label.size(), ' ');
  for (std::size_t k = 0; k < cells.size(); ++k) {
    const std::size_t cell_width = k + 1 == cells.size() ? 5 : 8;
    line += " " + std::string(cell_width - std::min(cell_width, cells[k].size()), ' ') + cells[k];
  }
  return line + (tail.empty() ? "" : "  " + tail) + "\n";
}

/// The cells of one row of statistics, in namedNightStatistics' order.
std::vector<std::string> nightCells(const std::vector<std::optional<double>>& values) {
  const std::vector<NamedNightStatistic> keys = namedNightStatistics(NightStatistics{});
  std::vector<std::string> cells;
  for (std::size_t k = 0; k < keys.size(); ++k) cells.push_back(nightCell(keys[k].key, values[k]));
  return cells;
}

/// The terminal table: a row per image (its path as given), then the reference's rows.
std::string nightTable(const NightEvaluation& run) {
  int width = 12;
  for (const fs::path& f : run.files) width = std::max(width, static_cast<int>(f.string().size()));
  width = std::min(width, 48);
  const bool has_reference = !run.ranges.empty();
  std::string out = "solo eval night\n" +
                    nightTableLine("image", width,
                                   {"mean", "p50", "p90", "p99", "clipped", "bright", "noise", "chroma", "cast_cb",
                                    "cast_cr", "halo_px", "blobs"},
                                   has_reference ? "outside reference range" : "");
  for (std::size_t i = 0; i < run.files.size(); ++i) {
    std::vector<std::optional<double>> values;
    for (const NamedNightStatistic& n : namedNightStatistics(run.statistics[i])) values.push_back(n.value);
    const std::string outside =
        has_reference ? joined(nightStatisticsOutsideRange(run.statistics[i], run.ranges), ", ") : "";
    out += nightTableLine(run.files[i].string(), width, nightCells(values),
                          has_reference ? (outside.empty() ? "none" : outside) : "");
  }
  if (has_reference) {
    out += "  reference: " + run.reference->string() + " (" + std::to_string(run.reference_files.size()) + " images)\n";
    for (const auto& [name, field] : kRangeRows) {
      std::vector<std::optional<double>> values;
      for (const NightReferenceRange& r : run.ranges) values.push_back(r.*field);
      out += nightTableLine(std::string("  ") + name, width, nightCells(values), "");
    }
  }
  char time[64];
  std::snprintf(time, sizeof time, "  time %.3f s\n", run.seconds);
  return out + time;
}

nlohmann::ordered_json optionalJson(const std::optional<double>& v) { return v ? nlohmann::ordered_json(*v) : nullptr; }

/// A statistic in JSON: the blob count as an integer, the others as numbers, none as null.
nlohmann::ordered_json statisticJson(const std::string& key, const std::optional<double>& v) {
  if (key == "halo_blobs" && v) return static_cast<std::int64_t>(*v);
  return optionalJson(v);
}

std::string nightJson(const NightEvaluation& run) {
  nlohmann::ordered_json j;
  j["command"] = "eval night";
  j["reference"] = nullptr;
  if (!run.ranges.empty()) {
    auto& ref = j["reference"] = nlohmann::ordered_json::object();
    ref["source"] = run.reference->string();
    ref["images"] = nlohmann::ordered_json::array();
    for (const fs::path& f : run.reference_files) ref["images"].push_back(f.string());
    const std::vector<NamedNightStatistic> keys = namedNightStatistics(NightStatistics{});
    for (const auto& [name, field] : kRangeRows) {
      auto& object = ref[name] = nlohmann::ordered_json::object();
      for (std::size_t k = 0; k < keys.size(); ++k)
        object[keys[k].key] = statisticJson(keys[k].key, run.ranges[k].*field);
    }
  }
  j["images"] = nlohmann::ordered_json::array();
  for (std::size_t i = 0; i < run.files.size(); ++i) {
    const NightStatistics& s = run.statistics[i];
    nlohmann::ordered_json image;
    image["file"] = run.files[i].string();
    image["width_px"] = s.source_width_px;
    image["height_px"] = s.source_height_px;
    auto& statistics = image["statistics"] = nlohmann::ordered_json::object();
    for (const NamedNightStatistic& n : namedNightStatistics(s)) statistics[n.key] = statisticJson(n.key, n.value);
    image["outside_reference"] = run.ranges.empty()
                                     ? nlohmann::ordered_json(nullptr)
                                     : nlohmann::ordered_json(nightStatisticsOutsideRange(s, run.ranges));
    j["images"].push_back(image);
  }
  j["seconds"] = run.seconds;
  return j.dump(2) + "\n";
}

}  // namespace

int runEvalNight(const EvalNightOptions& o) {
  if (o.images.empty()) throw InputError("IMAGE", "no image to evaluate");
  const NightEvaluation run = evaluateNightImages(o);
  if (o.output.csv)
    for (std::size_t i = 0; i < run.files.size(); ++i)
      appendEvaluationCsvRow(*o.output.csv, nightEvaluationRecord(run, i));
  std::cout << (o.output.json ? nightJson(run) : nightTable(run));
  return 0;
}

}  // namespace solo::tools
