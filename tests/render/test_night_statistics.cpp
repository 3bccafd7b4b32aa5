#include <solo/post/night_statistics.h>

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

constexpr int kWidth = 960, kHeight = 540;  // the analysis size: no resize
constexpr double kPixels = kWidth * kHeight;

cv::Mat grey(int value, int width = kWidth, int height = kHeight) {
  return cv::Mat(height, width, CV_8UC3, cv::Scalar::all(value));
}

/// `base` plus white Gaussian noise of `sigma` codes (seeded) in the channels of `mask`
/// (1 = channel gets noise; one draw shared by all of them), rounded to 8-bit codes.
cv::Mat withNoise(int base, double sigma, cv::Vec3d mask, std::uint64_t seed) {
  cv::Mat noise(kHeight, kWidth, CV_64F);
  cv::RNG rng(seed);
  rng.fill(noise, cv::RNG::NORMAL, 0.0, sigma);
  cv::Mat image(kHeight, kWidth, CV_8UC3);
  for (int y = 0; y < kHeight; ++y)
    for (int x = 0; x < kWidth; ++x)
      for (int c = 0; c < 3; ++c)
        image.at<cv::Vec3b>(y, x)[c] = cv::saturate_cast<uchar>(base + mask[c] * noise.at<double>(y, x));
  return image;
}

/// A clipped disc of radius `disc_px` around (cx, cy) on `background`, its luma falling
/// linearly from 255 at the disc's edge to the background `ramp_px` further out.
cv::Mat discWithRamp(double cx, double cy, double disc_px, double ramp_px, int background) {
  cv::Mat image = grey(background);
  for (int y = 0; y < kHeight; ++y)
    for (int x = 0; x < kWidth; ++x) {
      const double d = std::hypot(x - cx, y - cy);
      const double t = ramp_px > 0 ? std::clamp((d - disc_px) / ramp_px, 0.0, 1.0) : (d <= disc_px ? 0.0 : 1.0);
      image.at<cv::Vec3b>(y, x) = cv::Vec3b::all(cv::saturate_cast<uchar>(255.0 - t * (255.0 - background)));
    }
  return image;
}

solo::NightStatistics statisticsOf(const cv::Mat& rgb) {
  return solo::computeNightStatistics(rgb, solo::ChannelOrder::Rgb);
}

}  // namespace

TEST(NightStatistics, WhiteNoiseOfKnownSigmaReadsThatSigma) {
  for (const double sigma : {2.0, 4.0, 8.0}) {
    const solo::NightStatistics s = statisticsOf(withNoise(100, sigma, {1, 1, 1}, 7));
    ASSERT_TRUE(s.noise_luma);
    EXPECT_NEAR(*s.noise_luma, sigma, 0.05 * sigma) << "sigma " << sigma;
    ASSERT_TRUE(s.chroma_noise);
    EXPECT_NEAR(*s.chroma_noise, 0.0, 1e-9);  // grey noise: B - Y = R - Y = 0
  }
}

TEST(NightStatistics, NoiseInOneChannelSplitsIntoLumaAndChromaByTheLumaWeights) {
  // Noise n in B only: Y carries 0.114 n, B - Y carries 0.886 n, R - Y carries -0.114 n.
  const double sigma = 8.0;
  const solo::NightStatistics s = statisticsOf(withNoise(100, sigma, {0, 0, 1}, 11));
  ASSERT_TRUE(s.noise_luma && s.chroma_noise);
  EXPECT_NEAR(*s.noise_luma, 0.114 * sigma, 0.05 * 0.114 * sigma);
  EXPECT_NEAR(*s.chroma_noise, 0.5 * (0.886 + 0.114) * sigma, 0.05 * 0.5 * sigma);
}

TEST(NightStatistics, FlatImageReadsZeroNoiseAndBlackHasNoMidTones) {
  const solo::NightStatistics s = statisticsOf(grey(100));
  ASSERT_TRUE(s.noise_luma && s.chroma_noise);
  EXPECT_EQ(*s.noise_luma, 0.0);
  EXPECT_NEAR(*s.chroma_noise, 0.0, 1e-12);
  EXPECT_NEAR(s.mean_luma, 100.0, 1e-9);
  EXPECT_NEAR(s.p50_luma, 100.0, 1e-9);
  EXPECT_NEAR(s.p99_luma, 100.0, 1e-9);

  const solo::NightStatistics black = statisticsOf(grey(0));
  EXPECT_FALSE(black.noise_luma);  // no pixel with 5 < Y < 250
  EXPECT_FALSE(black.chroma_noise);
  EXPECT_FALSE(black.cast_cb);  // no pixel with 20 < Y < 80
  EXPECT_EQ(black.halo_blobs, 0);
  EXPECT_FALSE(black.halo_radius_px);
}

