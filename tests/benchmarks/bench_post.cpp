// Post-processing at 1920x1080: the fog glare's cost for what the image holds (baseline: a
// full bright field, one FFT of the frame) and the whole chain (baseline: all steps on).
// Run: build/release/tests/benchmarks/bench_post

#include <solo/post/fog_glare.h>
#include <solo/post/post_process.h>

#include "bench_support.h"

#include <random>

namespace {

enum class Content { FullField, FewSpots, TwoClusters, Nothing };

cv::Mat frame(Content content) {
  cv::Mat image = cv::Mat::zeros(1080, 1920, CV_32FC3);
  switch (content) {
    case Content::FullField: {
      cv::RNG rng(1);
      rng.fill(image, cv::RNG::UNIFORM, 0.0, 0.2);
      break;
    }
    case Content::FewSpots: {  // five 3x3 lamps: 45 bright pixels
      const cv::Point spots[] = {{100, 100}, {900, 300}, {1800, 200}, {400, 1000}, {1500, 900}};
      for (const cv::Point& p : spots) image(cv::Rect(p.x, p.y, 3, 3)).setTo(cv::Scalar::all(50));
      break;
    }
    case Content::TwoClusters:  // two 60x60 windows near opposite corners: 7200 bright pixels
      image(cv::Rect(0, 0, 60, 60)).setTo(cv::Scalar::all(5));
      image(cv::Rect(1800, 900, 60, 60)).setTo(cv::Scalar::all(5));
      break;
    case Content::Nothing: break;
  }
  return image;
}

void glare(benchmark::State& state, Content content, solo::GlareMethod method) {
  const cv::Mat original = frame(content);
  solo::FogGlareOptions options;
  options.method = method;
  for (auto _ : state) {
    state.PauseTiming();
    cv::Mat image = original.clone();
    state.ResumeTiming();
    benchmark::DoNotOptimize(solo::applyFogGlare(image, options).seconds);
  }
}

void chain(benchmark::State& state, bool glare_on, bool noise_on) {
  cv::Mat render(1080, 1920, CV_32FC3);
  cv::RNG(2).fill(render, cv::RNG::UNIFORM, 0.0, 0.05);
  render(cv::Rect(900, 500, 4, 4)).setTo(cv::Scalar::all(200));
  solo::PostProcessOptions options;
  options.glare = glare_on;
  options.noise = noise_on;
  options.glare_options.threshold = 1.0;  // only the lamp glows
  for (auto _ : state) benchmark::DoNotOptimize(solo::postProcess(render, options).encoded.data);
}

using solo::GlareMethod;

}  // namespace

BENCHMARK_CAPTURE(glare, full, Content::FullField, GlareMethod::Automatic)
    ->Name("glare_1080p/baseline_full_field_fft")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(glare, full_tiled, Content::FullField, GlareMethod::TiledFft)
    ->Name("glare_1080p/full_field_forced_tiled")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(glare, spots, Content::FewSpots, GlareMethod::Automatic)
    ->Name("glare_1080p/five_3x3_spots_auto")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(glare, spots_fft, Content::FewSpots, GlareMethod::Fft)
    ->Name("glare_1080p/five_3x3_spots_forced_fft")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(glare, clusters, Content::TwoClusters, GlareMethod::Automatic)
    ->Name("glare_1080p/two_60px_clusters_auto")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(glare, clusters_direct, Content::TwoClusters, GlareMethod::Direct)
    ->Name("glare_1080p/two_60px_clusters_forced_direct")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(glare, clusters_fft, Content::TwoClusters, GlareMethod::Fft)
    ->Name("glare_1080p/two_60px_clusters_forced_fft")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(glare, nothing, Content::Nothing, GlareMethod::Automatic)
    ->Name("glare_1080p/nothing_bright")->Unit(benchmark::kMillisecond);

BENCHMARK_CAPTURE(chain, all, true, true)->Name("post_1080p/baseline_all_steps")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(chain, no_glare, false, true)->Name("post_1080p/no_glare")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(chain, no_noise, true, false)->Name("post_1080p/no_noise")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(chain, neither, false, false)->Name("post_1080p/no_glare_no_noise")->Unit(benchmark::kMillisecond);

SOLO_BENCHMARK_MAIN();
