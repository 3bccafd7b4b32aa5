#include "solo/core/report.h"

#include "solo/core/atomic_file.h"

#include <nlohmann/json.hpp>

#include <cstdio>
#include <sstream>

namespace solo {

const MetricValue* StageReport::find(const std::string& metric) const {
  for (const Metric& m : metrics)
    if (m.name == metric) return &m.value;
  return nullptr;
}

namespace {

nlohmann::json toJson(const MetricValue& v) {
  return std::visit([](const auto& x) { return nlohmann::json(x); }, v);
}

std::string formatValue(const MetricValue& v) {
  if (const double* d = std::get_if<double>(&v)) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.4g", *d);
    return buf;
  }
  if (const std::int64_t* i = std::get_if<std::int64_t>(&v)) return std::to_string(*i);
  if (const bool* b = std::get_if<bool>(&v)) return *b ? "yes" : "no";
  return std::get<std::string>(v);
}

}  // namespace

std::string reportToJson(const RunReport& r) {
  nlohmann::ordered_json j;
  j["command"] = r.command;
  j["scene"] = r.scene;
  j["seed"] = r.seed;
  if (!r.preset.empty()) j["preset"] = r.preset;
  j["total_seconds"] = r.total_seconds;
  auto& versions = j["versions"] = nlohmann::ordered_json::object();
  for (const auto& [name, version] : r.versions) versions[name] = version;
  auto& stages = j["stages"] = nlohmann::ordered_json::array();
  for (const StageReport& s : r.stages) {
    nlohmann::ordered_json js;
    js["name"] = s.name;
    js["seconds"] = s.seconds;
    js["skipped"] = s.skipped;
    if (s.skipped) js["skip_reason"] = s.skip_reason;
    auto& metrics = js["metrics"] = nlohmann::ordered_json::object();
    for (const Metric& m : s.metrics) {
      if (m.unit.empty()) metrics[m.name] = toJson(m.value);
      else metrics[m.name] = {{"value", toJson(m.value)}, {"unit", m.unit}};
    }
    js["notes"] = s.notes;
    if (!s.warnings.empty()) js["warnings"] = s.warnings;
    stages.push_back(js);
  }
  j["notes"] = r.notes;
  return j.dump(2) + "\n";
}

void writeReportJson(const std::filesystem::path& file, const RunReport& report) {
  writeTextAtomically(file, reportToJson(report));
}

namespace {

// "  refine        1.234 s  metric v, metric v ... (3 notes)": the first six metrics.
std::string stageLine(const StageReport& s, bool with_note_count) {
  char head[96];
  std::snprintf(head, sizeof head, "  %-12s %8.3f s  ", s.name.c_str(), s.seconds);
  std::string line = head;
  if (s.skipped) return line + "skipped: " + s.skip_reason + "\n";
  int shown = 0;
  for (const Metric& m : s.metrics) {
    if (shown++ == 6) {
      line += " ...";
      break;
    }
    line += (shown > 1 ? ", " : "") + m.name + " " + formatValue(m.value) + (m.unit.empty() ? "" : " " + m.unit);
  }
  if (with_note_count && !s.notes.empty())
    line += "  (" + std::to_string(s.notes.size()) + (s.notes.size() == 1 ? " note" : " notes") + ")";
  return line + "\n";
}

}  // namespace

std::string reportSummary(const RunReport& r, const SummaryOptions& options) {
  std::ostringstream out;
  out << "solo " << r.command << "  scene: " << r.scene << "  seed: " << r.seed;
  if (!r.preset.empty()) out << "  preset: " << r.preset;
  out << "\n";
  for (const StageReport& s : r.stages) {
    out << stageLine(s, !options.notes);
    for (const std::string& w : s.warnings) out << "               warning: " << w << "\n";
    if (options.notes)
      for (const std::string& n : s.notes) out << "               note: " << n << "\n";
  }
  if (options.notes)
    for (const std::string& n : r.notes) out << "  note: " << n << "\n";
  else if (!r.notes.empty())
    out << "  (" << r.notes.size() << (r.notes.size() == 1 ? " note" : " notes") << " on the run in the report)\n";
  char total[64];
  std::snprintf(total, sizeof total, "  total        %8.3f s\n", r.total_seconds);
  out << total;
  return out.str();
}

}  // namespace solo
