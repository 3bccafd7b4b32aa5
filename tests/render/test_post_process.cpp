#include <solo/post/post_process.h>

#include "test_support.h"

#include <cmath>
#include <limits>

namespace {

solo::PostProcessOptions noiseless() {
  solo::PostProcessOptions options;
  options.noise = false;
  options.glare = false;
  return options;
}

const solo::StageReport& step(const solo::PostProcessResult& r, const std::string& name) {
  for (const auto& s : r.steps)
    if (s.name == name) return s;
  throw std::runtime_error("no step " + name);
}

const double kReferenceScale = std::exp2(3.25);

}  // namespace

TEST(PostProcess, WhiteEAtUnitExposureBecomesSrgbWhiteAndGreyStaysNeutral) {
  cv::Mat xyz(2, 2, CV_32FC3, cv::Scalar::all(1.0 / kReferenceScale));
  xyz.at<cv::Vec3f>(1, 1) = cv::Vec3f::all(static_cast<float>(0.18 / kReferenceScale));
  const solo::PostProcessResult r = solo::postProcess(xyz, noiseless());
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(r.encoded.at<cv::Vec3f>(0, 0)[c], 1.0, 1e-5);
    EXPECT_NEAR(r.linear_rgb.at<cv::Vec3f>(0, 0)[c], 1.0, 1e-5);
    EXPECT_NEAR(r.encoded.at<cv::Vec3f>(1, 1)[c], std::pow(0.18, 1 / 2.2), 1e-5);
  }
  ASSERT_EQ(r.steps.size(), 7u);
  const char* order[] = {"input", "glare", "exposure", "noise", "adaptation", "colour", "chroma"};
  for (int i = 0; i < 7; ++i) EXPECT_EQ(r.steps[i].name, order[i]);
  EXPECT_EQ(r.report.name, "post");
  EXPECT_NE(r.report.find("exposure.stops"), nullptr);
  EXPECT_NE(r.report.find("adaptation.m00"), nullptr);
}

TEST(PostProcess, EverySwitchedOffStepSaysSo) {
  solo::PostProcessOptions options = noiseless();
  options.exposure = false;
  options.adaptation = false;
  const cv::Mat xyz(4, 4, CV_32FC3, cv::Scalar(0.2, 0.2, 0.2));
  const solo::PostProcessResult r = solo::postProcess(xyz, options);
  for (const char* name : {"glare", "exposure", "noise", "adaptation", "chroma"}) {
    EXPECT_TRUE(step(r, name).skipped) << name;
    EXPECT_EQ(step(r, name).skip_reason.rfind("switched off", 0), 0u) << name;
  }
  EXPECT_EQ(r.report.notes.size(), 5u);
  // Without adaptation, E white (X = Y = Z) is not neutral in sRGB: red exceeds blue.
  const cv::Vec3f p = r.linear_rgb.at<cv::Vec3f>(0, 0);
  EXPECT_GT(p[0], p[2]);
}

TEST(PostProcess, NonFiniteAndNegativeInputsAreZeroedAndCounted) {
  cv::Mat xyz(3, 3, CV_32FC3, cv::Scalar::all(0.05));
  xyz.at<cv::Vec3f>(0, 0) = {std::numeric_limits<float>::quiet_NaN(), 0.05f, 0.05f};
  xyz.at<cv::Vec3f>(1, 1) = cv::Vec3f::all(std::numeric_limits<float>::infinity());
  xyz.at<cv::Vec3f>(2, 2) = {-1.f, -1.f, -1.f};
  xyz.at<cv::Vec3f>(2, 0) = {0.05f, -std::numeric_limits<float>::infinity(), 0.05f};
  const solo::PostProcessResult r = solo::postProcess(xyz, noiseless());
  const solo::StageReport& input = step(r, "input");
  EXPECT_EQ(std::get<std::int64_t>(*input.find("nan_values")), 1);
  EXPECT_EQ(std::get<std::int64_t>(*input.find("inf_values")), 4);
  EXPECT_EQ(std::get<std::int64_t>(*input.find("negative_values")), 3);
  ASSERT_EQ(input.notes.size(), 1u);
  EXPECT_TRUE(cv::checkRange(r.encoded, true, nullptr, 0.0, 1.0 + 1e-6));
  EXPECT_EQ(r.encoded.at<cv::Vec3f>(1, 1), cv::Vec3f(0, 0, 0));
  EXPECT_EQ(r.encoded.at<cv::Vec3f>(2, 2), cv::Vec3f(0, 0, 0));
  // With glare and noise on, the zeroed pixels do not poison the image either.
  const solo::PostProcessResult full = solo::postProcess(xyz, solo::PostProcessOptions{});
  EXPECT_TRUE(cv::checkRange(full.encoded));
}

