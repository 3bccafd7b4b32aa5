#pragma once
// Run reports: every stage states its time, its accuracy figures, and what it skipped and
// why. Serialised to JSON by writeReportJson; kept free of JSON headers on purpose.

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <string>
#include <utility>
#include <variant>
#include <vector>

namespace solo {

using MetricValue = std::variant<bool, std::int64_t, double, std::string>;

struct Metric {
  std::string name;
  MetricValue value;
  std::string unit;  ///< "m", "px", "s", "deg", "" for counts and text
};

struct StageReport {
  std::string name;
  double seconds = 0;
  bool skipped = false;
  std::string skip_reason;  ///< why the stage or an effect did not run
  std::vector<Metric> metrics;
  std::vector<std::string> notes;     ///< details: effects skipped inside the stage, what was chosen
  std::vector<std::string> warnings;  ///< what the user must see on the terminal (a guessed camera, ...)

  StageReport& add(std::string metric, MetricValue value, std::string unit = {}) {
    metrics.push_back({std::move(metric), std::move(value), std::move(unit)});
    return *this;
  }
  /// Value of a metric by name, or nullptr.
  const MetricValue* find(const std::string& metric) const;
};

struct RunReport {
  std::string command;  ///< "night", "depth", ...
  std::uint64_t seed = 0;
  std::string scene;
  std::string preset;  ///< quality preset of the run ("draft", ...); empty: the command has none
  std::vector<std::pair<std::string, std::string>> versions;  ///< library -> version
  std::vector<StageReport> stages;
  std::vector<std::string> notes;
  double total_seconds = 0;
};

/// The report as pretty-printed JSON.
std::string reportToJson(const RunReport& report);
/// Writes it atomically.
void writeReportJson(const std::filesystem::path& file, const RunReport& report);
struct SummaryOptions {
  bool notes = false;  ///< every stage's notes under its line; otherwise only their count
};

/// A short human-readable summary: one line per stage with its time and key figures (and the
/// count of its notes, which the report holds), every warning on a line of its own.
std::string reportSummary(const RunReport& report, const SummaryOptions& options = {});

/// Wall-clock stopwatch in seconds.
class Stopwatch {
 public:
  Stopwatch() : start_(std::chrono::steady_clock::now()) {}
  double seconds() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  }

 private:
  std::chrono::steady_clock::time_point start_;
};

}  // namespace solo