TEST(NightStatistics, ClippedAndBrightSharesAreExactAtTheirThresholds) {
  cv::Mat image = grey(100);
  image(cv::Rect(10, 10, 30, 20)).setTo(cv::Scalar::all(255));  // 600 clipped and bright
  image(cv::Rect(100, 10, 10, 10)).setTo(cv::Scalar::all(250));  // 100 clipped (>= 250) and bright
  image(cv::Rect(200, 10, 10, 10)).setTo(cv::Scalar::all(249));  // 100 bright only
  image(cv::Rect(300, 10, 40, 10)).setTo(cv::Scalar::all(200));  // 400 bright (>= 200)
  image(cv::Rect(400, 10, 10, 10)).setTo(cv::Scalar::all(199));  // neither
  const solo::NightStatistics s = statisticsOf(image);
  EXPECT_DOUBLE_EQ(s.clipped_share, 700 / kPixels);
  EXPECT_DOUBLE_EQ(s.bright_share, 1200 / kPixels);
  EXPECT_EQ(s.analysis_width_px, kWidth);
  EXPECT_EQ(s.analysis_height_px, kHeight);
}

TEST(NightStatistics, PercentilesAndMeanOfATwoLevelImage) {
  cv::Mat image = grey(10);
  image(cv::Rect(0, 0, kWidth, kHeight / 2)).setTo(cv::Scalar::all(90));  // half the pixels at 90
  const solo::NightStatistics s = statisticsOf(image);
  EXPECT_NEAR(s.mean_luma, 50.0, 1e-9);
  EXPECT_NEAR(s.p50_luma, 50.0, 1e-9);  // NumPy's median of an even count: mean of the middle two
  EXPECT_NEAR(s.p90_luma, 90.0, 1e-9);
}

TEST(NightStatistics, HaloRadiusOfAClippedDiscWithALinearFallOff) {
  // Background 30 (the image's median), headroom 225, edge 30 + 22.5: reached 0.9 of the way
  // down a 20 px ramp starting at the disc's edge, 10 + 18 = 28 px from the centre.
  cv::Mat image = discWithRamp(480, 270, 10, 20, 30);
  image(cv::Rect(50, 50, 3, 1)).setTo(cv::Scalar::all(255));  // a 3 px blob: too small for a halo
  const solo::NightStatistics s = statisticsOf(image);
  EXPECT_EQ(s.halo_blobs, 1);
  ASSERT_TRUE(s.halo_radius_px);
  EXPECT_NEAR(*s.halo_radius_px, 28.0, 0.3);
}

TEST(NightStatistics, HaloRadiusOfASharpDiscIsItsRadiusAndTheMedianIsOverBlobs) {
  // Without a halo the ring profile drops inside the ring that straddles the edge.
  cv::Mat image = grey(30);
  cv::circle(image, {200, 200}, 12, cv::Scalar::all(255), cv::FILLED);
  cv::circle(image, {500, 200}, 12, cv::Scalar::all(255), cv::FILLED);
  cv::circle(image, {800, 200}, 30, cv::Scalar::all(255), cv::FILLED);
  const solo::NightStatistics s = statisticsOf(image);
  EXPECT_EQ(s.halo_blobs, 3);
  ASSERT_TRUE(s.halo_radius_px);
  EXPECT_GE(*s.halo_radius_px, 12.0);  // the median: a 12 px disc
  EXPECT_LE(*s.halo_radius_px, 13.0);
}

TEST(NightStatistics, HaloRadiusStopsAtTheMaximumWhenTheProfileNeverFalls) {
  const cv::Mat luma(101, 101, CV_64F, cv::Scalar(255));
  EXPECT_EQ(solo::haloRadiusPx(luma, {50, 50}, 100, 40), 40.0);
}

TEST(NightStatistics, WarmDimImageHasNegativeCbAndPositiveCrInEitherChannelOrder) {
  const cv::Mat warm_rgb(kHeight, kWidth, CV_8UC3, cv::Scalar(60, 40, 25));  // R, G, B
  const double luma = 0.299 * 60 + 0.587 * 40 + 0.114 * 25;                  // 44.27
  const solo::NightStatistics s = statisticsOf(warm_rgb);
  ASSERT_TRUE(s.cast_cb && s.cast_cr);
  EXPECT_NEAR(*s.cast_cb, 25 - luma, 1e-9);
  EXPECT_NEAR(*s.cast_cr, 60 - luma, 1e-9);
  EXPECT_LT(*s.cast_cb, 0);
  EXPECT_GT(*s.cast_cr, 0);

  cv::Mat warm_bgr;
  cv::cvtColor(warm_rgb, warm_bgr, cv::COLOR_RGB2BGR);
  const solo::NightStatistics from_bgr = solo::computeNightStatistics(warm_bgr, solo::ChannelOrder::Bgr);
  EXPECT_NEAR(*from_bgr.cast_cb, *s.cast_cb, 1e-12);
  EXPECT_NEAR(*from_bgr.cast_cr, *s.cast_cr, 1e-12);
  // The same bytes read in the wrong order are a cool image.
  const solo::NightStatistics swapped = solo::computeNightStatistics(warm_rgb, solo::ChannelOrder::Bgr);
  EXPECT_GT(*swapped.cast_cb, 0);
  EXPECT_LT(*swapped.cast_cr, 0);
}

