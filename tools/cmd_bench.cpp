// `solo bench accuracy`: what accuracy costs in time. Makes (or takes) a synthetic scene with
// exact ground truth, runs the sweeps of pipeline/accuracy_sweep.h, and writes into OUT_DIR one CSV per
// stage (refine, mesh, render, end_to_end), a gnuplot script per plot (run when gnuplot is on
// PATH, PNG output) and a README with the seed, the machine's load and what each file holds.
//
// `solo bench realism`: the realism benchmark of pipeline/realism_bench.h (`solo night`'s
// pipeline on the embedded default scene and on synthetic streets; realism.csv, README.md and a
// contact sheet of the night images); here its progress lines and the table on the terminal.

#include "commands.h"
#include <solo/pipeline/accuracy_sweep.h>
#include <solo/pipeline/data_dir.h>
#include <solo/pipeline/realism_bench.h>

#include <solo/core/atomic_file.h>
#include <solo/core/error.h>
#include <solo/core/report.h>
#include <solo/core/scene.h>
#include <solo/core/version.h>
#include <solo/synth/scene_folder.h>

#include <algorithm>
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
      {"power, fixed spp", {{"mode", "fixed"}, {"light_sampler", "power"}, {"near_field", "off"}},
       "with linespoints pt 7 lw 2", "max_spp"},
      {"power with near field", {{"mode", "fixed"}, {"light_sampler", "power"}, {"near_field", "on"}},
       "with linespoints pt 6 lw 1 dt 3", ""},
      {"uniform, fixed spp", {{"mode", "fixed"}, {"light_sampler", "uniform"}}, "with linespoints pt 5 lw 1", ""},
      {"hierarchy, fixed spp", {{"mode", "fixed"}, {"light_sampler", "hierarchy"}, {"near_field", "off"}},
       "with linespoints pt 9 lw 1", ""},
      {"hierarchy with near field", {{"mode", "fixed"}, {"light_sampler", "hierarchy"}, {"near_field", "on"}},
       "with linespoints pt 8 lw 1 dt 3", ""},
      {"power, adaptive (target)", {{"mode", "adaptive"}}, "with linespoints pt 13 ps 1.5 lw 1 dt 2",
       "relative_error_target"},
      {"power, noise target 2-8 spp (shadow roulette)", {{"mode", "noise_target"}, {"near_field", "off"}},
       "with points pt 11 ps 1.5", ""},
      {"the same with near field", {{"mode", "noise_target"}, {"near_field", "on"}}, "with points pt 10 ps 1.5", ""}};
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

// ---- solo bench realism ---------------------------------------------------------------------

int runBenchRealism(const BenchRealismOptions& o) {
  Stopwatch wall;
  const std::vector<RealismRow> rows =
      runRealismBench(o, [](const std::string& line) { say("solo bench realism: " + line); });
  std::cout << realismTable(rows) << "\nsolo bench realism: " << rows.size() - 1 << " scenes in "
            << static_cast<int>(wall.seconds()) << " s, written to " << o.output.string()
            << ": realism.csv README.md contact_sheet.png night/\n";
  return 0;
}

}  // namespace solo::tools
