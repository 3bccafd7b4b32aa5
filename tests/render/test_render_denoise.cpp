#include <solo/render/render_denoise.h>

#include "test_support.h"

#include <cmath>
#include <functional>

namespace {

constexpr int kWidth = 160, kHeight = 120;

// What a synthetic render's pixel shows: the truth the filter should recover.
struct SurfaceTruth {
  float depth_m = 10.f;
  cv::Vec3f normal{0, 0, -1};  // facing the camera (which looks along +z)
  float albedo = 0.5f;
  float irradiance = 2.f;  // radiance = albedo x irradiance, every XYZ channel
};

solo::PinholeCamera camera() {
  solo::PinholeCamera c;
  c.fx = c.fy = 120;
  c.cx = (kWidth - 1) / 2.0;
  c.cy = (kHeight - 1) / 2.0;
  c.width = kWidth;
  c.height = kHeight;
  return c;
}

// A render of `truth` with independent Gaussian noise of `sigma` on every channel of the
// radiance and the matching std_error AOV (the standard error of Y is sigma).
solo::RenderOutput noisyRender(const std::function<SurfaceTruth(int x, int y)>& truth, float sigma,
                               std::uint64_t seed) {
  solo::RenderOutput r;
  r.radiance.create(kHeight, kWidth, CV_32FC3);
  r.albedo.create(kHeight, kWidth, CV_32FC3);
  r.normal.create(kHeight, kWidth, CV_32FC3);
  r.depth_m.create(kHeight, kWidth, CV_32F);
  r.light_id = cv::Mat::zeros(kHeight, kWidth, CV_32S);
  r.emitter_coverage = cv::Mat::zeros(kHeight, kWidth, CV_32F);
  r.samples = cv::Mat(kHeight, kWidth, CV_32S, cv::Scalar(4));
  r.std_error = cv::Mat(kHeight, kWidth, CV_32F, cv::Scalar(sigma));
  cv::Mat noise(kHeight, kWidth, CV_32FC3);
  cv::RNG rng(seed);
  rng.fill(noise, cv::RNG::NORMAL, 0.0, sigma);
  for (int y = 0; y < kHeight; ++y)
    for (int x = 0; x < kWidth; ++x) {
      const SurfaceTruth t = truth(x, y);
      r.albedo.at<cv::Vec3f>(y, x) = cv::Vec3f::all(t.albedo);
      r.normal.at<cv::Vec3f>(y, x) = t.normal;
      r.depth_m.at<float>(y, x) = t.depth_m;
      r.radiance.at<cv::Vec3f>(y, x) = cv::Vec3f::all(t.albedo * t.irradiance) + noise.at<cv::Vec3f>(y, x);
    }
  return r;
}

// Mean and standard deviation of the Y error against `truth_y` over a region.
struct ErrorStats {
  double mean = 0, sigma = 0;
};
ErrorStats yError(const cv::Mat& radiance, const cv::Rect& region, double truth_y) {
  cv::Mat channels[3];
  cv::split(radiance(region), channels);
  cv::Scalar mean, sigma;
  cv::meanStdDev(channels[1], mean, sigma);
  return {mean[0] - truth_y, sigma[0]};
}

double columnMeanY(const cv::Mat& radiance, int x, int y0, int y1) {
  return yError(radiance, cv::Rect(x, y0, 1, y1 - y0), 0).mean;
}

bool bitIdentical(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() && cv::norm(a, b, cv::NORM_INF) == 0;
}

}  // namespace

