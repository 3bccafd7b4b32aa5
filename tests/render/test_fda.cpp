#include <solo/post/fda.h>
#include <solo/core/error.h>

#include "test_support.h"

#include <cmath>
#include <random>

namespace {

cv::Mat randomImage(int rows, int cols, std::uint64_t seed, double lo, double hi) {
  cv::Mat image(rows, cols, CV_32FC3);
  cv::RNG rng(seed);
  rng.fill(image, cv::RNG::UNIFORM, lo, hi);
  // Some low-frequency structure, so amplitudes differ between the images.
  for (int y = 0; y < rows; ++y)
    for (int x = 0; x < cols; ++x)
      image.at<cv::Vec3f>(y, x) += cv::Vec3f::all(static_cast<float>(0.2 * std::sin(0.1 * x + 0.05 * seed * y)));
  return image;
}

/// Complex spectrum (CV_64FC2) of one channel.
cv::Mat spectrum(const cv::Mat& image, int channel) {
  cv::Mat plane, as_double, out;
  cv::extractChannel(image, plane, channel);
  plane.convertTo(as_double, CV_64F);
  cv::dft(as_double, out, cv::DFT_COMPLEX_OUTPUT);
  return out;
}

double amplitude(const cv::Mat& s, int y, int x) { return std::hypot(s.at<cv::Vec2d>(y, x)[0], s.at<cv::Vec2d>(y, x)[1]); }
double phase(const cv::Mat& s, int y, int x) { return std::atan2(s.at<cv::Vec2d>(y, x)[1], s.at<cv::Vec2d>(y, x)[0]); }

}  // namespace

TEST(Fda, BetaZeroReturnsTheSource) {
  const cv::Mat source = randomImage(40, 60, 1, 0.0, 1.0), target = randomImage(40, 60, 2, 0.0, 0.3);
  solo::FdaOptions options;
  options.beta = 0;
  const solo::FdaResult r = solo::fourierDomainAdaptation(source, target, options);
  EXPECT_EQ(cv::norm(r.image, source, cv::NORM_INF), 0.0);
  EXPECT_EQ(std::get<std::int64_t>(*r.report.find("swapped_frequencies")), 0);
}

TEST(Fda, FullBandGivesTheTargetAmplitudeWithTheSourcePhase) {
  const cv::Mat source = randomImage(48, 64, 3, 0.0, 1.0), target = randomImage(48, 64, 4, 0.0, 0.3);
  solo::FdaOptions options;
  options.beta = 1.0;  // b = 48 > 64/2: every frequency
  const solo::FdaResult r = solo::fourierDomainAdaptation(source, target, options);
  EXPECT_EQ(std::get<std::int64_t>(*r.report.find("swapped_frequencies")), 48 * 64);
  for (int c = 0; c < 3; ++c) {
    const cv::Mat out = spectrum(r.image, c), tgt = spectrum(target, c), src = spectrum(source, c);
    for (int y = 0; y < 48; y += 5)
      for (int x = 0; x < 64; x += 3) {
        EXPECT_NEAR(amplitude(out, y, x), amplitude(tgt, y, x), 1e-3 * (1 + amplitude(tgt, y, x)));
        if (amplitude(tgt, y, x) > 1e-2 && amplitude(src, y, x) > 1e-2) {
          EXPECT_NEAR(std::cos(phase(out, y, x) - phase(src, y, x)), 1.0, 1e-4);
        }
      }
  }
}

TEST(Fda, SmallBandSwapsOnlyTheLowestFrequencies) {
  const cv::Mat source = randomImage(100, 120, 5, 0.0, 1.0), target = randomImage(100, 120, 6, 0.0, 0.3);
  solo::FdaOptions options;
  options.beta = 0.03;  // b = 3: |fy|, |fx| <= 2
  const solo::FdaResult r = solo::fourierDomainAdaptation(source, target, options);
  EXPECT_EQ(std::get<std::int64_t>(*r.report.find("band_half_size")), 3);
  EXPECT_EQ(std::get<std::int64_t>(*r.report.find("swapped_frequencies")), 25);
  // DC swapped: every channel takes the target's mean.
  const cv::Scalar out_mean = cv::mean(r.image), target_mean = cv::mean(target);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(out_mean[c], target_mean[c], 1e-5);
  const cv::Mat out = spectrum(r.image, 1), tgt = spectrum(target, 1), src = spectrum(source, 1);
  EXPECT_NEAR(amplitude(out, 2, 118), amplitude(tgt, 2, 118), 1e-3);  // (fy, fx) = (2, -2): inside
  EXPECT_NEAR(amplitude(out, 3, 0), amplitude(src, 3, 0), 1e-3);      // fy = 3: outside, kept
  EXPECT_NEAR(amplitude(out, 0, 60), amplitude(src, 0, 60), 1e-3);
}

TEST(Fda, TargetOfAnotherSizeIsResized) {
  const cv::Mat source = randomImage(30, 40, 7, 0.0, 1.0);
  const cv::Mat target(60, 80, CV_32FC3, cv::Scalar(0.1, 0.2, 0.3));
  const solo::FdaResult r = solo::fourierDomainAdaptation(source, target, {});
  ASSERT_EQ(r.image.size(), source.size());
  ASSERT_FALSE(r.report.notes.empty());
  EXPECT_NE(r.report.notes[0].find("resized from 80x60 to the source's 40x30"), std::string::npos);
  const cv::Scalar m = cv::mean(r.image);  // b = 0.3 -> 0: beta 0.01 on a 30 px image swaps nothing
  EXPECT_NEAR(m[0], cv::mean(source)[0], 1e-5);
  solo::FdaOptions wide;
  wide.beta = 0.1;  // b = 3: DC from the flat target
  const cv::Scalar m2 = cv::mean(solo::fourierDomainAdaptation(source, target, wide).image);
  EXPECT_NEAR(m2[0], 0.1, 1e-5);
  EXPECT_NEAR(m2[2], 0.3, 1e-5);
  EXPECT_THROW(solo::fourierDomainAdaptation(source, target, solo::FdaOptions{1.5}), solo::InputError);
}
