#pragma once
// The realism benchmark of `solo bench realism` (docs/realism.md): the night conversion
// (runNightConversion, a preset applied) on the embedded default scene and on `solo synth`
// streets of several seeds and variants, one at twice the street size. Per run: the night
// image, its realism statistics (docs/evaluation.md), the day image's mean luma, the road's and
// the lit windows' luminance in cd/m^2 and the run's time; a median row over the runs; and in
// the output folder night/<scene>.png, scenes/ (the streets), realism.csv, README.md (the table
// against the targets, the seed, the machine's load) and contact_sheet.png.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace solo {

struct RealismBenchOptions {
  std::filesystem::path output;    ///< folder to write (created)
  std::uint64_t seed = 1;          ///< lights, render and sensor noise of every run
  bool quick = false;              ///< the default scene and two streets only
  std::string preset = "default";  ///< night conversion preset (night_presets.h)
  int width = 960, height = 540;   ///< pixels of the streets; the large street is twice each
};

/// One row of realism.csv: the scene's names and its figures by column (none: no value).
struct RealismRow {
  std::string scene, variant, street_seed;
  std::vector<std::pair<std::string, std::optional<double>>> values;
  /// The seed of the scene's lights, render and sensor noise: nightBatchSceneSeed(bench seed,
  /// scene name), as `solo night --batch` gives each scene its own; empty in the median row.
  std::string night_seed;

  /// The value of column `key`; none when the row has no such column or no value there.
  std::optional<double> get(const std::string& key) const;
};

/// Runs the bench and writes its files; returns one row per scene and the median row last.
/// `progress` receives one line per scene as it finishes ("[i/n] scene WxH: mean ..."); may be
/// empty. Throws InputError for a street size outside 16-4096 pixels per side, an unknown
/// preset or an output that is not a folder, before anything is written.
std::vector<RealismRow> runRealismBench(const RealismBenchOptions& options,
                                        const std::function<void(const std::string&)>& progress = {});

/// The row of per-column medians (mean of the two middle values for an even count) over the
/// values the rows have; scene "MEDIAN", no size. `rows` must not be empty.
RealismRow medianRow(const std::vector<RealismRow>& rows);

/// The targets of docs/realism.md (and the road's EN 13201 M1-M6 range) a row misses: keys
/// mean, clipped, bright, noise, chroma_noise, cast, night_to_day, road_cd_m2. A statistic
/// without a value misses its target.
std::vector<std::string> missedTargets(const RealismRow& row);

/// realism.csv: header, then one line per row (numbers in their shortest exact form, missed
/// targets joined by ';'). `rows` must not be empty.
std::string realismCsv(const std::vector<RealismRow>& rows, std::uint64_t seed, const std::string& preset);

/// The markdown table: a targets line, one line per row; a missed target's cell ends in " ✗".
std::string realismTable(const std::vector<RealismRow>& rows);

}  // namespace solo