TEST(RenderDenoise, FlatPlaneNoiseDropsTwentyFiveFoldAndItsMeanStaysUnbiased) {
  const float sigma = 0.2f;  // 20 % of the radiance 0.5 x 2 = 1
  solo::RenderOutput r = noisyRender([](int, int) { return SurfaceTruth{}; }, sigma, 11);
  const cv::Rect all(0, 0, kWidth, kHeight);
  const ErrorStats before = yError(r.radiance, all, 1.0);
  ASSERT_NEAR(before.sigma, sigma, 0.01);

  const solo::StageReport report = solo::denoiseRender(r, camera());
  const ErrorStats after = yError(r.radiance, all, 1.0);
  // Measured 0.201 -> 0.0042 (48x); a plain linear filter of this footprint: about 65x (estimated).
  EXPECT_LT(after.sigma, before.sigma / 25) << "noise " << before.sigma << " -> " << after.sigma;
  // Unfiltered, the mean's own noise is 0.2 / sqrt(19200) = 0.0014; symmetric noise must not
  // shift it.
  EXPECT_NEAR(after.mean, 0.0, 0.005);
  EXPECT_NEAR(solo::test::metricNumber(report, "luminance_ratio"), 1.0, 0.005);
  EXPECT_EQ(solo::test::metricNumber(report, "pixels_filtered"), kWidth * kHeight);
  EXPECT_EQ(solo::test::metricNumber(report, "footprint_radius"), 68);  // 2 (2^5 - 1) + 2 (2^2 - 1)
  EXPECT_FALSE(report.skipped);
}

TEST(RenderDenoise, EdgesInDepthNormalAndAlbedoStaySharp) {
  const int edge = kWidth / 2;  // the first column of the right side
  const float sigma = 0.05f;
  struct Case {
    const char* name;
    SurfaceTruth left, right;
  };
  SurfaceTruth near_bright, far_dark, tilted, dark_paint;
  near_bright.depth_m = 5.f;
  near_bright.irradiance = 1.6f;  // radiance 0.8
  far_dark.depth_m = 10.f;
  far_dark.irradiance = 0.4f;                              // radiance 0.2
  tilted.normal = {std::sin(1.0f), 0.f, -std::cos(1.0f)};  // 57 degrees from the left side's
  tilted.irradiance = 0.4f;
  dark_paint.albedo = 0.1f;  // radiance 0.2, same irradiance 2 as the left side
  const Case cases[] = {
      {"depth", near_bright, far_dark}, {"normal", SurfaceTruth{}, tilted}, {"albedo", SurfaceTruth{}, dark_paint}};
  for (const Case& c : cases) {
    solo::RenderOutput r = noisyRender([&](int x, int) { return x < edge ? c.left : c.right; }, sigma, 23);
    solo::denoiseRender(r, camera());
    const double left_truth = c.left.albedo * c.left.irradiance, right_truth = c.right.albedo * c.right.irradiance;
    const double step = std::abs(left_truth - right_truth);
    // The columns on either side of the edge: a filter blind to it would put them half way.
    for (const int x : {edge - 2, edge - 1}) {
      EXPECT_NEAR(columnMeanY(r.radiance, x, 0, kHeight), left_truth, 0.01 * step) << c.name << " column " << x;
    }
    for (const int x : {edge, edge + 1}) {
      EXPECT_NEAR(columnMeanY(r.radiance, x, 0, kHeight), right_truth, 0.01 * step) << c.name << " column " << x;
    }
    EXPECT_LT(yError(r.radiance, cv::Rect(edge - 1, 0, 1, kHeight), left_truth).sigma, sigma / 10) << c.name;
    EXPECT_LT(yError(r.radiance, cv::Rect(edge, 0, 1, kHeight), right_truth).sigma, sigma / 10) << c.name;
  }
}

TEST(RenderDenoise, RadianceThatIsNotAlbedoTimesIrradianceStaysOnItsAlbedo) {
  // A texture of dark (0.05) and light (0.5) pixels at random, irradiance 2, plus a specular
  // reflection of 0.1 that does not scale with the albedo: 0.2 and 1.1. Divided by the albedo, the
  // dark pixels' reflection is 2 of irradiance; mixed into the light pixels and multiplied back
  // it would make them 1.55.
  cv::Mat light(kHeight, kWidth, CV_8U);
  cv::RNG rng(17);
  rng.fill(light, cv::RNG::UNIFORM, 0, 2);
  solo::RenderOutput r = noisyRender(
      [&](int x, int y) {
        SurfaceTruth t;
        t.albedo = light.at<std::uint8_t>(y, x) ? 0.5f : 0.05f;
        return t;
      },
      0.05f, 29);
  r.radiance += cv::Scalar::all(0.1);
  solo::denoiseRender(r, camera());
  cv::Mat y_channel;
  cv::extractChannel(r.radiance, y_channel, 1);
  EXPECT_NEAR(cv::mean(y_channel, light)[0], 1.1, 0.01);
  EXPECT_NEAR(cv::mean(y_channel, light == 0)[0], 0.2, 0.01);
}

