// Depth refinement on a synthetic scene with exact ground truth: what each step buys and what
// it costs. Not a Google Benchmark: one run of each method, the Ceres solve and Adam observed
// at every iteration, written as a CSV (docs/data/) and a table on stdout.
// Run (docs/depth-refinement.md):
//   build/release/tools/solo synth -o /tmp/s1080 --size 1920x1080 --seed 1
//   build/release/tests/benchmarks/bench_refine /tmp/s1080 docs/data/depth_refinement_1080p.csv
// Several scenes, the optimisation step only (from the depth refineDepth filters, with its
// normals and uncertain mask), per solver setting and iteration:
//   bench_refine --sweep OUT.csv [--config NAME:key=value,...]... SCENE_DIR...
//   keys: objective (paper|default: the whole objective, set before the keys after it),
//   it (iterations), dw (lambda2), tw (lambda1), loss (squared|huber|cauchy|deadzone),
//   c (loss scale), stencil (central|onesided), units (metres|footprints)

#include <solo/geometry/adam_depth_optimizer.h>
#include <solo/geometry/depth_metrics.h>
#include <solo/geometry/depth_refinement.h>
#include <solo/core/image_io.h>
#include <solo/geometry/instance_bilateral_filter.h>
#include <solo/geometry/normal_guided_optimization.h>
#include <solo/geometry/normal_metrics.h>
#include <solo/geometry/normals_from_depth.h>
#include <solo/core/scene.h>
#include <solo/geometry/uncertain_regions.h>
#include <solo/geometry/upsample_maps.h>

#include <opencv2/imgproc.hpp>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;

namespace {

using solo::sizeText;

struct Truth {
  cv::Mat depth_m, normals;
};

struct Row {
  Row(std::string method_name, std::string size, int iteration_number = -1, double time_s = 0,
      solo::ObjectiveValue objective = {}, bool with_value = false)
      : method(std::move(method_name)), resolution(std::move(size)), iteration(iteration_number), seconds(time_s),
        value(objective), has_value(with_value) {}
  std::string method;
  std::string resolution;
  int iteration = -1;
  double seconds = 0;
  solo::ObjectiveValue value;
  bool has_value = false;
  bool has_accuracy = false;
  double abs_rel = 0, rmse_m = 0, normal_mean_deg = 0, normal_median_deg = 0;
};

void measure(Row& row, const cv::Mat& depth_m, const Truth& truth, const solo::PinholeCamera& camera) {
  solo::DepthEvaluationInput d;
  d.prediction_m = depth_m, d.ground_truth_m = truth.depth_m;
  const solo::DepthMetrics dm = solo::evaluateDepth(d);
  solo::NormalEvaluationInput n;
  n.prediction = solo::normalsFromDepth(depth_m, camera), n.ground_truth = truth.normals;
  const solo::NormalMetrics nm = solo::evaluateNormals(n);
  row.has_accuracy = true;
  row.abs_rel = dm.abs_rel, row.rmse_m = dm.rmse_m;
  row.normal_mean_deg = nm.mean_deg, row.normal_median_deg = nm.median_deg;
}

class Table {
 public:
  explicit Table(const fs::path& csv) : csv_(csv) {
    csv_ << "method,resolution,iteration,seconds,objective,tangent_term,data_term_m2,abs_rel,rmse_m,"
            "normal_mean_deg,normal_median_deg\n";
    std::printf("%-26s %-10s %5s %9s %12s %9s %8s %9s %9s\n", "method", "size", "iter", "seconds", "objective",
                "AbsRel", "RMSE m", "n mean", "n median");
  }
  void add(const Row& r) {
    const auto num = [](bool has, double v) { return has ? std::to_string(v) : std::string(); };
    csv_ << r.method << "," << r.resolution << "," << (r.iteration >= 0 ? std::to_string(r.iteration) : "") << ","
         << r.seconds << "," << num(r.has_value, r.value.total) << "," << num(r.has_value, r.value.tangent) << ","
         << num(r.has_value, r.value.data) << "," << num(r.has_accuracy, r.abs_rel) << ","
         << num(r.has_accuracy, r.rmse_m) << "," << num(r.has_accuracy, r.normal_mean_deg) << ","
         << num(r.has_accuracy, r.normal_median_deg) << "\n";
    if (r.has_accuracy || r.iteration <= 0)
      std::printf("%-26s %-10s %5d %9.3f %12.6g %9.5f %8.4f %9.3f %9.3f\n", r.method.c_str(), r.resolution.c_str(),
                  r.iteration, r.seconds, r.has_value ? r.value.total : 0.0, r.abs_rel, r.rmse_m, r.normal_mean_deg,
                  r.normal_median_deg);
    std::fflush(stdout);
  }

