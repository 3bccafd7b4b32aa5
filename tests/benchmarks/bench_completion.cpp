// Depth completion on synthetic scenes with simulated sensors (solo synth --depth-source): the
// accuracy of the filled pixels against the exact depth and the time, for a range of relaxation
// sweeps. One row per scene and setting (median time of three runs), a table on stdout and a CSV.
// Run (docs/depth-refinement.md):
//   for s in stereo lidar mono; do
//     build/release/tools/solo synth --seed 3 --size 1920x1080 --depth-source $s -o /tmp/c_$s; done
//   build/release/tests/benchmarks/bench_completion docs/data/depth_completion.csv /tmp/c_stereo /tmp/c_lidar /tmp/c_mono

#include <solo/core/report.h>
#include <solo/core/scene.h>
#include <solo/geometry/depth_completion.h>
#include <solo/geometry/upsample_maps.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;

namespace {

struct FilledError {
  double abs_rel = 0, rmse_m = 0, within_5_percent = 0;
  std::int64_t pixels = 0;
};

// Errors of the filled pixels that have an exact depth.
FilledError filledError(const cv::Mat& depth_m, const cv::Mat& filled, const cv::Mat& truth_m) {
  FilledError e;
  double sum_rel = 0, sum_sq = 0;
  std::int64_t close = 0;
  for (int y = 0; y < depth_m.rows; ++y)
    for (int x = 0; x < depth_m.cols; ++x) {
      const float t = truth_m.at<float>(y, x), d = depth_m.at<float>(y, x);
      if (!filled.at<std::uint8_t>(y, x) || !(t > 0)) continue;
      const double rel = std::abs(d - t) / t;
      sum_rel += rel, sum_sq += (d - t) * (d - t), close += rel < 0.05 ? 1 : 0, ++e.pixels;
    }
  if (e.pixels > 0) {
    const auto n = static_cast<double>(e.pixels);
    e.abs_rel = sum_rel / n, e.rmse_m = std::sqrt(sum_sq / n), e.within_5_percent = static_cast<double>(close) / n;
  }
  return e;
}

double medianOf(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: %s OUT.csv SCENE_DIR...\n", argv[0]);
    return 2;
  }
  std::ofstream csv(argv[1]);
  csv << "scene,relax_iterations,seconds,filled_share_percent,filled_abs_rel,filled_rmse_m,filled_within_5_percent\n";
  std::printf("%-24s %6s %9s %8s %10s %10s %8s\n", "scene", "sweeps", "time s", "filled%", "AbsRel", "RMSE m",
              "<5%");
  for (int i = 2; i < argc; ++i) {
    const fs::path folder = argv[i];
    const solo::Scene scene = solo::loadScene(folder / "scene.json");
    const solo::Scene truth = solo::loadScene(folder / "gt" / "scene.json");
    const solo::UpsampledMaps maps = solo::upsampleMaps(scene);
    for (const int sweeps : {0, 10, 20, 40, 80, 160}) {
      solo::DepthCompletionOptions options;
      options.relax_iterations = sweeps;
      std::vector<double> times;
      solo::DepthCompletionResult r;
      for (int run = 0; run < 3; ++run) {
        const solo::Stopwatch clock;
        r = solo::completeDepth(maps.depth_m, scene.image, maps.labels, maps.instances, options);
        times.push_back(clock.seconds());
      }
      const FilledError e = filledError(r.depth_m, r.filled, truth.depth_m);
      const double share = std::get<double>(*r.report.find("filled_share"));
      const double seconds = medianOf(times);
      std::printf("%-24s %6d %9.3f %8.2f %10.4f %10.3f %8.3f\n", folder.filename().c_str(), sweeps, seconds, share,
                  e.abs_rel, e.rmse_m, e.within_5_percent);
      csv << folder.filename().string() << "," << sweeps << "," << seconds << "," << share << "," << e.abs_rel << ","
          << e.rmse_m << "," << e.within_5_percent << "\n";
    }
  }
  return 0;
}
