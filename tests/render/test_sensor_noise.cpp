#include <solo/post/post_process.h>
#include <solo/post/sensor_noise.h>

#include "test_support.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <vector>

namespace {

struct Moments {
  double mean = 0, variance = 0;
  std::int64_t n = 0;
};

/// Sample mean and unbiased variance of all values of a single-channel image.
Moments sampleMoments(const cv::Mat& plane) {
  Moments m;
  cv::Mat flat;
  plane.reshape(1, 1).convertTo(flat, CV_64F);
  m.n = static_cast<std::int64_t>(flat.total());
  cv::Scalar mean, sd;
  cv::meanStdDev(flat, mean, sd);
  m.mean = mean[0];
  m.variance = sd[0] * sd[0] * m.n / (m.n - 1);
  return m;
}

/// The camera R, G, B planes (1 = sensor white) of an exposed XYZ (white E) image.
std::vector<cv::Mat> cameraPlanes(const cv::Mat& xyz_e) {
  cv::Mat camera;
  cv::transform(xyz_e, camera, cv::Matx33f(solo::cameraRgbFromXyzE()));
  std::vector<cv::Mat> planes;
  cv::split(camera, planes);
  return planes;
}

/// Linear sRGB luminance of camera RGB planes.
cv::Mat luminance(const std::vector<cv::Mat>& rgb) {
  const cv::Vec3d w = solo::linearSrgbLuminanceWeights();
  return rgb[0] * w[0] + rgb[1] * w[1] + rgb[2] * w[2];
}

/// Grey of exposed linear level v: XYZ = (v, v, v), white E.
cv::Mat flatGrey(int rows, int cols, double level) { return cv::Mat(rows, cols, CV_32FC3, cv::Scalar::all(level)); }

/// ../shared/docs/realism.md's robust noise sigma of one 8-bit-derived plane (CV_64F, codes),
/// over every pixel away from the border (the test images are flat, so no flatness selection):
/// 1.4826 x the median absolute deviation of h = p - mean of its 4 neighbours, / sqrt(1.25).
double robustHighPassSigma(const cv::Mat& plane) {
  cv::Mat high_pass;
  const cv::Matx33d kernel(0, -0.25, 0, -0.25, 1, -0.25, 0, -0.25, 0);
  cv::filter2D(plane, high_pass, CV_64F, kernel);
  std::vector<double> values(high_pass(cv::Rect(1, 1, plane.cols - 2, plane.rows - 2)).clone().reshape(1, 1));
  auto median = [](std::vector<double> v) {
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return v[v.size() / 2];
  };
  const double centre = median(values);
  for (double& v : values) v = std::abs(v - centre);
  return 1.4826 * median(values) / std::sqrt(1.25);
}

struct EightBitNoise {
  double luma = 0, chroma = 0;
};

/// Luma and chroma noise (realism.md) of an 8-bit RGB image: Y = 0.299 R + 0.587 G + 0.114 B,
/// chroma = mean of the sigmas of B - Y and R - Y.
EightBitNoise measure8Bit(const cv::Mat& rgb8) {
  cv::Mat rgb;
  rgb8.convertTo(rgb, CV_64FC3);
  std::vector<cv::Mat> c;
  cv::split(rgb, c);
  const cv::Mat y = 0.299 * c[0] + 0.587 * c[1] + 0.114 * c[2];
  return {robustHighPassSigma(y), 0.5 * (robustHighPassSigma(c[2] - y) + robustHighPassSigma(c[0] - y))};
}

/// A flat grey exposed image through the noise and the colour step (no glare, no exposure),
/// quantised to 8 bits.
cv::Mat developGrey(double level, const solo::SensorNoiseOptions& noise, int size = 512) {
  solo::PostProcessOptions options;
  options.glare = false;
  options.exposure = false;
  options.noise_options = noise;
  return solo::quantiseEncoded(solo::postProcess(flatGrey(size, size, level), options).encoded, 8);
}

/// sum_c w_c^2 f_c, f_c the bilinear demosaicking's squared weights averaged over the four
/// Bayer phases: red (and blue) is its own sample at its site (1), the mean of 2 at the two
/// green sites (2 x 1/4 each) and of 4 at the blue site (4 x 1/16): f = (1 + 1/2 + 1/2 + 1/4) / 4
/// = 9/16; green: 1 at its two sites, 4 x 1/16 at the others: f = (1 + 1 + 1/4 + 1/4) / 4 = 5/8.
double bilinearLumaFactor() {
  const double wr = 0.2126729, wg = 0.7151522, wb = 0.0721750;
  return 9.0 / 16.0 * wr * wr + 5.0 / 8.0 * wg * wg + 9.0 / 16.0 * wb * wb;
}

}  // namespace

