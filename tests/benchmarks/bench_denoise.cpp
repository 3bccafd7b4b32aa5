// The render denoiser at 960x540 (the default render size up to 1080p): the default filter
// (five a-trous passes and two fine passes) as the baseline, without the fine passes, and
// without the luminance weight (no std_error AOV). The render: a road and a facade with an
// albedo texture, normals 2 degrees apart from pixel to pixel (a normal map's noise), Gaussian
// noise, and one pixel in fifty holding a bright sample.
// Run: build/release/tests/benchmarks/bench_denoise

#include <solo/render/render_denoise.h>

#include "bench_support.h"

#include <opencv2/core.hpp>

namespace {

constexpr int kWidth = 960, kHeight = 540;

solo::PinholeCamera camera() {
  solo::PinholeCamera c;
  c.fx = c.fy = 890;
  c.cx = (kWidth - 1) / 2.0;
  c.cy = (kHeight - 1) / 2.0;
  c.width = kWidth;
  c.height = kHeight;
  return c;
}

// The lower half a road 1.5 m below the camera, the upper half a facade 20 m ahead.
solo::RenderOutput streetRender() {
  const solo::PinholeCamera c = camera();
  solo::RenderOutput r;
  r.radiance.create(kHeight, kWidth, CV_32FC3);
  r.albedo.create(kHeight, kWidth, CV_32FC3);
  r.normal.create(kHeight, kWidth, CV_32FC3);
  r.depth_m.create(kHeight, kWidth, CV_32F);
  r.std_error.create(kHeight, kWidth, CV_32F);
  r.samples = cv::Mat(kHeight, kWidth, CV_32S, cv::Scalar(4));
  r.light_id = cv::Mat::zeros(kHeight, kWidth, CV_32S);
  r.emitter_coverage = cv::Mat::zeros(kHeight, kWidth, CV_32F);
  cv::RNG rng(7);
  for (int y = 0; y < kHeight; ++y)
    for (int x = 0; x < kWidth; ++x) {
      const bool road = y > kHeight / 2 + 10;
      const float depth = road ? static_cast<float>(1.5 * c.fy / (y - c.cy)) : 20.f;
      const float albedo = ((x / 24 + y / 16) % 2 == 0) ? 0.3f : 0.6f;
      const float irradiance = road ? 2.f : 1.f + static_cast<float>(x) / kWidth;
      const bool firefly = rng.uniform(0.0, 1.0) < 0.02;
      const float noise = static_cast<float>(rng.gaussian(0.2));
      const float value = albedo * irradiance + noise + (firefly ? 50.f : 0.f);
      r.radiance.at<cv::Vec3f>(y, x) = cv::Vec3f::all(value);
      r.albedo.at<cv::Vec3f>(y, x) = cv::Vec3f::all(albedo);
      const cv::Vec3f n = (road ? cv::Vec3f(0, -1, 0) : cv::Vec3f(0, 0, -1)) +
                          cv::Vec3f(static_cast<float>(rng.gaussian(0.03)), static_cast<float>(rng.gaussian(0.03)), 0);
      r.normal.at<cv::Vec3f>(y, x) = n / cv::norm(n);
      r.depth_m.at<float>(y, x) = depth;
      r.std_error.at<float>(y, x) = firefly ? 25.f : 0.2f;
    }
  return r;
}

void denoise(benchmark::State& state, int fine_passes, bool luminance) {
  const solo::RenderOutput original = streetRender();
  solo::RenderDenoiseOptions options;
  options.fine_passes = fine_passes;
  for (auto _ : state) {
    state.PauseTiming();
    solo::RenderOutput r = original;
    r.radiance = original.radiance.clone();
    if (!luminance) r.std_error = cv::Mat();
    state.ResumeTiming();
    benchmark::DoNotOptimize(solo::denoiseRender(r, camera(), options).seconds);
  }
}

}  // namespace

BENCHMARK_CAPTURE(denoise, default, 2, true)->Name("denoise_960x540/baseline_default")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(denoise, no_fine, 0, true)->Name("denoise_960x540/no_fine_passes")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(denoise, no_luminance, 2, false)
    ->Name("denoise_960x540/no_luminance_weight")->Unit(benchmark::kMillisecond);

SOLO_BENCHMARK_MAIN();