TEST(PostProcess, AllBlackImage) {
  const cv::Mat black = cv::Mat::zeros(32, 48, CV_32FC3);
  const solo::PostProcessResult quiet = solo::postProcess(black, noiseless());
  EXPECT_EQ(cv::countNonZero(quiet.encoded.reshape(1)), 0);
  solo::PostProcessOptions with_glare = noiseless();
  with_glare.glare = true;
  const solo::PostProcessResult glare = solo::postProcess(black, with_glare);
  EXPECT_TRUE(step(glare, "glare").skipped);
  EXPECT_NE(step(glare, "glare").skip_reason.find("no pixel brighter"), std::string::npos);
  // Sensor noise at the black level still shows (as in a real night photo), finite and in range.
  const solo::PostProcessResult noisy = solo::postProcess(black, solo::PostProcessOptions{});
  EXPECT_TRUE(cv::checkRange(noisy.encoded, true, nullptr, 0.0, 1.0 + 1e-6));
  EXPECT_GT(cv::mean(noisy.encoded)[1], 0.0);
}

TEST(PostProcess, TinyVeryBrightSourceBurnsOutWithoutOverflow) {
  cv::Mat xyz = cv::Mat::zeros(300, 400, CV_32FC3);
  xyz.at<cv::Vec3f>(150, 200) = cv::Vec3f::all(1e7f);
  solo::PostProcessOptions options;
  options.noise = false;
  const solo::PostProcessResult r = solo::postProcess(xyz, options);
  EXPECT_TRUE(cv::checkRange(r.encoded, true, nullptr, 0.0, 1.0 + 1e-6));
  EXPECT_NEAR(r.encoded.at<cv::Vec3f>(150, 200)[1], 1.0, 1e-6);
  // The glow reaches far: 100 px away the kernel still passes 1e7 * 9.5 * k >> 1.
  EXPECT_NEAR(r.encoded.at<cv::Vec3f>(150, 300)[1], 1.0, 1e-6);
  EXPECT_GT(std::get<std::int64_t>(*step(r, "colour").find("over_range_pixels")), 1000);
  EXPECT_EQ(std::get<std::string>(*step(r, "glare").find("method")), "direct");
}

TEST(PostProcess, RejectsBadImagesAndOptionsBeforeWorking) {
  EXPECT_THROW(solo::postProcess(cv::Mat(), {}), std::invalid_argument);
  EXPECT_THROW(solo::postProcess(cv::Mat::zeros(4, 4, CV_32FC1), {}), std::invalid_argument);
  solo::PostProcessOptions options;
  options.noise_options.iso = 12800;
  EXPECT_THROW(solo::postProcess(cv::Mat::zeros(4, 4, CV_32FC3), options), solo::InputError);
}

TEST(PostProcess, RenderNoiseSigmaScalesWithTheSensorWhite) {
  // The noise target is set in render units: a scene rendered twice as bright and exposed to a
  // twice higher white gets the same image, so its noise sigma at twice the luminance is twice
  // as large.
  const auto at_5 = solo::renderNoiseSigma(5.0), at_10 = solo::renderNoiseSigma(10.0);
  for (const double y : {0.0, 0.01, 0.5, 2.0, 5.0}) {
    EXPECT_GT(at_5(y), 0.0) << y;
    EXPECT_NEAR(at_10(2 * y), 2 * at_5(y), 1e-9 * at_5(y)) << y;
  }
  // More light, more shot noise.
  EXPECT_GT(at_5(5.0), at_5(0.0));
}