TEST(SensorNoise, CalibrationTableAndInterpolationByIso) {
  const auto& table = solo::referenceNoiseCalibration();
  ASSERT_EQ(table.size(), 6u);
  const solo::NoiseCalibration at3200 = solo::noiseCalibrationAtIso(3200);
  EXPECT_DOUBLE_EQ(at3200.beta1, 4.245);
  EXPECT_DOUBLE_EQ(at3200.beta2, -231.0);
  // Linear in ISO between 400 and 800.
  const solo::NoiseCalibration at566 = solo::noiseCalibrationAtIso(566);
  EXPECT_NEAR(at566.beta1, 0.5615 + (166.0 / 400.0) * (1.1175 - 0.5615), 1e-12);
  EXPECT_NEAR(at566.beta2, -35.5 + (166.0 / 400.0) * (-69.6 + 35.5), 1e-12);
  EXPECT_THROW(solo::noiseCalibrationAtIso(50), std::invalid_argument);
  EXPECT_THROW(solo::noiseCalibrationAtIso(6400), std::invalid_argument);
  // Variance at the black level (64 counts), unscaled: about 0.2 at ISO 100, about 40 at 3200.
  solo::SensorNoiseOptions plain;
  plain.std_scale = 1;
  plain.quantise = false;
  plain.iso = 100;
  EXPECT_NEAR(solo::noiseVarianceCounts(64, plain), 0.141 * 64 - 8.8, 1e-12);
  plain.iso = 3200;
  EXPECT_NEAR(solo::noiseVarianceCounts(64, plain), 4.245 * 64 - 231.0, 1e-12);
  EXPECT_NEAR(solo::noiseVarianceCounts(64, plain), 40.0, 1.0);
  // Below the level where beta1 I + beta2 crosses zero there is no noise, never a negative variance.
  EXPECT_EQ(solo::noiseVarianceCounts(10, plain), 0.0);
  // The default scale 0.4: 0.16 x the variance.
  EXPECT_NEAR(solo::noiseVarianceCounts(64, solo::SensorNoiseOptions{}), 0.16 * (4.245 * 64 - 231.0) + 1.0 / 12, 1e-12);
}

TEST(SensorNoise, CameraSpaceMapsWhiteEToOne) {
  const cv::Vec3d white = solo::cameraRgbFromXyzE() * solo::kWhitePointE;
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(white[c], 1.0, 1e-9);
}

TEST(SensorNoise, PhotositeMeanAndVarianceMatchTheModelWithoutMosaic) {
  // Without mosaic and chroma noise reduction each camera channel of each pixel is one
  // photosite: its variance is the calibration's. 256 x 256 x 3 samples; tolerances are 5
  // standard errors of the estimators.
  struct Case {
    double iso, scale, level;
    bool clip;
  };
  for (const Case& c : {Case{3200, 3.0, 0.5, false}, Case{400, 1.0, 0.5, true}, Case{1131, 1.0, 0.1, true}}) {
    solo::SensorNoiseOptions options;
    options.iso = c.iso;
    options.std_scale = c.scale;
    options.clip = c.clip;
    options.demosaic = false;
    options.chroma_denoise_sigma_px = 0;
    options.seed = 42;
    cv::Mat patch = flatGrey(256, 256, c.level);
    const solo::StageReport report = solo::applySensorNoise(patch, options);
    EXPECT_FALSE(report.skipped);
    const double level_counts = 64 + c.level * 959;
    const double variance = solo::noiseVarianceCounts(level_counts, options);  // includes rounding's 1/12
    for (const cv::Mat& plane : cameraPlanes(patch)) {
      const Moments m = sampleMoments(plane * 959.0 + 64.0);  // back to raw counts
      EXPECT_NEAR(m.mean, level_counts, 5 * std::sqrt(variance / m.n)) << "ISO " << c.iso;
      EXPECT_NEAR(m.variance, variance, 5 * variance * std::sqrt(2.0 / (m.n - 1))) << "ISO " << c.iso;
    }
  }
}