 private:
  std::ofstream csv_;
};

// ---- --sweep: the optimisation step on several scenes ----

struct SweepConfig {
  std::string name;
  solo::NormalGuidedOptimizationOptions options;
};

// NAME:key=value,... (keys in the file comment) over the default options.
SweepConfig parseConfig(const std::string& text) {
  SweepConfig config;
  const std::size_t colon = text.find(':');
  config.name = text.substr(0, colon);
  std::stringstream rest(colon == std::string::npos ? std::string() : text.substr(colon + 1));
  std::string item;
  while (std::getline(rest, item, ',')) {
    const std::size_t eq = item.find('=');
    const std::string key = item.substr(0, eq), value = item.substr(eq + 1);
    solo::NormalGuidedOptimizationOptions& o = config.options;
    if (key == "objective") o.objective = value == "paper" ? solo::NormalGuidedObjectiveOptions::paper()
                                                           : solo::NormalGuidedObjectiveOptions{};
    else if (key == "it") o.max_iterations = std::stoi(value);
    else if (key == "dw") o.objective.data_weight = std::stod(value);
    else if (key == "tw") o.objective.tangent_weight = std::stod(value);
    else if (key == "c") o.objective.tangent_loss_scale = std::stod(value);
    else if (key == "loss")
      o.objective.tangent_loss = value == "huber"    ? solo::TangentLoss::Huber
                                 : value == "cauchy" ? solo::TangentLoss::Cauchy
                                 : value == "deadzone" ? solo::TangentLoss::DeadZone
                                                     : solo::TangentLoss::Squared;
    else if (key == "stencil")
      o.objective.tangent_stencil = value == "onesided" ? solo::TangentStencil::OneSided : solo::TangentStencil::Central;
    else if (key == "units")
      o.objective.data_units = value == "footprints" ? solo::DataUnits::Footprints : solo::DataUnits::Metres;
    else throw std::runtime_error("unknown config key " + key);
  }
  return config;
}

struct Accuracy {
  double abs_rel = 0, rmse_m = 0, normal_mean_deg = 0, normal_median_deg = 0;
};

Accuracy accuracyOf(const cv::Mat& depth_m, const Truth& truth, const solo::PinholeCamera& camera) {
  Row row{"", ""};
  measure(row, depth_m, truth, camera);
  return {row.abs_rel, row.rmse_m, row.normal_mean_deg, row.normal_median_deg};
}

int sweep(const fs::path& csv_path, const std::vector<SweepConfig>& configs, const std::vector<fs::path>& dirs) {
  const std::set<int> curve = {0, 1, 2, 3, 5, 7, 10, 15, 20, 30, 40, 60};
  std::ofstream csv(csv_path);
  csv << "scene,config,iteration,seconds,objective,abs_rel,rmse_m,normal_mean_deg,normal_median_deg\n";
  struct Tally {
    int scenes = 0, depth_kept = 0, normals_better = 0;
    double abs_rel_ratio = 0, rmse_ratio = 0, normal_gain_deg = 0, seconds = 0;
  };
  std::map<std::string, Tally> tally;
  for (const fs::path& dir : dirs) {
    const solo::Scene scene = solo::loadScene(dir / "scene.json");
    const solo::Scene exact = solo::loadScene(dir / "gt" / "scene.json");
    const Truth truth{exact.depth_m, exact.normals};
    solo::DepthRefinementOptions steps;
    steps.optimize = false;
    const solo::DepthRefinementResult r = solo::refineDepth(scene, steps);
    const Accuracy f = accuracyOf(r.filtered_depth_m, truth, scene.camera);
    {
      solo::NormalEvaluationInput n;
      n.prediction = r.normals, n.ground_truth = truth.normals;
      const solo::NormalMetrics nm = solo::evaluateNormals(n);
      const Accuracy exact_depth = accuracyOf(truth.depth_m, truth, scene.camera);
      std::printf("against the true normals: predicted normals mean %.3f, median %.3f deg; normals of the true depth "
                  "mean %.3f, median %.3f deg\n",
                  nm.mean_deg, nm.median_deg, exact_depth.normal_mean_deg, exact_depth.normal_median_deg);
    }
    const std::string name = dir.filename().string();
    std::printf("\n%s (%s, normals %s)\n%-22s %4s %7s %9s %8s %8s %8s\n", name.c_str(), sizeText(scene.image).c_str(),
                r.normals_from_depth ? "of the filtered depth" : "estimated", "config", "iter", "seconds", "AbsRel",
                "RMSE m", "n mean", "n med");
    std::printf("%-22s %4s %7s %9.5f %8.4f %8.3f %8.3f\n", "filtered", "", "", f.abs_rel, f.rmse_m, f.normal_mean_deg,
                f.normal_median_deg);
    csv << name << ",filtered,,," << "," << f.abs_rel << "," << f.rmse_m << "," << f.normal_mean_deg << ","
        << f.normal_median_deg << "\n";
    for (const SweepConfig& config : configs) {
      const solo::NormalGuidedOptimizationResult result = solo::optimizeDepthWithNormals(
          r.filtered_depth_m, r.normals, r.uncertain, r.maps.instances, scene.camera, config.options,
          [&](const solo::OptimizationIteration& it, const cv::Mat& depth) {
            if (!curve.count(it.iteration)) return;
            const Accuracy a = accuracyOf(depth, truth, scene.camera);
            csv << name << "," << config.name << "," << it.iteration << "," << it.seconds << "," << it.value.total << ","
                << a.abs_rel << "," << a.rmse_m << "," << a.normal_mean_deg << "," << a.normal_median_deg << "\n";
          });
      const Accuracy a = accuracyOf(result.depth_m, truth, scene.camera);
      const int iterations = result.trace.empty() ? 0 : result.trace.back().iteration;
      std::printf("%-22s %4d %7.3f %9.5f %8.4f %8.3f %8.3f\n", config.name.c_str(), iterations, result.report.seconds,
                  a.abs_rel, a.rmse_m, a.normal_mean_deg, a.normal_median_deg);
      std::fflush(stdout);
      Tally& t = tally[config.name];
      ++t.scenes;
      t.depth_kept += a.abs_rel <= f.abs_rel && a.rmse_m <= f.rmse_m;
      t.normals_better += a.normal_mean_deg < f.normal_mean_deg && a.normal_median_deg <= f.normal_median_deg;
      t.abs_rel_ratio += a.abs_rel / f.abs_rel, t.rmse_ratio += a.rmse_m / f.rmse_m;
      t.normal_gain_deg += f.normal_mean_deg - a.normal_mean_deg, t.seconds += result.report.seconds;
    }
  }
  std::printf("\n%-22s %6s %12s %14s %10s %10s %12s %9s\n", "config", "scenes", "depth kept", "normals better",
              "AbsRel x", "RMSE x", "n gain deg", "seconds");
  for (const SweepConfig& config : configs) {
    const Tally& t = tally[config.name];
    const double n = std::max(1, t.scenes);
    std::printf("%-22s %6d %12d %14d %10.4f %10.4f %12.3f %9.3f\n", config.name.c_str(), t.scenes, t.depth_kept,
                t.normals_better, t.abs_rel_ratio / n, t.rmse_ratio / n, t.normal_gain_deg / n, t.seconds / n);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc >= 3 && std::string(argv[1]) == "--sweep") {
    std::vector<SweepConfig> configs;
    std::vector<fs::path> dirs;
    for (int i = 3; i < argc; ++i) {
      if (std::string(argv[i]) == "--config" && i + 1 < argc) configs.push_back(parseConfig(argv[++i]));
      else dirs.emplace_back(argv[i]);
    }
    if (configs.empty()) configs = {parseConfig("default"), parseConfig("paper:objective=paper,it=10")};
    return sweep(argv[2], configs, dirs);
  }
  if (argc != 3) {
    std::fprintf(stderr, "usage: bench_refine SYNTH_SCENE_DIR OUTPUT.csv\n");
    return 2;
  }
  const fs::path dir = argv[1];
  const solo::Scene scene = solo::loadScene(dir / "scene.json");
  const solo::Scene exact = solo::loadScene(dir / "gt" / "scene.json");
  const Truth truth{exact.depth_m, exact.normals};
  const solo::PinholeCamera& camera = scene.camera;
  const std::string size = sizeText(scene.image);
  Table table(argv[2]);

  // Steps 1-3, each timed alone.
  solo::Stopwatch clock;
  const solo::UpsampledMaps maps = solo::upsampleMaps(scene);
  const double upsample_s = clock.seconds();
  clock = {};
  const solo::InstanceBilateralFilterResult filtered = solo::instanceBilateralFilter(maps.depth_m, maps.instances);
  const double filter_s = clock.seconds();
  clock = {};
  const solo::UncertainRegionResult uncertain = solo::findUncertainRegions(filtered.depth_m, maps.labels);
  const double uncertain_s = clock.seconds();
  std::printf("upsample %.3f s, filter %.3f s, uncertain %.3f s (%lld uncertain pixels)\n", upsample_s, filter_s,
              uncertain_s, static_cast<long long>(cv::countNonZero(uncertain.mask)));
  const solo::NormalGuidedObjective objective(filtered.depth_m, maps.normals, uncertain.mask, camera, {}, maps.instances);
  const auto valueOf = [&](const cv::Mat& depth) {
    solo::ObjectiveValue v;
    const std::vector<double> z = objective.fromImage(depth);
    objective.evaluate(z.data(), v);
    return v;
  };
  {
    Row raw{"raw", size};
    raw.seconds = upsample_s;
    raw.value = valueOf(maps.depth_m), raw.has_value = true;
    measure(raw, maps.depth_m, truth, camera);
    table.add(raw);
    Row f{"filtered", size};
    f.seconds = filter_s;
    f.value = valueOf(filtered.depth_m), f.has_value = true;
    measure(f, filtered.depth_m, truth, camera);
    table.add(f);
  }

  // Adam, the paper's optimiser: accuracy at 0, 100, 1000 iterations, the objective at each.
  double adam_seconds = 0, adam_objective = 0;
  {
    const std::set<int> measured = {0, 100, 1000};
    solo::optimizeDepthWithAdam(filtered.depth_m, maps.normals, uncertain.mask, maps.instances, camera, {},
                                [&](const solo::OptimizationIteration& it, const cv::Mat& depth) {
                                  Row r{it.iteration == 100 ? "adam_100" : it.iteration == 1000 ? "adam_1000" : "adam",
                                        size, it.iteration, it.seconds, it.value, true};
                                  if (measured.count(it.iteration)) measure(r, depth, truth, camera);
                                  if (it.iteration % 10 == 0 || measured.count(it.iteration)) table.add(r);
                                  adam_seconds = it.seconds, adam_objective = it.value.total;
                                });
  }

  // Ceres, whole-image L-BFGS (the default layout): every iteration measured.
  double ceres_seconds = 0, ceres_objective = 0;
  {
    solo::NormalGuidedOptimizationOptions curve;
    curve.max_iterations = 60;  // past the default 10, to show where the objective leads
    solo::NormalGuidedOptimizationResult result = solo::optimizeDepthWithNormals(
        filtered.depth_m, maps.normals, uncertain.mask, maps.instances, camera, curve,
        [&](const solo::OptimizationIteration& it, const cv::Mat& depth) {
          Row r{"ceres_lbfgs", size, it.iteration, it.seconds, it.value, true};
          measure(r, depth, truth, camera);
          table.add(r);
        });
    ceres_seconds = result.report.seconds, ceres_objective = result.final.total;
    for (const solo::OptimizationIteration& it : result.trace)
      if (it.level > 0) table.add(Row{"ceres_lbfgs_level" + std::to_string(it.level), size, it.iteration, it.seconds, it.value, true});
    std::printf("ceres: %s\n", result.termination.c_str());
  }
  // Ceres with the coarse-to-fine start, and without Jacobi scaling, for the docs.
  for (const auto& [name, levels, scaling] :
       {std::tuple{"ceres_lbfgs_pyramid4", 4, true}, std::tuple{"ceres_lbfgs_no_jacobi_scaling", 0, false}}) {
    solo::NormalGuidedOptimizationOptions o;
    o.coarse_levels = levels, o.jacobi_scaling = scaling, o.max_iterations = 60;
    solo::NormalGuidedOptimizationResult result =
        solo::optimizeDepthWithNormals(filtered.depth_m, maps.normals, uncertain.mask, maps.instances, camera, o);
    for (const solo::OptimizationIteration& it : result.trace) table.add(Row{name, size, it.iteration, it.seconds, it.value, true});
    Row last{name, size, -1, result.report.seconds, result.final, true};
    measure(last, result.depth_m, truth, camera);
    table.add(last);
  }

  // Layouts at a quarter of the resolution: per-pixel residual blocks (LM) vs whole-image L-BFGS.
  {
    const cv::Size small(scene.image.cols / 4, scene.image.rows / 4);
    const solo::PinholeCamera small_camera = camera.scaledTo(small.width, small.height);
    cv::Mat d, n, u, h;
    cv::resize(maps.instances, h, small, 0, 0, cv::INTER_NEAREST);
    cv::resize(filtered.depth_m, d, small, 0, 0, cv::INTER_NEAREST);
    cv::resize(maps.normals, n, small, 0, 0, cv::INTER_NEAREST);
    cv::resize(uncertain.mask, u, small, 0, 0, cv::INTER_NEAREST);
    for (const auto layout : {solo::DepthSolverLayout::PerPixelResidualBlocks, solo::DepthSolverLayout::WholeImageLbfgs}) {
      solo::NormalGuidedOptimizationOptions o;
      o.layout = layout;
      if (layout == solo::DepthSolverLayout::PerPixelResidualBlocks) o.max_iterations = 30;
      solo::Stopwatch total;
      const solo::NormalGuidedOptimizationResult result = solo::optimizeDepthWithNormals(d, n, u, h, small_camera, o);
      const std::string name = layout == solo::DepthSolverLayout::PerPixelResidualBlocks ? "ceres_per_pixel_lm" : "ceres_lbfgs";
      for (const solo::OptimizationIteration& it : result.trace)
        if (it.level == 0) table.add(Row{name + "_quarter", sizeText(d), it.iteration, it.seconds, it.value, true});
      std::printf("%s at %s: objective %.6g -> %.6g in %.3f s (with problem construction)\n", name.c_str(),
                  sizeText(d).c_str(), result.initial.total, result.final.total, total.seconds());
    }
  }

  // The whole stage as `solo depth` runs it.
  {
    solo::Stopwatch total;
    const solo::DepthRefinementResult refined = solo::refineDepth(scene);
    Row r{"refine_stage", size, -1, total.seconds(), valueOf(refined.depth_m), true};
    measure(r, refined.depth_m, truth, camera);
    table.add(r);
    for (const solo::StageReport& step : refined.steps) std::printf("  %s %.3f s\n", step.name.c_str(), step.seconds);
  }
  std::printf("\nCeres %.3f s, objective %.6g; Adam-1000 %.3f s, objective %.6g; time ratio %.3f\n", ceres_seconds,
              ceres_objective, adam_seconds, adam_objective, ceres_seconds / adam_seconds);
  return 0;
}
