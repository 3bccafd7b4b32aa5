// `solo bench accuracy`: what accuracy costs in time. Makes (or takes) a synthetic scene with
// exact ground truth, runs the sweeps of pipeline/accuracy_sweep.h, and writes into OUT_DIR one CSV per
// stage (refine, mesh, render, end_to_end), a gnuplot script per plot (run when gnuplot is on
// PATH, PNG output) and a README with the seed, the machine's load and what each file holds.
//
// `solo bench realism`: `solo night`'s pipeline on the embedded default scene and on synthetic
// streets of several seeds and variants; per run the night image, its realism statistics
// (docs/evaluation.md) against the targets of docs/realism.md, the day image's mean luma, the
// road's and the lit windows' luminance and the run's time: realism.csv, README.md and a
// contact sheet of the night images.

#include "commands.h"
#include <solo/pipeline/accuracy_sweep.h>
#include <solo/pipeline/night_conversion.h>
#include <solo/pipeline/night_presets.h>

#include <solo/core/atomic_file.h>
#include <solo/core/error.h>
#include <solo/core/image_io.h>
#include <solo/core/report.h>
#include <solo/core/scene.h>
#include <solo/core/version.h>
#include <solo/lighting/light_category.h>
#include <solo/post/colour_encoding.h>
#include <solo/render/contact_sheet.h>
#include <solo/post/night_statistics.h>
#include <solo/synth/scene_folder.h>

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <iostream>
#include <sstream>
#include <thread>

namespace fs = std::filesystem;

