// The realism benchmark (realism_bench.h): the cases, one night conversion per case and its
// measurements, the median row, and the files realism.csv, README.md and contact_sheet.png.

#include <solo/pipeline/realism_bench.h>

#include <solo/pipeline/accuracy_sweep.h>
#include <solo/pipeline/data_dir.h>
#include <solo/pipeline/night_conversion.h>
#include <solo/pipeline/night_batch.h>
#include <solo/pipeline/night_job.h>
#include <solo/pipeline/night_presets.h>

#include <solo/core/atomic_file.h>
#include <solo/core/error.h>
#include <solo/core/image_io.h>
#include <solo/core/report.h>
#include <solo/core/scene.h>
#include <solo/core/version.h>
#include <solo/lighting/light_category.h>
#include <solo/post/colour_encoding.h>
#include <solo/post/night_statistics.h>
#include <solo/render/contact_sheet.h>
#include <solo/synth/scene_folder.h>

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <sstream>
#include <thread>

namespace fs = std::filesystem;

namespace solo {

std::optional<double> RealismRow::get(const std::string& key) const {
  for (const auto& [k, v] : values)
    if (k == key) return v;
  return std::nullopt;
}

namespace {
/// One scene of the realism bench: the embedded default scene or a `solo synth` street.
struct RealismCase {
  std::string name;
  bool street = false;
  std::uint64_t street_seed = 0;
  std::string variant = "embedded";
  int width_px = 0, height_px = 0;  ///< of a street; the default scene has its own size
};

/// The default scene (seed 1's default street), then eight other streets of seeds 1-4 over
/// every variant at options' size, one of them at twice the size (1920x1080 by default);
/// --quick: the default scene and two streets.
std::vector<RealismCase> realismCases(const RealismBenchOptions& o) {
  std::vector<RealismCase> cases = {{"default-scene"}};
  const auto street = [&](std::uint64_t seed, const std::string& variant, int scale) {
    const int w = o.width * scale, h = o.height * scale;
    std::string name = "street-s" + std::to_string(seed) + "-" + variant;
    if (scale > 1) name += "-" + std::to_string(w) + "x" + std::to_string(h);
    cases.push_back({name, true, seed, variant, w, h});
  };
  street(2, "default", 1);  // the embedded default scene is seed 1's default street
  street(2, "wide-sky", 1);
  if (o.quick) return cases;
  street(3, "grazing", 1);
  street(4, "thin-pole", 1);
  street(1, "near-object", 1);
  street(3, "wide-sky", 1);
  street(1, "grazing", 1);
  street(4, "default", 2);
  return cases;
}

/// Mean of the render's luminance Y (channel 1 of its XYZ, cd/m^2) over the non-zero pixels
/// of `mask`; none for an empty mask. `pixels` receives their count.
std::optional<double> meanLuminanceCdM2(const RenderOutput& r, const cv::Mat& mask, std::int64_t& pixels) {
  pixels = cv::countNonZero(mask);
  if (pixels == 0) return std::nullopt;
  cv::Mat y;
  cv::extractChannel(r.radiance, y, 1);
  return cv::mean(y, mask)[0];
}

/// Pixels that see no emitter at all (emitter coverage 0, no light id).
cv::Mat noEmitterMask(const RenderOutput& r) {
  cv::Mat none = r.light_id == 0;
  if (!r.emitter_coverage.empty()) none &= r.emitter_coverage == 0;
  return none;
}

/// Road pixels (Cityscapes label 7 of the scene's label map, at the render's size) without emitter.
cv::Mat roadMask(const Scene& scene, const RenderOutput& r) {
  if (scene.labels.empty()) return cv::Mat::zeros(r.radiance.size(), CV_8U);
  cv::Mat labels = scene.labels;
  if (labels.size() != r.radiance.size()) cv::resize(scene.labels, labels, r.radiance.size(), 0, 0, cv::INTER_NEAREST);
  cv::Mat road = labels == 7;
  return road & noEmitterMask(r);
}

/// Pixels wholly covered by a lit building window (light category window_building).
cv::Mat litWindowMask(const RenderOutput& r) {
  const int first = static_cast<int>(LightCategory::WindowBuilding) * 1000;
  cv::Mat windows = (r.light_id >= first) & (r.light_id < first + 1000);
  if (!r.emitter_coverage.empty()) windows &= r.emitter_coverage >= 1.0f;
  return windows;
}

/// The seconds of the pipeline stage named `name` (0 when it did not run).
double stageSeconds(const NightConversionResult& result, const std::string& name) {
  for (const StageReport& s : result.stages)
    if (s.name == name) return s.seconds;
  return 0;
}

/// Makes the street of `c` as `solo synth` does under out/scenes/<name> (no report on the
/// terminal); returns its manifest.
fs::path makeStreet(const RealismCase& c, const fs::path& out) {
  SyntheticSceneOptions synth;
  synth.seed = c.street_seed;
  synth.variant = c.variant;
  synth.width = c.width_px;
  synth.height = c.height_px;
  synth.force = true;
  const fs::path folder = out / "scenes" / c.name;
  writeSyntheticScene(folder, synth);
  return folder / "scene.json";
}

/// Runs `solo night`'s pipeline (`night`: preset applied) on `scene_file`, writes the night
/// image to out/night/<name>.png and measures it. `night8` receives the 8-bit night image (RGB).
RealismRow runRealismCase(const RealismCase& c, const fs::path& scene_file, const NightConversionOptions& night,
                          const fs::path& out, cv::Mat& night8) {
  Stopwatch clock;
  const Scene scene = loadScene(scene_file);
  NightConversionCallbacks quiet;
  quiet.render_progress = false;
  const NightConversionResult result = runNightConversion(scene, night, quiet);
  writeDevelopedImage(out / "night" / (c.name + ".png"), result.developed.encoded, result.developed.linear_rgb, false);
  const double total_seconds = clock.seconds();
  night8 = quantiseEncoded(result.developed.encoded, 8);

  const NightStatistics s = computeNightStatistics(night8, ChannelOrder::Rgb);
  const double day_mean = computeNightStatistics(scene.image, ChannelOrder::Rgb).mean_luma;
  std::int64_t road_pixels = 0, window_pixels = 0;
  const std::optional<double> road = meanLuminanceCdM2(result.rendered, roadMask(scene, result.rendered), road_pixels);
  const std::optional<double> windows =
      meanLuminanceCdM2(result.rendered, litWindowMask(result.rendered), window_pixels);

  RealismRow row{c.name, c.variant, c.street ? std::to_string(c.street_seed) : std::string(), {},
                 std::to_string(night.seed)};
  row.values = {{"width_px", scene.width()}, {"height_px", scene.height()}};
  for (const NamedNightStatistic& n : namedNightStatistics(s)) row.values.emplace_back(n.key, n.value);
  row.values.insert(row.values.end(),
                    {{"day_mean", day_mean},
                     {"night_to_day", day_mean > 0 ? std::optional<double>(s.mean_luma / day_mean) : std::nullopt},
                     {"road_cd_m2", road},
                     {"road_pixels", static_cast<double>(road_pixels)},
                     {"windows_cd_m2", windows},
                     {"windows_pixels", static_cast<double>(window_pixels)},
                     {"sensor_white_cd_m2", result.sensor_white_cd_m2},
                     {"seconds_total", total_seconds},
                     {"seconds_render", stageSeconds(result, "render")}});
  return row;
}

/// A number in its shortest form that reads back exactly.
std::string shortestNumber(double v) {
  char text[32];
  const auto end = std::to_chars(text, text + sizeof text, v).ptr;
  return std::string(text, end);
}

/// `v` printed with `format`; "none" without a value.
std::string formatted(const std::optional<double>& v, const char* format) {
  if (!v) return "none";
  char text[48];
  std::snprintf(text, sizeof text, format, *v);
  return text;
}

/// Refuses a street size out of range, an unknown preset or an output that is not a folder;
/// returns the night conversion's options (preset applied; each scene's seed is set per run).
NightConversionOptions checkedNightOptions(const RealismBenchOptions& o) {
  if (o.width < 16 || o.height < 16 || o.width > 4096 || o.height > 4096)
    throw InputError("--size", "street size must be between 16 and 4096 pixels per side");
  NightConversionOptions night = nightPreset(o.preset);  // throws for an unknown preset
  std::error_code ec;
  if (fs::exists(o.output, ec) && !fs::is_directory(o.output, ec))
    throw InputError(o.output, "exists and is not a folder");
  return night;
}

}  // namespace

RealismRow medianRow(const std::vector<RealismRow>& rows) {
  RealismRow median{"MEDIAN", "", "", {}, ""};
  for (std::size_t k = 0; k < rows.front().values.size(); ++k) {
    const std::string& key = rows.front().values[k].first;
    if (key == "width_px" || key == "height_px") {
      median.values.emplace_back(key, std::nullopt);
      continue;
    }
    std::vector<double> v;
    for (const RealismRow& r : rows)
      if (r.values[k].second) v.push_back(*r.values[k].second);
    std::sort(v.begin(), v.end());
    std::optional<double> m;
    if (!v.empty()) m = v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
    median.values.emplace_back(rows.front().values[k].first, m);
  }
  return median;
}

std::vector<std::string> missedTargets(const RealismRow& row) {
  const auto within = [&](const std::string& key, double lo, double hi) {
    const std::optional<double> v = row.get(key);
    return v && *v >= lo && *v <= hi;
  };
  const std::optional<double> cb = row.get("cast_cb"), cr = row.get("cast_cr");
  const std::vector<std::pair<std::string, bool>> met = {{"mean", within("mean", 30, 70)},
                                                         {"clipped", within("clipped", 0, 0.005)},
                                                         {"bright", within("bright", 0, 0.02)},
                                                         {"noise", within("noise", 0.5, 1.5)},
                                                         {"chroma_noise", within("chroma_noise", 0, 1.0)},
                                                         {"cast", cb && cr && *cb < 0 && *cr > 0},
                                                         {"night_to_day", within("night_to_day", 0, 0.5)},
                                                         {"road_cd_m2", within("road_cd_m2", 0.3, 2.0)}};
  std::vector<std::string> missed;
  for (const auto& [key, ok] : met)
    if (!ok) missed.push_back(key);
  return missed;
}

std::string realismCsv(const std::vector<RealismRow>& rows, std::uint64_t seed, const std::string& preset) {
  std::string csv = "scene,variant,street_seed,seed,night_seed,preset";
  for (const auto& [key, value] : rows.front().values) csv += "," + key;
  csv += ",missed_targets\n";
  for (const RealismRow& r : rows) {
    csv += r.scene + "," + r.variant + "," + r.street_seed + "," + std::to_string(seed) + "," + r.night_seed + "," +
           preset;
    for (const auto& [key, value] : r.values) csv += "," + (value ? shortestNumber(*value) : std::string());
    std::string missed;
    for (const std::string& m : missedTargets(r)) missed += (missed.empty() ? "" : ";") + m;
    csv += "," + missed + "\n";
  }
  return csv;
}

std::string realismTable(const std::vector<RealismRow>& rows) {
  std::ostringstream t;
  t << "| scene | size | mean | p50 | clipped | bright | noise | chroma noise | cast Cb' / Cr' | halo px | day mean "
       "| night / day | road cd/m² | windows cd/m² | s total | s render |\n"
    << "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n"
    << "| *target* | | 30-70 | | <= 0.005 | <= 0.02 | 0.5-1.5 | <= 1.0 | < 0 / > 0 | | | <= 0.5 | 0.3-2.0 | | | |\n";
  for (const RealismRow& r : rows) {
    const std::vector<std::string> missed = missedTargets(r);
    const auto cell = [&](const std::string& key, const char* format) {
      const bool miss = std::find(missed.begin(), missed.end(), key) != missed.end();
      return " " + formatted(r.get(key), format) + (miss ? " ✗" : "") + " |";
    };
    const bool cast_miss = std::find(missed.begin(), missed.end(), "cast") != missed.end();
    const std::string size = r.get("width_px")
                                 ? formatted(r.get("width_px"), "%.0f") + "x" + formatted(r.get("height_px"), "%.0f")
                                 : std::string();
    t << "| " << (r.scene == "MEDIAN" ? "**median**" : r.scene) << " | " << size << " |" << cell("mean", "%.1f")
      << cell("p50", "%.1f") << cell("clipped", "%.4f") << cell("bright", "%.4f") << cell("noise", "%.2f")
      << cell("chroma_noise", "%.2f") << " " << formatted(r.get("cast_cb"), "%.1f") << " / "
      << formatted(r.get("cast_cr"), "%+.1f") << (cast_miss ? " ✗" : "") << " |" << cell("halo_radius_px", "%.1f")
      << cell("day_mean", "%.1f") << cell("night_to_day", "%.2f") << cell("road_cd_m2", "%.2f")
      << cell("windows_cd_m2", "%.1f") << cell("seconds_total", "%.1f") << cell("seconds_render", "%.1f") << "\n";
  }
  return t.str();
}

namespace {

/// Whether the median row is closer to the real-night medians than the reference pipeline's
/// renderings are (docs/realism.md), on mean, p50, bright and chroma noise.
std::string closerThanReference(const RealismRow& median) {
  struct Figure {
    const char* key;
    double real, reference;
  };
  const Figure figures[] = {
      {"mean", 44.5, 59.2}, {"p50", 30.8, 44.8}, {"bright", 0.006, 0.015}, {"chroma_noise", 0.0, 1.04}};
  std::ostringstream text;
  for (const Figure& f : figures) {
    const std::optional<double> v = median.get(f.key);
    const bool closer = v && std::abs(*v - f.real) < std::abs(f.reference - f.real);
    text << "- " << f.key << ": median " << formatted(v, "%.4g") << ", real night " << f.real << ", reference "
         << f.reference << ": " << (closer ? "closer to real night than the reference" : "not closer ✗") << "\n";
  }
  return text.str();
}

std::string realismReadme(const RealismBenchOptions& o, const std::vector<RealismRow>& rows, double load_start,
                          double load_end, double wall_seconds) {
  const std::time_t now = std::time(nullptr);
  char date[64];
  std::strftime(date, sizeof date, "%Y-%m-%d %H:%M:%S %Z", std::localtime(&now));
  std::ostringstream r;
  r << "# solo bench realism\n\n"
    << "`solo night`'s pipeline (preset `" << o.preset << "`) on the embedded default scene and on `solo synth` "
    << "streets; the realism statistics of each night image (docs/evaluation.md) against the targets of "
    << "docs/realism.md. A cell ending in ✗ misses its target.\n\n"
    << realismTable(rows) << "\n"
    << "The median row against the real-night medians and the reference pipeline's renderings:\n\n"
    << closerThanReference(rows.back()) << "\n"
    << "- seed: " << o.seed << " (each scene's lights, render and sensor noise take the seed `solo night --batch` "
    << "derives from it and the scene's name, column `night_seed`, so that no two scenes share one draw of their "
    << "lights; the streets' own seeds are in their names and in column `street_seed`)\n"
    << "- streets: made by `solo synth` in `scenes/`, " << o.width << "x" << o.height << " (one at twice that); "
    << (o.quick ? "quick: the default scene and two streets" : "full set") << "\n"
    << "- columns: mean, p50, clipped, bright, noise, chroma noise, cast and halo radius as `solo eval night`; day "
    << "mean: mean luma of the day image; road: mean luminance Y of the render (cd/m², after the denoiser, before "
    << "exposure) over the road pixels (label 7) that see no emitter, target the EN 13201 M1-M6 range; windows: "
    << "the same over pixels wholly covered by a lit building window; s total: scene loaded to night image "
    << "written; s render: the render stage (BVH, exposure preview and path tracing)\n"
    << "- machine: " << std::thread::hardware_concurrency() << " hardware threads; load average (1 min) " << load_start
    << " at the start, " << load_end << " at the end; wall time " << static_cast<int>(wall_seconds) << " s; finished "
    << date << "\n"
    << "- solo " << soloVersion() << "\n\n"
    << "Files: `realism.csv` (every figure, one row per scene and the median), `night/` (the night images), "
    << "`scenes/` (the streets), `contact_sheet.png` (the night images side by side).\n";
  return r.str();
}

/// The line of run i of count for the progress callback.
std::string progressLine(std::size_t i, std::size_t count, const RealismRow& r) {
  char line[256];
  std::snprintf(line, sizeof line,
                "[%zu/%zu] %s %sx%s: mean %s, clipped %s, bright %s, noise %s, chroma %s, "
                "night/day %s, road %s cd/m2, %s s (render %s s)",
                i + 1, count, r.scene.c_str(), formatted(r.get("width_px"), "%.0f").c_str(),
                formatted(r.get("height_px"), "%.0f").c_str(), formatted(r.get("mean"), "%.1f").c_str(),
                formatted(r.get("clipped"), "%.4f").c_str(), formatted(r.get("bright"), "%.4f").c_str(),
                formatted(r.get("noise"), "%.2f").c_str(), formatted(r.get("chroma_noise"), "%.2f").c_str(),
                formatted(r.get("night_to_day"), "%.2f").c_str(), formatted(r.get("road_cd_m2"), "%.2f").c_str(),
                formatted(r.get("seconds_total"), "%.1f").c_str(), formatted(r.get("seconds_render"), "%.1f").c_str());
  return line;
}

}  // namespace

std::vector<RealismRow> runRealismBench(const RealismBenchOptions& o,
                                        const std::function<void(const std::string&)>& progress) {
  Stopwatch wall;
  const NightConversionOptions night = checkedNightOptions(o);
  const fs::path default_scene = defaultScene();
  fs::create_directories(o.output / "night");
  const double load_start = loadAverage1Min();

  const std::vector<RealismCase> cases = realismCases(o);
  std::vector<RealismRow> rows;
  std::vector<ContactSheetTile> tiles;
  for (std::size_t i = 0; i < cases.size(); ++i) {
    const RealismCase& c = cases[i];
    const fs::path scene_file = c.street ? makeStreet(c, o.output) : default_scene;
    cv::Mat night8;
    NightConversionOptions scene_night = night;
    scene_night.seed = nightBatchSceneSeed(o.seed, c.name);
    rows.push_back(runRealismCase(c, scene_file, scene_night, o.output, night8));
    tiles.push_back({c.name, night8});
    if (progress) progress(progressLine(i, cases.size(), rows.back()));
  }
  rows.push_back(medianRow(rows));
  const double load_end = loadAverage1Min();

  writeTextAtomically(o.output / "realism.csv", realismCsv(rows, o.seed, o.preset));
  writeImage(o.output / "contact_sheet.png", composeContactSheet(tiles));
  writeTextAtomically(o.output / "README.md", realismReadme(o, rows, load_start, load_end, wall.seconds()));
  return rows;
}

}  // namespace solo
