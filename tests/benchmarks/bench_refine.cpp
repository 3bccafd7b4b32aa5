// Depth refinement on a synthetic scene with exact ground truth: what each step buys and what
// it costs. Not a Google Benchmark: one run of each method, the Ceres solve and Adam observed
// at every iteration, written as a CSV (docs/data/) and a table on stdout.
// Run (docs/depth-refinement.md):
//   build/release/tools/solo synth -o /tmp/s1080 --size 1920x1080 --seed 1
//   build/release/tests/benchmarks/bench_refine /tmp/s1080 docs/data/depth_refinement_1080p.csv

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
#include <filesystem>
#include <fstream>
#include <set>
#include <string>

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

}  // namespace

int main(int argc, char** argv) {
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