TEST(RenderDenoise, EmitterPixelsStayBitIdenticalAndLightNoNeighbour) {
  solo::RenderOutput r = noisyRender([](int, int) { return SurfaceTruth{}; }, 0.1f, 5);
  const cv::Rect lamp(40, 40, 12, 12), sliver(100, 60, 6, 6);
  r.radiance(lamp).setTo(cv::Scalar(2000, 3000, 1000));
  r.light_id(lamp).setTo(7);
  r.albedo(lamp).setTo(cv::Scalar::all(0));  // an emitting face reflects nothing
  r.radiance(sliver).setTo(cv::Scalar(400, 500, 300));
  r.emitter_coverage(sliver).setTo(0.25f);  // light_id 0: the first sample missed the emitter
  r.std_error(lamp).setTo(50.f);
  const cv::Mat before = r.radiance.clone();

  const solo::StageReport report = solo::denoiseRender(r, camera());
  EXPECT_TRUE(bitIdentical(r.radiance(lamp), before(lamp)));
  EXPECT_TRUE(bitIdentical(r.radiance(sliver), before(sliver)));
  EXPECT_EQ(solo::test::metricNumber(report, "pixels_kept_emitter"), lamp.area() + sliver.area());
  // The pixels around them still show the plane's radiance 1: none of the lamps' light leaked.
  for (const cv::Rect& emitter : {lamp, sliver}) {
    const cv::Rect ring(emitter.x - 2, emitter.y - 2, emitter.width + 4, 2);
    EXPECT_NEAR(yError(r.radiance, ring, 1.0).mean, 0.0, 0.01);
  }
}

TEST(RenderDenoise, SkyAndBlackSurfacesGiveFiniteOutputAndSkyStaysExact) {
  solo::RenderOutput r = noisyRender(
      [](int x, int y) {
        SurfaceTruth t;
        if (y < kHeight / 3) {  // sky
          t.depth_m = 0;
          t.normal = {0, 0, 0};
          t.albedo = 0;
        } else if (x < kWidth / 4) {  // black paint
          t.albedo = 0;
        }
        return t;
      },
      0.05f, 9);
  r.std_error(cv::Rect(0, kHeight - 10, kWidth, 10)).setTo(0.f);  // a band whose samples all agreed
  const cv::Rect sky(0, 0, kWidth, kHeight / 3);
  const cv::Mat before = r.radiance.clone();

  const solo::StageReport report = solo::denoiseRender(r, camera());
  EXPECT_TRUE(cv::checkRange(r.radiance));
  EXPECT_TRUE(bitIdentical(r.radiance(sky), before(sky)));
  EXPECT_EQ(solo::test::metricNumber(report, "pixels_kept_no_surface"), sky.area());
  // Black paint: radiance only noise around 0, and it stays around 0 (albedo floor 0.02).
  EXPECT_NEAR(yError(r.radiance, cv::Rect(0, kHeight / 2, kWidth / 4 - 4, 20), 0.0).mean, 0.0, 0.01);
}

TEST(RenderDenoise, SwitchedOffChangesNothingAndSaysSkipped) {
  solo::RenderOutput r = noisyRender([](int, int) { return SurfaceTruth{}; }, 0.1f, 3);
  const cv::Mat before = r.radiance.clone();
  solo::RenderDenoiseOptions options;
  options.enabled = false;
  const solo::StageReport report = solo::denoiseRender(r, camera(), options);
  EXPECT_TRUE(report.skipped);
  EXPECT_EQ(report.name, "denoise");
  EXPECT_FALSE(report.skip_reason.empty());
  EXPECT_TRUE(bitIdentical(r.radiance, before));
}