TEST(PostProcess, SaturatedRedLampKeepsItsHueWithSensorNoiseOn) {
  // A red tail lamp (SAE J578 chromaticity 0.70, 0.29) at 20x the level where its red channel
  // reaches white, on a dark street, noise on: the noise step keeps the over-range values
  // (saturated photosites get no noise) and the colour step desaturates them toward white;
  // clipping red alone would leave G < B, a magenta core. Its rim (2x) stays red: R > G, R > B.
  const cv::Vec3d red_xyz{0.70 / 0.29, 1.0, 0.01 / 0.29};
  solo::PostProcessOptions options;
  options.glare = false;
  options.exposure = false;
  options.adaptation = false;  // the lamp is given relative to D65
  cv::Mat probe(1, 1, CV_32FC3, cv::Scalar(red_xyz[0], red_xyz[1], red_xyz[2]));
  solo::PostProcessOptions quiet = options;
  quiet.noise = false;
  const cv::Vec3f unit_rgb = solo::postProcess(probe, quiet).linear_rgb.at<cv::Vec3f>(0, 0);
  const double clip_level = 1.0 / std::max({unit_rgb[0], unit_rgb[1], unit_rgb[2]});
  cv::Mat xyz(64, 64, CV_32FC3, cv::Scalar::all(0.01));
  const cv::Vec3d core = red_xyz * (20 * clip_level), rim = red_xyz * (2 * clip_level);
  xyz(cv::Rect(16, 16, 32, 32)).setTo(cv::Scalar(rim[0], rim[1], rim[2]));
  xyz(cv::Rect(28, 28, 8, 8)).setTo(cv::Scalar(core[0], core[1], core[2]));
  const solo::PostProcessResult r = solo::postProcess(xyz, options);
  EXPECT_EQ(r.encoded.at<cv::Vec3f>(31, 31), cv::Vec3f(1, 1, 1));  // luminance 20 x 0.22 > 1: white
  const cv::Vec3f rim_pixel = r.encoded.at<cv::Vec3f>(20, 20);
  EXPECT_GT(rim_pixel[0], 0.99f);  // the shoulder approaches 1
  EXPECT_GT(rim_pixel[0], rim_pixel[1] + 0.2f);
  EXPECT_GT(rim_pixel[0], rim_pixel[2] + 0.2f);
  EXPECT_GT(std::get<std::int64_t>(*step(r, "colour").find("desaturated_highlight_pixels")), 32 * 32 - 1);
}

TEST(PostProcess, ANegativeGlareThresholdIsWhatWillClip) {
  // 64x64 black with a 4x4 lamp at 20x the white clip's luminance and a facade patch at half of it.
  solo::PostProcessOptions options = noiseless();
  options.glare = true;
  options.glare_options.size = 5;
  options.encoding_options.white_clip = 8;
  const double clip_y = 8 / kReferenceScale;  // what the encoding's white clip stands for before exposure
  cv::Mat xyz(64, 64, CV_32FC3, cv::Scalar::all(0));
  xyz(cv::Rect(30, 30, 4, 4)).setTo(cv::Scalar::all(20 * clip_y));
  xyz(cv::Rect(4, 4, 8, 8)).setTo(cv::Scalar::all(0.5 * clip_y));

  options.glare_options.threshold = -1;
  const solo::PostProcessResult what_clips = solo::postProcess(xyz, options);
  options.glare_options.threshold = clip_y;
  const solo::PostProcessResult explicit_clip = solo::postProcess(xyz, options);
  EXPECT_EQ(cv::norm(what_clips.encoded, explicit_clip.encoded, cv::NORM_INF), 0) << "-1 is the white clip's level";
  // The lamp glows onto its black surroundings; the facade below the clip does not glow at all.
  EXPECT_GT(what_clips.linear_rgb.at<cv::Vec3f>(31, 37)[1], 0.f);
  EXPECT_EQ(what_clips.linear_rgb.at<cv::Vec3f>(13, 13)[1], 0.f) << "next to the facade, which is below the clip";

  options.glare_options.threshold = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(solo::postProcess(xyz, options), solo::InputError);
}