TEST(SensorNoise, LumaVarianceFactorIsTheBilinearMosaics) {
  solo::SensorNoiseOptions options;
  // The library derives the weights from the sRGB primaries; the 7-decimal ones agree to 1e-7.
  EXPECT_NEAR(solo::lumaVarianceFactor(options), bilinearLumaFactor(), 1e-6);
  EXPECT_NEAR(bilinearLumaFactor(), 0.348024, 1e-6);
  options.demosaic = false;  // every pixel samples R, G and B: sum of w_c^2
  EXPECT_NEAR(solo::lumaVarianceFactor(options), 0.2126729 * 0.2126729 + 0.7151522 * 0.7151522 + 0.0721750 * 0.0721750,
              1e-6);
}

TEST(SensorNoise, LuminanceNoiseMatchesThePredictionAndChromaNoiseReductionKeepsIt) {
  // 512 x 512 grey at linear 0.3, ISO 3200 x 1: per-pixel luminance variance =
  // factor x photosite variance. Demosaicked noise is correlated between neighbours, so the
  // sample variance is less certain than for independent samples: 3 % tolerance.
  solo::SensorNoiseOptions options;
  options.std_scale = 1;
  options.seed = 3;
  const double level = 0.3, counts = 64 + level * 959;
  const double predicted = bilinearLumaFactor() * solo::noiseVarianceCounts(counts, options) / (959.0 * 959.0);
  cv::Mat with_nr = flatGrey(512, 512, level), without_nr = with_nr.clone();
  const solo::StageReport report = solo::applySensorNoise(with_nr, options);
  options.chroma_denoise_sigma_px = 0;
  solo::applySensorNoise(without_nr, options);
  const std::vector<cv::Mat> a = cameraPlanes(with_nr), b = cameraPlanes(without_nr);
  const Moments luma_a = sampleMoments(luminance(a));
  EXPECT_NEAR(luma_a.mean, level, 1e-4);
  EXPECT_NEAR(luma_a.variance, predicted, 0.03 * predicted);
  // Same seed: the noise reduction changed the colour differences only.
  EXPECT_LE(cv::norm(luminance(a), luminance(b), cv::NORM_INF), 1e-6);
  // B - Y: the Gaussian of sigma 2 px leaves a third of its standard deviation (demosaicked
  // blue noise is already smooth: blue is interpolated from a quarter of the photosites).
  const Moments cb_a = sampleMoments(a[2] - luminance(a)), cb_b = sampleMoments(b[2] - luminance(b));
  EXPECT_LT(std::sqrt(cb_a.variance), 0.35 * std::sqrt(cb_b.variance));
  EXPECT_NEAR(std::get<double>(*report.find("added_luma_std")), std::sqrt(predicted), 0.02 * std::sqrt(predicted));
  EXPECT_NEAR(std::get<double>(*report.find("added_chroma_std")),
              0.5 * (std::sqrt(cb_a.variance) + std::sqrt(sampleMoments(a[0] - luminance(a)).variance)), 1e-4);
}

TEST(SensorNoise, VarianceInRenderUnitsMatchesWhatTheNoiseAdds) {
  solo::SensorNoiseOptions options;
  options.clip = false;
  options.quantise = false;
  const double exposure = 9.513656920021768, render_value = 0.04;
  const double predicted = solo::noiseVarianceRenderUnits(render_value, exposure, options);
  const double counts = 64 + render_value * exposure * 959;
  EXPECT_NEAR(predicted,
              bilinearLumaFactor() * solo::noiseVarianceCounts(counts, options) / std::pow(959 * exposure, 2),
              1e-6 * predicted);
  cv::Mat patch = flatGrey(512, 512, render_value * exposure);
  solo::applySensorNoise(patch, options);
  const Moments m = sampleMoments(luminance(cameraPlanes(patch / exposure)));
  EXPECT_NEAR(m.variance, predicted, 0.03 * predicted);
  // Per pixel, from each pixel's camera levels: a grey pixel gets the scalar's value.
  const cv::Mat per_pixel = solo::noiseVarianceRenderUnits(flatGrey(2, 2, render_value), exposure, options);
  ASSERT_EQ(per_pixel.type(), CV_32FC1);
  EXPECT_NEAR(per_pixel.at<float>(1, 1), predicted, predicted * 1e-5);
}