TEST(RenderDenoise, RefusesMismatchedAovsCameraAndOptions) {
  solo::RenderOutput r = noisyRender([](int, int) { return SurfaceTruth{}; }, 0.1f, 3);
  solo::PinholeCamera small = camera().scaledTo(kWidth / 2, kHeight / 2);
  EXPECT_THROW(solo::denoiseRender(r, small), std::invalid_argument);
  solo::RenderDenoiseOptions bad;
  bad.iterations = 0;
  EXPECT_THROW(solo::denoiseRender(r, camera(), bad), std::invalid_argument);
  bad = {};
  bad.fine_passes = -1;
  EXPECT_THROW(solo::denoiseRender(r, camera(), bad), std::invalid_argument);
  bad.fine_passes = 11;
  EXPECT_THROW(solo::denoiseRender(r, camera(), bad), std::invalid_argument);
  bad = {};
  bad.plane_tolerance = 0;
  EXPECT_THROW(solo::denoiseRender(r, camera(), bad), std::invalid_argument);
  solo::RenderOutput wrong = r;
  wrong.emitter_coverage = cv::Mat::zeros(kHeight / 2, kWidth / 2, CV_32F);
  EXPECT_THROW(solo::denoiseRender(wrong, camera()), std::invalid_argument);
  wrong = r;
  wrong.depth_m = cv::Mat();
  EXPECT_THROW(solo::denoiseRender(wrong, camera()), std::invalid_argument);
}

// A rare bright sample on a noisy plane: a firefly of 1000 (its own standard error half its
// value, as one bright sample of four gives) among pixels of radiance 1.
solo::RenderOutput planeWithFirefly(int x, int y, float value, float std_error) {
  solo::RenderOutput r = noisyRender([](int, int) { return SurfaceTruth{}; }, 0.2f, 17);
  r.radiance.at<cv::Vec3f>(y, x) = cv::Vec3f::all(value);
  r.std_error.at<float>(y, x) = std_error;
  return r;
}

// The largest |Y - 1| over the 41x41 pixels around (x, y), the pixel itself left out.
double largestErrorAround(const cv::Mat& radiance, int x, int y) {
  double largest = 0;
  for (int v = y - 20; v <= y + 20; ++v)
    for (int u = x - 20; u <= x + 20; ++u)
      if (u != x || v != y) largest = std::max(largest, std::abs(radiance.at<cv::Vec3f>(v, u)[1] - 1.0));
  return largest;
}

double meanY(const cv::Mat& radiance) { return cv::mean(radiance)[1]; }

TEST(RenderDenoise, AFireflyIsClampedAndItsLightSpreadInsteadOfABlotch) {
  const int x = 80, y = 60;
  solo::RenderOutput spread = planeWithFirefly(x, y, 1000.f, 500.f);
  solo::RenderOutput blotch = planeWithFirefly(x, y, 1000.f, 500.f);  // its own pixels (Mats share theirs)
  solo::RenderOutput removed = planeWithFirefly(x, y, 1000.f, 500.f);
  const double mean_before = meanY(spread.radiance);  // about (19 199 + 1 000) / 19 200
  const solo::StageReport report = solo::denoiseRender(spread, camera());
  solo::RenderDenoiseOptions off;
  off.firefly_sigma = 0;
  solo::denoiseRender(blotch, camera(), off);
  solo::RenderDenoiseOptions remove;
  remove.firefly_spread_px = 0;
  const solo::StageReport removed_report = solo::denoiseRender(removed, camera(), remove);
  // Unclamped, its 999 extra units of light stay within the 62 px footprint and raise the plane
  // around it by more than a third. Clamped to 20 standard deviations of its neighbours (about
  // 0.2 each: 1 + 20 x 0.2 = 5), the rest spread by a Gaussian of 96 px (wider than this
  // 160x120 image: +0.05 on average, a little more near its centre), the plane around it stays
  // within 0.02 of the image's mean.
  EXPECT_GT(largestErrorAround(blotch.radiance, x, y), 0.3);
  const double mean_after = meanY(spread.radiance);
  double largest_bump = 0;
  for (int v = y - 20; v <= y + 20; ++v)
    for (int u = x - 20; u <= x + 20; ++u)
      largest_bump = std::max(largest_bump, std::abs(spread.radiance.at<cv::Vec3f>(v, u)[1] - mean_after));
  EXPECT_LT(largest_bump, 0.02);
  // The light is kept: the image's mean moves by less than the filter's own bias on a plane.
  EXPECT_NEAR(mean_after, mean_before, 0.005);
  EXPECT_EQ(solo::test::metricNumber(report, "fireflies_clamped"), 1);
  // About 995 of the 19 200 + 999 units of the plane lie above the bound.
  EXPECT_NEAR(solo::test::metricNumber(report, "firefly_light_spread"), 995.0 / 20199.0, 0.002);
  // Removed instead, the image loses them and the plane keeps its level.
  EXPECT_NEAR(solo::test::metricNumber(removed_report, "firefly_light_removed"), 995.0 / 20199.0, 0.002);
  EXPECT_LT(largestErrorAround(removed.radiance, x, y), 0.06);
  EXPECT_NEAR(meanY(removed.radiance), 1.0, 0.005);
}