TEST(NightStatistics, SixteenBitAndFloatInputsAreQuantisedToTheSameCodes) {
  const cv::Mat codes = withNoise(60, 5, {1, 0.5, 0.2}, 3);
  cv::Mat sixteen, floating;
  codes.convertTo(sixteen, CV_16U, 257.0);
  codes.convertTo(floating, CV_32F, 1.0 / 255.0);
  const solo::NightStatistics a = statisticsOf(codes), b = statisticsOf(sixteen), c = statisticsOf(floating);
  for (const solo::NightStatistics* other : {&b, &c}) {
    EXPECT_EQ(other->mean_luma, a.mean_luma);
    EXPECT_EQ(*other->noise_luma, *a.noise_luma);
    EXPECT_EQ(*other->chroma_noise, *a.chroma_noise);
    EXPECT_EQ(*other->cast_cb, *a.cast_cb);
  }
}

TEST(NightStatistics, PilBilinearShrinkWeighsATriangleOfTwiceTheSupport) {
  // Columns 0, 10, ..., 70 shrunk to 4: weights (1, 3, 3, 1) / 8 inside, renormalised at the
  // borders ((3, 3, 1) / 7): 50/7 -> 7, 25, 45, 440/7 -> 63.
  cv::Mat ramp(4, 8, CV_8UC3);
  for (int x = 0; x < 8; ++x) ramp.col(x).setTo(cv::Scalar::all(10 * x));
  const cv::Mat out = solo::resizeBilinearLikePil(ramp, {4, 2});
  ASSERT_EQ(out.size(), cv::Size(4, 2));
  const int expected[] = {7, 25, 45, 63};
  for (int y = 0; y < 2; ++y)
    for (int x = 0; x < 4; ++x) EXPECT_EQ(out.at<cv::Vec3b>(y, x), cv::Vec3b::all(expected[x])) << x << "," << y;
}

TEST(NightStatistics, WiderImagesAreResizedTo960AndHeightRoundsHalfToEven) {
  // 1920x1081 -> 960 x round(540.5) = 960x540 (Python's round: half to even).
  const solo::NightStatistics s = statisticsOf(grey(100, 1920, 1081));
  EXPECT_EQ(s.source_width_px, 1920);
  EXPECT_EQ(s.analysis_width_px, 960);
  EXPECT_EQ(s.analysis_height_px, 540);
  EXPECT_NEAR(s.mean_luma, 100.0, 1e-9);
}

TEST(NightStatistics, RejectsWhatIsNotAColourImage) {
  EXPECT_THROW(statisticsOf(cv::Mat(10, 10, CV_8UC1, cv::Scalar(3))), std::invalid_argument);
  EXPECT_THROW(statisticsOf(cv::Mat()), std::invalid_argument);
  EXPECT_THROW(statisticsOf(cv::Mat(10, 10, CV_32SC3, cv::Scalar::all(3))), std::invalid_argument);
}

TEST(NightStatistics, ReportStageLeadsWithTheHeadlineAndNotesWhatHasNoValue) {
  const solo::NightStatistics s = statisticsOf(grey(0));  // no mid-tones, no dim pixels, no blob
  const solo::StageReport report = solo::nightStatisticsReport(s, 0.25);
  EXPECT_EQ(report.name, "realism");
  EXPECT_EQ(report.seconds, 0.25);
  std::vector<std::string> names;
  for (const solo::Metric& m : report.metrics) names.push_back(m.name);
  EXPECT_EQ(names, (std::vector<std::string>{"mean", "clipped", "bright", "p50", "p90", "p99", "halo_blobs"}));
  EXPECT_EQ(report.notes, (std::vector<std::string>{"noise: none", "chroma_noise: none", "halo_radius_px: none",
                                                    "cast_cb: none", "cast_cr: none"}));
  EXPECT_EQ(std::get<std::int64_t>(*report.find("halo_blobs")), 0);
  EXPECT_EQ(std::get<double>(*report.find("mean")), 0.0);
}