TEST(SensorNoise, Final8BitLumaNoiseMatchesThePredictedStatistic) {
  // Flat grey images through noise, Bradford, sRGB, gamma 2.2 and 8-bit quantisation, measured
  // like ../shared/docs/realism.md: the luma noise within 10 % of the prediction. Chroma noise:
  // the 8-bit rounding of R, G and B one by one alone gives 0.28 codes; the chroma noise
  // reduction keeps the rest below 0.1 x the luma noise, where without it the chroma noise is
  // 1.5 times the luma noise.
  struct Case {
    double level, iso, scale;
  };
  for (const Case& c : {Case{0.0113, 3200, 0.4}, Case{0.0216, 3200, 0.4}, Case{0.05, 3200, 0.2}, Case{0.02, 1600, 0.5},
                        Case{0.1, 3200, 1.0}}) {
    solo::SensorNoiseOptions options;
    options.iso = c.iso;
    options.std_scale = c.scale;
    options.seed = 11;
    const EightBitNoise measured = measure8Bit(developGrey(c.level, options));
    const double predicted = solo::predictedLumaNoise8Bit(c.level, options);
    EXPECT_NEAR(measured.luma, predicted, 0.1 * predicted) << "level " << c.level << " ISO " << c.iso;
    EXPECT_LT(measured.chroma, 0.3 + 0.1 * measured.luma) << "level " << c.level << " ISO " << c.iso;
    options.chroma_denoise_sigma_px = 0;
    const EightBitNoise no_reduction = measure8Bit(developGrey(c.level, options));
    EXPECT_GT(no_reduction.chroma, 1.3 * no_reduction.luma) << "level " << c.level << " ISO " << c.iso;
  }
  EXPECT_THROW(solo::predictedLumaNoise8Bit(0.0, {}), std::invalid_argument);
}

TEST(SensorNoise, EncodedChromaReductionTakesOutTheColourTheCurveGivesLuminanceNoise) {
  // A flat saturated orange, linear camera RGB (0.30, 0.06, 0.01), with luminance-only noise
  // n (1, 1, 1) in linear (what the linear reduction leaves), encoded with gamma 2.2: each
  // channel moves by its slope s(v) = 255 / 2.2 v^(1 / 2.2 - 1) times n, 223, 537 and 1425
  // codes per unit, so Y' moves by 544 n, B' - Y' by 881 n and R' - Y' by -321 n: the chroma
  // statistic is (881 + 321) / 2 / 544 = 1.10 x the luma statistic before the reduction.
  // After it only the colour differences' smooth share (sigma 2 px: about 1 / 8 of white noise's
  // high-pass) and the 8-bit rounding (0.28 codes) are left; Y' is kept exactly.
  const cv::Vec3f orange(0.30f, 0.06f, 0.01f);
  cv::Mat linear_clean(256, 256, CV_32FC3, cv::Scalar(orange[0], orange[1], orange[2]));
  cv::Mat noise(256, 256, CV_32F);
  cv::RNG rng(17);
  rng.fill(noise, cv::RNG::NORMAL, 0.0, 0.0025);  // luma noise of about 1.4 codes
  cv::Mat linear_noisy = linear_clean.clone();
  for (int y = 0; y < noise.rows; ++y)
    for (int x = 0; x < noise.cols; ++x) linear_noisy.at<cv::Vec3f>(y, x) += cv::Vec3f::all(noise.at<float>(y, x));
  auto encode = [](const cv::Mat& linear) {
    cv::Mat encoded = linear.clone();
    encoded.forEach<cv::Vec3f>([](cv::Vec3f& p, const int*) {
      for (int k = 0; k < 3; ++k) p[k] = solo::encodeTransfer(p[k], solo::TransferCurve::Gamma22);
    });
    return encoded;
  };
  const cv::Mat clean = encode(linear_clean);
  cv::Mat noisy = encode(linear_noisy);
  // The statistics on the codes before rounding, then as an 8-bit image stores them.
  const EightBitNoise before = measure8Bit(noisy * 255.0);
  EXPECT_NEAR(before.chroma, 1.10 * before.luma, 0.05 * before.luma);
  const cv::Mat unreduced = noisy.clone();
  const solo::StageReport report = solo::reduceEncodedChromaNoise(noisy, clean, {});
  EXPECT_NEAR(measure8Bit(noisy * 255.0).luma, before.luma, 1e-4 * before.luma);
  const EightBitNoise after = measure8Bit(solo::quantiseEncoded(noisy, 8));
  EXPECT_LT(after.chroma, 0.3 + 0.1 * after.luma);
  double worst_luma_change = 0;
  for (int y = 0; y < noisy.rows; ++y)
    for (int x = 0; x < noisy.cols; ++x) {
      const cv::Vec3f &a = unreduced.at<cv::Vec3f>(y, x), &b = noisy.at<cv::Vec3f>(y, x);
      const double luma_a = 0.299 * a[0] + 0.587 * a[1] + 0.114 * a[2];
      const double luma_b = 0.299 * b[0] + 0.587 * b[1] + 0.114 * b[2];
      worst_luma_change = std::max(worst_luma_change, std::abs(luma_a - luma_b));
    }
  EXPECT_LT(worst_luma_change * 255, 1e-3);
  EXPECT_GT(std::get<double>(*report.find("noise_chroma_std_before")),
            5 * std::get<double>(*report.find("noise_chroma_std_after")));
  // Without noise nothing changes; a size mismatch is refused.
  cv::Mat same = clean.clone();
  solo::reduceEncodedChromaNoise(same, clean, {});
  EXPECT_EQ(cv::norm(same, clean, cv::NORM_INF), 0.0);
  cv::Mat smaller(8, 8, CV_32FC3, cv::Scalar::all(0.5));
  EXPECT_ANY_THROW(solo::reduceEncodedChromaNoise(smaller, clean, {}));
}

