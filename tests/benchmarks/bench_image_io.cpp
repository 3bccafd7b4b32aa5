// Reading a 1920x1080 depth map in each supported format; baseline: NPY (a raw memory copy).
// Run: build/release/tests/benchmarks/bench_image_io

#include <solo/core/image_io.h>

#include "bench_support.h"

#include <filesystem>

namespace {

const std::filesystem::path& folder() {
  static const std::filesystem::path dir = [] {
    auto d = std::filesystem::temp_directory_path() / "solo_bench_image_io";
    std::filesystem::create_directories(d);
    cv::Mat depth(1080, 1920, CV_32F);
    cv::randu(depth, 0.5, 1000.0);
    for (const char* name : {"d.npy", "d.exr", "d.pfm", "d.tif", "d.png"}) solo::writeDepth(d / name, depth, 0.001);
    return d;
  }();
  return dir;
}

void readDepth(benchmark::State& state, const char* name, double scale) {
  const auto file = folder() / name;
  for (auto _ : state) benchmark::DoNotOptimize(solo::readDepth(file, scale).data);
  state.SetItemsProcessed(state.iterations() * 1920 * 1080);
}

}  // namespace

BENCHMARK_CAPTURE(readDepth, baseline_npy, "d.npy", 0.0)->Name("read_depth_1080p/baseline_npy")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(readDepth, exr, "d.exr", 0.0)->Name("read_depth_1080p/exr")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(readDepth, pfm, "d.pfm", 0.0)->Name("read_depth_1080p/pfm")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(readDepth, tiff, "d.tif", 0.0)->Name("read_depth_1080p/tiff")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(readDepth, png16, "d.png", 0.001)->Name("read_depth_1080p/png16_mm")->Unit(benchmark::kMillisecond);

SOLO_BENCHMARK_MAIN();
