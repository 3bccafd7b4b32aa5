// Adaptive sampling against fixed sampling at the same total samples, on a scene whose pixels
// differ in noise: a floor and a wall lit directly by a small bright lamp on one side of a
// screen, and only by light reflected past the screen on the other side.

#include <solo/render/path_tracer.h>

#include "render_quads.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <cstdio>
#include <string>

namespace {

using solo::test::addQuad;

// Camera frame (x right, y down, z forward): a floor at y = 1, a back wall at z = 10, a screen
// at x = 0 from z = 3 to 10, and a 0.2 m lamp of radiance 300 at (1.5, -0.5, 6), right of the
// screen: the left half is lit only by light reflected off the right half.
solo::RenderScene lampBehindAScreen() {
  solo::RenderScene s;
  s.emitters.push_back({Eigen::Vector3f::Constant(300.f), solo::EmitterProfile::Uniform, 0.f, 1});
  addQuad(s, {-6, 1, 0}, {0, 0, 12}, {12, 0, 0}, 0.5f);     // floor
  addQuad(s, {-6, -5, 10}, {12, 0, 0}, {0, 6, 0}, 0.5f);    // back wall
  addQuad(s, {0, -5, 3}, {0, 6, 0}, {0, 0, 7}, 0.7f);       // screen
  addQuad(s, {1.4f, -0.5f, 5.9f}, {0.2f, 0, 0}, {0, 0, 0.2f}, 0.f, 0);  // lamp
  s.camera = {16.0, 16.0, 15.5, 12.5, 32, 24};
  return s;
}

// Relative RMSE of Y against the reference: root of the summed squared errors over the summed
// squared reference, on the pixels that see no emitter.
double squaredError(const solo::RenderOutput& out, const solo::RenderOutput& reference, double* norm) {
  double sum = 0;
  *norm = 0;
  for (int y = 0; y < out.radiance.rows; ++y)
    for (int x = 0; x < out.radiance.cols; ++x) {
      if (reference.emitter_coverage.at<float>(y, x) > 0.f) continue;
      const double r = reference.radiance.at<cv::Vec3f>(y, x)[1], v = out.radiance.at<cv::Vec3f>(y, x)[1];
      sum += (v - r) * (v - r);
      *norm += r * r;
    }
  return sum;
}

// The image-error rule at `relative_error` (16 to 256 spp) against fixed sampling at its own
// mean samples per pixel (the pilot's included), over seeds 1 to 6 on lampBehindAScreen, both
// against a 4096-spp reference: summed squared errors, their norm and the mean spp. `check`
// sees each adaptive render.
struct EqualSampleErrors {
  double adaptive = 0, fixed = 0, norm = 0, spp = 0;
  int seeds = 6;
  double relative(double squared) const { return std::sqrt(squared / (seeds * norm)); }
};

template <typename Check>
EqualSampleErrors againstFixedSampling(double relative_error, const Check& check) {
  const solo::RenderScene scene = lampBehindAScreen();
  const solo::PreparedRenderScene prepared(scene);
  solo::PathTracerOptions o;
  o.progress = false;
  o.diffuse = solo::DiffuseModel::Lambert;
  o.seed = 1000;
  o.min_samples = o.max_samples = 4096;
  const solo::RenderOutput reference = solo::renderPathTraced(prepared, scene.camera, o);

  EqualSampleErrors e;
  for (int seed = 1; seed <= e.seeds; ++seed) {
    solo::PathTracerOptions a = o;
    a.seed = static_cast<std::uint64_t>(seed);
    a.relative_error = relative_error;
    a.min_samples = 16;
    a.max_samples = 256;
    const solo::RenderOutput out = solo::renderPathTraced(prepared, scene.camera, a);
    check(out);
    const solo::MetricValue* pilot = out.report.find("pilot_samples_per_pixel");
    const double spp = cv::mean(out.samples)[0] + (pilot ? std::get<double>(*pilot) : 0.0);
    e.spp += spp / e.seeds;
    e.adaptive += squaredError(out, reference, &e.norm);
    solo::PathTracerOptions f = a;
    f.min_samples = f.max_samples = static_cast<int>(std::lround(spp));
    e.fixed += squaredError(solo::renderPathTraced(prepared, scene.camera, f), reference, &e.norm);
  }
  return e;
}

}  // namespace

// The default rule (AdaptiveRule::ImageError) spends its samples where the per-sample spread
// is large: over 6 seeds its error is below that of fixed sampling at its own mean samples per
// pixel, the pilot's included (measured 0.022 against 0.031 at 102 spp).
TEST(PathTracerAdaptive, ImageErrorRuleBeatsFixedSamplingAtEqualSamples) {
  const EqualSampleErrors e = againstFixedSampling(0.05, [](const solo::RenderOutput& out) {
    EXPECT_NE(out.report.find("pilot_samples_per_pixel"), nullptr);
  });
  std::printf("relative RMSE over %d seeds: image-error rule %.4f at %.1f spp (mean), fixed %.4f\n", e.seeds,
              e.relative(e.adaptive), e.spp, e.relative(e.fixed));
  EXPECT_LT(e.spp, 200) << "the rule must leave room below max_samples";
  EXPECT_LT(e.adaptive, 0.8 * e.fixed);
}

// A target the pilot meets below min_samples (here 50 %) would give every pixel min_samples,
// i.e. fixed sampling. The rule spreads that budget instead: every pixel takes min_samples / 2,
// then counts by the spread with a pilot mean of min_samples. Over 6 seeds its error is below
// fixed sampling's at its own mean samples per pixel.
TEST(PathTracerAdaptive, ATargetMetBelowMinSamplesSpreadsTheMinSamplesBudget) {
  const EqualSampleErrors e = againstFixedSampling(0.5, [](const solo::RenderOutput& out) {
    const solo::MetricValue* budget = out.report.find("image_error_budget");
    ASSERT_NE(budget, nullptr);
    EXPECT_EQ(std::get<std::string>(*budget), "min_samples");
    double fewest = 0, most = 0;
    cv::minMaxLoc(out.samples, &fewest, &most);
    EXPECT_EQ(fewest, 8) << "the first pass is half of min_samples";
    EXPECT_GT(most, 32);
  });
  std::printf("relative RMSE over %d seeds: min_samples budget spread %.4f at %.1f spp (mean), fixed %.4f\n",
              e.seeds, e.relative(e.adaptive), e.spp, e.relative(e.fixed));
  EXPECT_GT(e.spp, 8);
  EXPECT_LT(e.spp, 24) << "about min_samples";
  EXPECT_LT(e.adaptive, 0.8 * e.fixed);
}

// The rule keeps the image the same whatever the number of threads: the pilot's sums and every
// tile's counts depend only on the seed.
TEST(PathTracerAdaptive, ImageErrorRuleIsDeterministic) {
  const solo::RenderScene scene = lampBehindAScreen();
  solo::PathTracerOptions o;
  o.progress = false;
  o.min_samples = 8;
  o.max_samples = 64;
  o.relative_error = 0.05;
  solo::RenderOutput a;
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
    a = solo::renderPathTraced(scene, o);
  }
  const solo::RenderOutput b = solo::renderPathTraced(scene, o);
  EXPECT_EQ(cv::norm(a.radiance, b.radiance, cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(a.samples, b.samples, cv::NORM_INF), 0.0);
}