TEST(SensorNoise, DevelopedSaturatedColourKeepsOnlyTheRoundingsChromaNoise) {
  // The whole camera (noise with mosaic, linear and encoded chroma reduction, colour step) on
  // the flat orange of the test above: the chroma statistic stays at the 8-bit rounding's
  // 0.28 codes plus at most 0.1 x the luma noise, as on a grey; the report has the step.
  solo::PostProcessOptions options;
  options.glare = false;
  options.exposure = false;
  options.noise_options.std_scale = 1.0;
  options.noise_options.seed = 5;
  const cv::Mat orange_xyz_e = [] {
    cv::Mat camera(512, 512, CV_32FC3, cv::Scalar(0.30, 0.06, 0.01));
    cv::Mat xyz;
    cv::transform(camera, xyz, cv::Matx33f(solo::cameraRgbFromXyzE().inv()));
    return xyz;
  }();
  const solo::PostProcessResult r = solo::postProcess(orange_xyz_e, options);
  const EightBitNoise measured = measure8Bit(solo::quantiseEncoded(r.encoded, 8));
  EXPECT_GT(measured.luma, 0.5);
  EXPECT_LT(measured.chroma, 0.3 + 0.1 * measured.luma);
  ASSERT_EQ(r.steps.back().name, "chroma");
  EXPECT_FALSE(r.steps.back().skipped);
  options.noise_options.chroma_denoise_sigma_px = 0;
  const solo::PostProcessResult unreduced = solo::postProcess(orange_xyz_e, options);
  EXPECT_TRUE(unreduced.steps.back().skipped);
  EXPECT_GT(measure8Bit(solo::quantiseEncoded(unreduced.encoded, 8)).chroma, measured.luma);
}

TEST(SensorNoise, DefaultScaleGivesNightPhotoNoiseInTheMidTones) {
  // Night photos' mid-tones: encoded luma 30-45 (linear 0.0111-0.0263). Real night photos'
  // luma noise is 0.66-1.15 codes (realism.md); the default ISO 3200 x 0.2 lands inside.
  for (const double codes : {30.0, 45.0}) {
    const double level = std::pow(codes / 255.0, 2.2);
    const double sigma = solo::predictedLumaNoise8Bit(level, {});
    EXPECT_GT(sigma, 0.66) << codes;
    EXPECT_LT(sigma, 1.15) << codes;
  }
}