TEST(RenderDenoise, ASteadyHighlightIsNoFirefly) {
  // As bright as the firefly above but measured steadily (standard error 1 % of its value):
  // a lamp's reflection that every sample finds. The clamp leaves it and the image alike.
  const int x = 80, y = 60;
  solo::RenderOutput with_clamp = planeWithFirefly(x, y, 1000.f, 10.f);
  solo::RenderOutput without = planeWithFirefly(x, y, 1000.f, 10.f);
  const solo::StageReport report = solo::denoiseRender(with_clamp, camera());
  solo::RenderDenoiseOptions off;
  off.firefly_sigma = 0;
  solo::denoiseRender(without, camera(), off);
  EXPECT_EQ(solo::test::metricNumber(report, "fireflies_clamped"), 0);
  EXPECT_TRUE(bitIdentical(with_clamp.radiance, without.radiance));
  EXPECT_GT(with_clamp.radiance.at<cv::Vec3f>(y, x)[1], 900.f);
}

TEST(RenderDenoise, SparseSamplesOfOneBrightnessAreNoFireflies) {
  // A dim region lit by rare paths: one pixel in twenty holds 20, the rest 0, every standard
  // error that of one hit in four samples. Their neighbours' spread covers them: no light is
  // removed (the bound is about 0.05 x 20 + 20 x 0.22 x 20 = 88).
  solo::RenderOutput r = noisyRender([](int, int) { return SurfaceTruth{}; }, 0.f, 1);
  cv::RNG rng(5);
  for (int y = 0; y < kHeight; ++y)
    for (int x = 0; x < kWidth; ++x) {
      const bool hit = rng.uniform(0.0, 1.0) < 0.05;
      r.radiance.at<cv::Vec3f>(y, x) = cv::Vec3f::all(hit ? 20.f : 0.f);
      r.std_error.at<float>(y, x) = hit ? 10.f : 0.f;
    }
  const solo::StageReport report = solo::denoiseRender(r, camera());
  EXPECT_EQ(solo::test::metricNumber(report, "fireflies_clamped"), 0);
  EXPECT_EQ(solo::test::metricNumber(report, "firefly_light_spread"), 0);
}

TEST(RenderDenoise, RefusesNegativeFireflySettingsAndAnEmptyWindow) {
  solo::RenderOutput r = noisyRender([](int, int) { return SurfaceTruth{}; }, 0.1f, 3);
  solo::RenderDenoiseOptions bad;
  bad.firefly_sigma = -1;
  EXPECT_THROW(solo::denoiseRender(r, camera(), bad), std::invalid_argument);
  bad = {};
  bad.firefly_radius_px = 0;
  EXPECT_THROW(solo::denoiseRender(r, camera(), bad), std::invalid_argument);
  bad = {};
  bad.firefly_spread_px = -1;
  EXPECT_THROW(solo::denoiseRender(r, camera(), bad), std::invalid_argument);
}

TEST(RenderDenoise, AFireflyOfAnyMagnitudeLeavesFiniteValuesAndKeepsTheLight) {
  // 1e30 squares beyond a float's range. Every pixel stays finite, the firefly is clamped and
  // its light, spread over this small image, raises it evenly (about 1e30 / 19 200 each): the
  // image's mean is kept to the spread's pyramid approximation (2 % on an image narrower than the
  // Gaussian) and the firefly's pixel ends within twice it.
  const int x = 80, y = 60;
  solo::RenderOutput r = planeWithFirefly(x, y, 1e30f, 5e29f);
  const double mean_before = meanY(r.radiance);
  const solo::StageReport report = solo::denoiseRender(r, camera());
  EXPECT_TRUE(cv::checkRange(r.radiance));
  EXPECT_GE(solo::test::metricNumber(report, "fireflies_clamped"), 1);
  EXPECT_NEAR(meanY(r.radiance) / mean_before, 1.0, 0.03);
  EXPECT_LT(r.radiance.at<cv::Vec3f>(y, x)[1], 2 * mean_before);
}