namespace solo::tools {
namespace {

const std::vector<std::string> kStages = {"refine", "mesh", "render", "end_to_end"};

void say(const std::string& line) { std::cerr << line << "\n" << std::flush; }


std::string shellQuoted(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

bool onPath(const std::string& program) {
  const char* path = std::getenv("PATH");
  if (!path) return false;
  std::stringstream dirs(path);
  std::string dir;
  std::error_code ec;
  while (std::getline(dirs, dir, ':'))
    if (!dir.empty() && fs::exists(fs::path(dir) / program, ec)) return true;
  return false;
}

// ---- gnuplot scripts ------------------------------------------------------------------------

/// One plotted series: the rows whose columns equal the given values.
struct Series {
  std::string title;
  std::vector<std::pair<std::string, std::string>> where;  ///< column name -> value
  std::string style;                                        ///< gnuplot "with ..." part
  std::string label_column;                                 ///< text beside each point, or none
};

bool hasRows(const SweepTable& t, const Series& s) {
  for (const auto& row : t.rows) {
    bool all = true;
    for (const auto& [column, value] : s.where) all = all && row[t.column(column)] == value;
    if (all) return true;
  }
  return false;
}

/// A plot command of the series that have rows (gnuplot columns are 1-based).
std::string plotCommand(const SweepTable& t, const std::vector<Series>& series, const std::string& x,
                        const std::string& y) {
  std::string out;
  const std::string file = "\"" + t.stage + ".csv\"";
  const auto col = [&](const std::string& name) { return std::to_string(t.column(name) + 1); };
  for (const Series& s : series) {
    if (!hasRows(t, s)) continue;
    std::string condition;
    for (const auto& [column, value] : s.where)
      condition += (condition.empty() ? "" : " && ") + std::string("strcol(") + col(column) + ") eq \"" + value + "\"";
    if (condition.empty()) condition = "1";
    const std::string xs = "(" + condition + " ? $" + col(x) + " : 1/0)";
    out += std::string(out.empty() ? "plot " : ", \\\n     ") + file + " using " + xs + ":" + col(y) + " " +
           s.style + " title \"" + s.title + "\"";
    if (!s.label_column.empty())
      out += ", \\\n     " + file + " using " + xs + ":" + col(y) + ":" + col(s.label_column) +
             " with labels offset 0.6,0.6 left font \",8\" notitle";
  }
  return out + "\n";
}

std::string scriptHeader(const SweepTable& t, const std::string& title, int panels) {
  const int width = panels == 1 ? 900 : 620 * panels + 80, height = 520;
  std::ostringstream g;
  g << "# " << t.stage << ".csv: error against time. Regenerate in this folder: gnuplot " << t.stage << ".gp\n"
    << "set datafile separator \",\"\n"
    << "if (strstrt(GPVAL_TERMINALS, \"pngcairo\") > 0) {\n"
    << "  set terminal pngcairo size " << width << "," << height << " font \",10\"\n"
    << "} else {\n"
    << "  set terminal png size " << width << "," << height << "\n"
    << "}\n"
    << "set output \"" << t.stage << ".png\"\n"
    << "set termoption noenhanced\n"  // setting names hold underscores, not subscripts
    << "set grid\nset key below\n";
  if (panels > 1) g << "set multiplot layout 1," << panels << " title \"" << title << "\"\n";
  else g << "set title \"" << title << "\"\n";
  return g.str();
}

std::string refineScript(const SweepTable& t, const std::string& scene_text) {
  const std::vector<Series> series = {
      {"Ceres L-BFGS, iterations", {{"method", "ceres_lbfgs"}}, "with linespoints pt 7 lw 2", "max_iterations"},
      {"Ceres L-BFGS, tolerance", {{"method", "ceres_lbfgs_tolerance"}}, "with points pt 5 ps 1.3", "function_tolerance"},
      {"Adam (paper), iterations", {{"method", "adam"}}, "with linespoints pt 9 ps 1.3 lw 1", "max_iterations"},
      {"filter, no optimisation", {{"method", "filter_only"}}, "with points pt 11 ps 2", ""},
      {"upsampling only", {{"method", "upsample_only"}}, "with points pt 13 ps 2", ""}};
  std::string g = scriptHeader(t, "Depth refinement: accuracy against time, " + scene_text, 2);
  g += "set logscale x\nset xlabel \"seconds (whole refine stage)\"\nset ylabel \"depth AbsRel\"\n";
  g += plotCommand(t, series, "seconds", "abs_rel");
  g += "set ylabel \"normals of the depth, mean error (deg)\"\n";
  g += plotCommand(t, series, "seconds", "normal_mean_deg");
  return g + "unset multiplot\n";
}

std::string meshScript(const SweepTable& t, const std::string& scene_text, bool distances) {
  const std::vector<Series> series = {{"mesh stage settings", {}, "with points pt 7 ps 1.5", "setting"}};
  std::string g = scriptHeader(t, "Mesh stage: accuracy against time, " + scene_text, distances ? 2 : 1);
  g += "set xlabel \"seconds (mesh stage)\"\n";
  if (distances) {
    g += "set ylabel \"mean distance to the true surfaces (m)\"\n";
    g += plotCommand(t, series, "seconds", "mean_to_ref_m");
  }
  g += "set ylabel \"holes left open\"\n";
  g += plotCommand(t, series, "seconds", "holes_left_open");
  return g + (distances ? "unset multiplot\n" : "");
}

std::string renderScript(const SweepTable& t, const std::string& scene_text) {
  const std::vector<Series> series = {
      {"power, fixed spp", {{"mode", "fixed"}, {"light_sampler", "power"}}, "with linespoints pt 7 lw 2", "max_spp"},
      {"uniform, fixed spp", {{"mode", "fixed"}, {"light_sampler", "uniform"}}, "with linespoints pt 5 lw 1", ""},
      {"hierarchy, fixed spp", {{"mode", "fixed"}, {"light_sampler", "hierarchy"}}, "with linespoints pt 9 lw 1", ""},
      {"power, adaptive (target)", {{"mode", "adaptive"}}, "with linespoints pt 13 ps 1.5 lw 1 dt 2",
       "relative_error_target"}};
  std::string g = scriptHeader(t, "Rendering: relative RMSE of non-emitting pixels against time, " + scene_text, 2);
  g += "set logscale xy\nset xlabel \"seconds (render)\"\nset ylabel \"relative RMSE of luminance\"\n";
  g += plotCommand(t, series, "seconds", "relative_rmse");
  g += "set xlabel \"mean samples per pixel\"\n";
  g += plotCommand(t, series, "mean_spp", "relative_rmse");
  return g + "unset multiplot\n";
}

std::string endToEndScript(const SweepTable& t, const std::string& scene_text) {
  const std::vector<Series> series = {{"solo night pipeline settings", {}, "with points pt 7 ps 1.5", "setting"}};
  std::string g = scriptHeader(t, "End to end: relative RMSE of the linear night render against time, " + scene_text, 1);
  g += "set xlabel \"seconds (input to post-process)\"\nset ylabel \"relative RMSE of luminance vs reference\"\n";
  return g + plotCommand(t, series, "seconds", "relative_rmse");
}

std::string describeFiles(const std::string& stage) {
  if (stage == "refine")
    return "depth refinement: Ceres L-BFGS iterations and function tolerance, Adam iterations, the filter alone and "
           "upsampling alone -> AbsRel, RMSE (m) and the mean/median angle (deg) of the depth's normals against "
           "the exact depth and normals; seconds of the whole stage";
  if (stage == "mesh")
    return "mesh stage on the default refined depth: hole filling on/off, fairing limit, solids on/off -> distances "
           "to the true box mesh (m), holes left open; seconds of the stage (quality evaluation off, as in solo night)";
  if (stage == "render")
    return "path tracing of the default night scene: samples per pixel per light sampler, adaptive noise target -> "
           "relative RMSE of the luminance of non-emitting pixels against a converged render of the same scene";
  return "the whole solo night pipeline at a few settings -> relative RMSE of the linear render against a converged "
         "render of the scene made from the exact depth; seconds of every stage";
}

// ---- solo bench accuracy ----------------------------------------------------------------------

/// Refuses bad options before anything is read or written.
void checkAccuracyOptions(const BenchAccuracyOptions& o) {
  for (const std::string& s : o.stages)
    if (std::find(kStages.begin(), kStages.end(), s) == kStages.end())
      throw InputError("--stages", "unknown stage \"" + s + "\" (use refine, mesh, render, end_to_end)");
  if (o.stages.empty()) throw InputError("--stages", "no stage to run");
  if (o.repeats < 1) throw InputError("--repeats", "must be at least 1");
  if (o.reference_spp < 0) throw InputError("--reference-spp", "must be positive (0 = the default)");
  if (!o.scene && (o.width < 16 || o.height < 16 || o.width > 8192 || o.height > 8192))
    throw InputError("--scene-size", "image size must be between 16 and 8192 pixels per side");
  std::error_code ec;
  if (fs::exists(o.output, ec) && !fs::is_directory(o.output, ec))
    throw InputError(o.output, "exists and is not a folder");
}

/// The manifest of a given scene (a `solo synth` folder or its scene.json), checked to exist
/// with its ground truth.
fs::path givenManifest(const fs::path& scene) {
  std::error_code ec;
  const fs::path manifest = fs::is_directory(scene, ec) ? scene / "scene.json" : scene;
  if (!fs::exists(manifest, ec)) throw InputError(manifest, "not found (a `solo synth` folder or its scene.json)");
  const fs::path truth_manifest = groundTruthManifest(manifest);
  if (!fs::exists(truth_manifest, ec)) throw InputError(truth_manifest, "not found (the scene's ground truth)");
  return manifest;
}

/// Makes the synthetic street in output/scene as `solo synth` does (its summary on stdout);
/// returns its manifest.
fs::path makeAccuracyScene(const BenchAccuracyOptions& o) {
  SyntheticSceneOptions synth;
  synth.seed = o.seed;
  synth.width = o.width;
  synth.height = o.height;
  synth.force = true;
  const fs::path folder = o.output / "scene";
  say("solo bench accuracy: making the synthetic scene " + folder.string() + " ...");
  const SyntheticSceneResult made = writeSyntheticScene(folder, synth);
  std::cout << reportSummary(made.report) << "scene: " << made.manifest.string() << "\n";
  return folder / "scene.json";
}

AccuracySweepOptions sweepOptions(const BenchAccuracyOptions& o, double input_seconds) {
  AccuracySweepOptions options;
  options.seed = o.seed;
  options.quick = o.quick;
  options.repeats = o.repeats;
  options.reference_spp = o.reference_spp > 0 ? o.reference_spp : (o.quick ? 64 : 256);
  options.distance_samples = o.quick ? 5000 : 50000;
  options.input_seconds = input_seconds;
  options.illuminant_table = defaultIlluminantTable();
  options.progress = say;
  return options;
}

/// What the sweeps produced: their tables, the files written (in order) and notes for the README.
struct AccuracyRun {
  std::vector<SweepTable> tables;
  std::vector<std::string> written, notes;
};

SweepTable runSweep(AccuracySweep& sweep, const std::string& stage) {
  return stage == "refine" ? sweep.refine()
         : stage == "mesh" ? sweep.mesh()
         : stage == "render" ? sweep.render()
                             : sweep.endToEnd();
}

/// Writes the gnuplot script of `t` and, when `gnuplot`, runs it for the PNG.
void writePlot(const BenchAccuracyOptions& o, const SweepTable& t, const std::string& scene_text, bool gnuplot,
               AccuracyRun& run) {
  const std::string& stage = t.stage;
  const bool distances = stage != "mesh" || (!t.rows.empty() && !t.rows.front()[t.column("mean_to_ref_m")].empty());
  const std::string script = stage == "refine" ? refineScript(t, scene_text)
                             : stage == "mesh" ? meshScript(t, scene_text, distances)
                             : stage == "render" ? renderScript(t, scene_text)
                                                 : endToEndScript(t, scene_text);
  writeTextAtomically(o.output / (stage + ".gp"), script);
  run.written.push_back(stage + ".gp");
  if (!gnuplot) return;
  std::error_code ec;
  const std::string command =
      "cd " + shellQuoted(o.output.string()) + " && gnuplot " + shellQuoted(stage + ".gp") + " 2>&1";
  if (std::system(command.c_str()) == 0 && fs::exists(o.output / (stage + ".png"), ec)) {
    run.written.push_back(stage + ".png");
  } else {
    run.notes.push_back("gnuplot failed on " + stage + ".gp: no " + stage + ".png");
    say("solo bench accuracy: " + run.notes.back());
  }
}

/// Runs the chosen sweeps in kStages' order, writing STAGE.csv (and STAGE.gp, STAGE.png) of each.
AccuracyRun runSweeps(const BenchAccuracyOptions& o, AccuracySweep& sweep, const std::string& scene_text) {
  const bool gnuplot = o.plots && onPath("gnuplot");
  AccuracyRun run;
  for (const std::string& stage : kStages) {
    if (std::find(o.stages.begin(), o.stages.end(), stage) == o.stages.end()) continue;
    say("solo bench accuracy: " + stage + " sweep ...");
    SweepTable t = runSweep(sweep, stage);
    writeTextAtomically(o.output / (stage + ".csv"), t.csv());
    run.written.push_back(stage + ".csv");
    if (o.plots) writePlot(o, t, scene_text, gnuplot, run);
    run.tables.push_back(std::move(t));
  }
  if (o.plots && !gnuplot) {
    run.notes.push_back("gnuplot is not on PATH: the .gp scripts are written, no PNG (install gnuplot-nox, then run "
                        "`gnuplot STAGE.gp` in this folder)");
    say("solo bench accuracy: " + run.notes.back());
  }
  return run;
}

/// What the README says about the run besides the tables.
struct AccuracyReadmeFacts {
  fs::path manifest, truth_manifest;
  int width = 0, height = 0;
  double load_start = 0, load_end = 0;
  double wall_seconds = 0;
};

/// README: what was run, on what, under which load.
std::string accuracyReadme(const BenchAccuracyOptions& o, const AccuracySweepOptions& options,
                           const AccuracyReadmeFacts& f, const AccuracyRun& run) {
  std::ostringstream r;
  const std::time_t now = std::time(nullptr);
  char date[64];
  std::strftime(date, sizeof date, "%Y-%m-%d %H:%M:%S %Z", std::localtime(&now));
  r << "# solo bench accuracy\n\n"
    << "What accuracy costs in time, stage by stage and end to end (docs/accuracy.md explains the curves).\n\n"
    << "- scene: `" << f.manifest.string() << "` (" << f.width << "x" << f.height << ", "
    << (o.scene ? "given" : "made by `solo synth` with the seed below") << "), ground truth `"
    << f.truth_manifest.string() << "`\n"
    << "- seed: " << o.seed << " (also in every CSV row)\n"
    << "- mode: " << (o.quick ? "quick (fewer points)" : "full") << "; reference renders "
    << options.reference_spp << " spp; timing: median of up to " << o.repeats << " runs when one run takes under "
    << options.cheap_seconds << " s, else one run (column `repeats`)\n"
    << "- machine: " << std::thread::hardware_concurrency() << " hardware threads; load average (1 min) "
    << f.load_start << " at the start, " << f.load_end << " at the end (column `load_1min`: at each point's end); "
    << "wall time of the whole run " << static_cast<int>(f.wall_seconds) << " s; finished " << date << "\n"
    << "- solo " << soloVersion() << ";";
  for (const auto& [library, version] : dependencyVersions()) r << " " << library << " " << version << ";";
  r << "\n\n## Files\n\n";
  for (const SweepTable& t : run.tables) {
    const bool png = std::find(run.written.begin(), run.written.end(), t.stage + ".png") != run.written.end();
    r << "- `" << t.stage << ".csv` (" << t.rows.size() << " rows), `" << t.stage << ".gp`"
      << (png ? ", `" + t.stage + ".png`" : "") << ": " << describeFiles(t.stage) << ".\n";
    for (const std::string& n : t.notes) r << "  - " << n << "\n";
  }
  if (!run.notes.empty()) {
    r << "\n## Notes\n\n";
    for (const std::string& n : run.notes) r << "- " << n << "\n";
  }
  return r.str();
}

}  // namespace

int runBenchAccuracy(const BenchAccuracyOptions& o) {
  Stopwatch total;
  checkAccuracyOptions(o);
  // The scene: checked completely before anything is written.
  const fs::path given = o.scene ? givenManifest(*o.scene) : fs::path();
  fs::create_directories(o.output);
  AccuracyReadmeFacts facts;
  facts.load_start = loadAverage1Min();
  const fs::path manifest = o.scene ? given : makeAccuracyScene(o);
  AccuracySweepInput input = readAccuracySweepInput(manifest);
  facts.manifest = input.manifest;
  facts.truth_manifest = input.truth_manifest;
  facts.width = input.scene.width();
  facts.height = input.scene.height();
  const AccuracySweepOptions options = sweepOptions(o, input.input_seconds);
  AccuracySweep sweep(std::move(input.scene), std::move(input.truth), std::move(input.truth_mesh), options);

  const std::string scene_text = std::to_string(facts.width) + "x" + std::to_string(facts.height) +
                                 " synthetic street, seed " + std::to_string(o.seed);
  const AccuracyRun run = runSweeps(o, sweep, scene_text);
  facts.load_end = loadAverage1Min();
  facts.wall_seconds = total.seconds();
  writeTextAtomically(o.output / "README.md", accuracyReadme(o, options, facts, run));
  std::cout << "solo bench accuracy: " << run.tables.size() << " sweeps in " << static_cast<int>(total.seconds())
            << " s, written to " << o.output.string() << ":";
  for (const std::string& f : run.written) std::cout << " " << f;
  std::cout << " README.md\n";
  return 0;
}

namespace {

// ---- solo bench realism ---------------------------------------------------------------------

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
std::vector<RealismCase> realismCases(const BenchRealismOptions& o) {
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

/// One row of realism.csv: the scene's names and its figures by column (none: no value).
struct RealismRow {
  std::string scene, variant, street_seed;
  std::vector<std::pair<std::string, std::optional<double>>> values;

  std::optional<double> get(const std::string& key) const {
    for (const auto& [k, v] : values)
      if (k == key) return v;
    return std::nullopt;
  }
};

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

  RealismRow row{c.name, c.variant, c.street ? std::to_string(c.street_seed) : std::string(), {}};
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

/// The row of per-column medians (mean of the two middle values for an even count) over the
/// values the rows have; no size.
RealismRow medianRow(const std::vector<RealismRow>& rows) {
  RealismRow median{"MEDIAN", "", "", {}};
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

/// The targets of docs/realism.md (and the road's EN 13201 M1-M6 range) a row misses: keys
/// mean, clipped, bright, noise, chroma_noise, cast, night_to_day, road_cd_m2. A statistic
/// without a value misses its target.
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

std::string shortestNumber(double v) {
  char text[32];
  const auto end = std::to_chars(text, text + sizeof text, v).ptr;
  return std::string(text, end);
}

std::string realismCsv(const std::vector<RealismRow>& rows, std::uint64_t seed, const std::string& preset) {
  std::string csv = "scene,variant,street_seed,seed,preset";
  for (const auto& [key, value] : rows.front().values) csv += "," + key;
  csv += ",missed_targets\n";
  for (const RealismRow& r : rows) {
    csv += r.scene + "," + r.variant + "," + r.street_seed + "," + std::to_string(seed) + "," + preset;
    for (const auto& [key, value] : r.values) csv += "," + (value ? shortestNumber(*value) : std::string());
    std::string missed;
    for (const std::string& m : missedTargets(r)) missed += (missed.empty() ? "" : ";") + m;
    csv += "," + missed + "\n";
  }
  return csv;
}

std::string formatted(const std::optional<double>& v, const char* format) {
  if (!v) return "none";
  char text[48];
  std::snprintf(text, sizeof text, format, *v);
  return text;
}

/// The markdown table: a targets line, one line per row; a missed target's cell ends in " ✗".
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

std::string realismReadme(const BenchRealismOptions& o, const std::vector<RealismRow>& rows, double load_start,
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
    << "- seed: " << o.seed << " (lights, render and sensor noise of every run; the streets' own seeds are in "
    << "their names and in column `street_seed`)\n"
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

std::string progressLine(std::size_t i, std::size_t count, const RealismRow& r) {
  char line[256];
  std::snprintf(line, sizeof line,
                "solo bench realism: [%zu/%zu] %s %sx%s: mean %s, clipped %s, bright %s, noise %s, chroma %s, "
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

int runBenchRealism(const BenchRealismOptions& o) {
  Stopwatch wall;
  if (o.width < 16 || o.height < 16 || o.width > 4096 || o.height > 4096)
    throw InputError("--size", "street size must be between 16 and 4096 pixels per side");
  NightConversionOptions night = nightPreset(o.preset);  // throws for an unknown preset
  night.seed = o.seed;
  std::error_code ec;
  if (fs::exists(o.output, ec) && !fs::is_directory(o.output, ec))
    throw InputError(o.output, "exists and is not a folder");
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
    rows.push_back(runRealismCase(c, scene_file, night, o.output, night8));
    tiles.push_back({c.name, night8});
    say(progressLine(i, cases.size(), rows.back()));
  }
  rows.push_back(medianRow(rows));
  const double load_end = loadAverage1Min();

  writeTextAtomically(o.output / "realism.csv", realismCsv(rows, o.seed, o.preset));
  writeImage(o.output / "contact_sheet.png", composeContactSheet(tiles));
  writeTextAtomically(o.output / "README.md", realismReadme(o, rows, load_start, load_end, wall.seconds()));
  std::cout << realismTable(rows) << "\nsolo bench realism: " << cases.size() << " scenes in "
            << static_cast<int>(wall.seconds()) << " s, written to " << o.output.string()
            << ": realism.csv README.md contact_sheet.png night/\n";
  return 0;
}

}  // namespace solo::tools