TEST(SensorNoise, SeededAndIndependentOfTheThreadCount) {
  cv::Mat base(64, 80, CV_32FC3, cv::Scalar(0.2, 0.3, 0.4));
  solo::SensorNoiseOptions options;
  options.seed = 9;
  cv::Mat a = base.clone(), b = base.clone(), c = base.clone(), d = base.clone();
  solo::applySensorNoise(a, options);
  solo::applySensorNoise(d, options);
  const int threads = cv::getNumThreads();
  cv::setNumThreads(1);
  solo::applySensorNoise(b, options);
  cv::setNumThreads(threads);
  EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(a, d, cv::NORM_INF), 0.0);
  options.seed = 10;
  solo::applySensorNoise(c, options);
  EXPECT_GT(cv::norm(a, c, cv::NORM_INF), 0.0);
}

TEST(SensorNoise, BlackImageStaysAtTheBlackLevelAndHighlightsPassUnchanged) {
  solo::SensorNoiseOptions options;
  options.std_scale = 3;  // the reference's strength, so that the black level is well above rounding
  cv::Mat black = cv::Mat::zeros(256, 256, CV_32FC3);
  const solo::StageReport report = solo::applySensorNoise(black, options);
  EXPECT_TRUE(cv::checkRange(black));
  // Photosite sigma at the black level = 3 sqrt(4.245 x 64 - 231) = 19.1 counts; the
  // luminance noise's mean is 0 within 5 standard errors of its (correlated: x2) samples.
  const double site_sigma = 3 * std::sqrt(4.245 * 64 - 231);
  const Moments luma = sampleMoments(luminance(cameraPlanes(black)) * 959.0);
  const double luma_sigma = std::sqrt(bilinearLumaFactor() * (site_sigma * site_sigma + 1.0 / 12));
  EXPECT_NEAR(luma.mean, 0.0, 2 * 5 * luma_sigma / std::sqrt(static_cast<double>(luma.n)));
  EXPECT_NEAR(std::sqrt(luma.variance), luma_sigma, 0.03 * luma_sigma);
  EXPECT_NEAR(std::get<double>(*report.find("std_at_black_level")), site_sigma, 1e-9);
  // Raw 0 is the floor: no photosite below -64 counts, so no camera channel far below it.
  double lo = 0;
  for (const cv::Mat& plane : cameraPlanes(black)) {
    double plane_lo = 0;
    cv::minMaxLoc(plane, &plane_lo);
    lo = std::min(lo, plane_lo);
  }
  EXPECT_GE(lo * 959, -64.0 - 1e-3);
  // Values above sensor white: every photosite saturates, gets no noise, and the image keeps
  // its own value for the colour step's highlight handling.
  cv::Mat bright(16, 16, CV_32FC3, cv::Scalar(5.0, 4.0, 3.0));
  const solo::StageReport saturated = solo::applySensorNoise(bright, {});
  EXPECT_EQ(cv::norm(bright, cv::Mat(16, 16, CV_32FC3, cv::Scalar(5.0, 4.0, 3.0)), cv::NORM_INF), 0.0);
  EXPECT_EQ(std::get<std::int64_t>(*saturated.find("clipped_at_white")), 16 * 16);  // one photosite per pixel
}

TEST(SensorNoise, SigmaInRenderUnitsFollowsTheCalibrationThroughBothScales) {
  // A render of luminance Y is multiplied by c = 0.01 before the post-process and by the
  // exposure e = 9.5: raw counts 64 + Y c e 959; the final luminance sigma in render units =
  // sqrt(factor) x photosite sigma / (959 e c).
  const solo::SensorNoiseOptions options;
  const double c = 0.01, e = 9.5;
  const auto sigma = solo::sensorNoiseSigma(c, e, options);
  for (double y : {0.0, 1.0, 5.0, 10.0}) {
    const double counts = 64 + y * c * e * 959;
    const double expected = std::sqrt(bilinearLumaFactor()) * 0.4 * std::sqrt(4.245 * counts - 231) / (959 * e * c);
    EXPECT_NEAR(sigma(y), expected, 1e-6 * expected) << y;  // 7-decimal weights
    EXPECT_NEAR(sigma(y), std::sqrt(solo::noiseVarianceRenderUnits(y * c, e, options)) / c, 1e-9 * expected);
  }
  EXPECT_THROW(solo::sensorNoiseSigma(0.0, e, options), std::invalid_argument);
  solo::SensorNoiseOptions bad;
  bad.chroma_denoise_strength = 2;
  EXPECT_THROW(solo::sensorNoiseSigma(c, e, bad), std::invalid_argument);
}