// Mean absolute difference of horizontally and vertically adjacent pixels' Y.
double neighbourVariation(const cv::Mat& radiance) {
  cv::Mat y;
  cv::extractChannel(radiance, y, 1);
  const cv::Mat dx = cv::abs(y.colRange(1, y.cols) - y.colRange(0, y.cols - 1));
  const cv::Mat dy = cv::abs(y.rowRange(1, y.rows) - y.rowRange(0, y.rows - 1));
  return (cv::mean(dx)[0] + cv::mean(dy)[0]) / 2;
}

TEST(RenderDenoise, FinePassesAverageOutTheGridAroundRareBrightSamples) {
  // One pixel in twenty holds 20, the rest 0 (a dim surface lit by rare paths; truth 1). The
  // passes of taps 4, 8 and 16 px apart print their spacing as blocks where the luminance
  // weight refuses some taps; the fine passes (taps 2 and 1) average them. Measured over three
  // seeds: neighbour variation 0.029-0.033 without them, 0.017-0.021 with (0.56-0.63x), the
  // mean the same to 4 digits.
  for (const std::uint64_t seed : {5, 6, 7}) {
    solo::RenderOutput sparse = noisyRender([](int, int) { return SurfaceTruth{}; }, 0.f, 1);
    cv::RNG rng(seed);
    for (int y = 0; y < kHeight; ++y)
      for (int x = 0; x < kWidth; ++x) {
        const bool hit = rng.uniform(0.0, 1.0) < 0.05;
        sparse.radiance.at<cv::Vec3f>(y, x) = cv::Vec3f::all(hit ? 20.f : 0.f);
        sparse.std_error.at<float>(y, x) = hit ? 10.f : 0.f;
      }
    solo::RenderOutput without = sparse;
    without.radiance = sparse.radiance.clone();
    solo::RenderDenoiseOptions no_fine;
    no_fine.fine_passes = 0;
    solo::denoiseRender(without, camera(), no_fine);
    const solo::StageReport report = solo::denoiseRender(sparse, camera());
    EXPECT_EQ(solo::test::metricNumber(report, "fine_passes"), 2);
    EXPECT_LT(neighbourVariation(sparse.radiance), 0.7 * neighbourVariation(without.radiance)) << "seed " << seed;
    EXPECT_NEAR(cv::mean(sparse.radiance)[1], cv::mean(without.radiance)[1], 0.002) << "seed " << seed;
  }
}

TEST(RenderDenoise, AShadowEdgeNoAovShowsStaysSharpWithTheFinePasses) {
  // Irradiance 2 left of x = 80, 0.2 right of it, on one plane of one albedo: only the
  // luminance weight sees the edge. Two columns away on either side the filtered radiance is
  // within 4 % of the step (0.9) of its truth (measured 2.7 % and 2.9 %), with or without the
  // fine passes.
  for (const int fine : {0, 2}) {
    solo::RenderOutput r = noisyRender(
        [](int x, int) {
          SurfaceTruth t;
          t.irradiance = x < 80 ? 2.f : 0.2f;
          return t;
        },
        0.1f, 7);
    solo::RenderDenoiseOptions o;
    o.fine_passes = fine;
    solo::denoiseRender(r, camera(), o);
    EXPECT_NEAR(columnMeanY(r.radiance, 78, 10, 110), 1.0, 0.04 * 0.9) << fine << " fine passes";
    EXPECT_NEAR(columnMeanY(r.radiance, 81, 10, 110), 0.1, 0.04 * 0.9) << fine << " fine passes";
    EXPECT_NEAR(columnMeanY(r.radiance, 40, 10, 110), 1.0, 0.01);
    EXPECT_NEAR(columnMeanY(r.radiance, 120, 10, 110), 0.1, 0.01);
  }
}
