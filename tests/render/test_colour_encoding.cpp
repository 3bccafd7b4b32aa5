#include <solo/post/chromatic_adaptation.h>
#include <solo/post/colour_encoding.h>

#include "test_support.h"

#include <cmath>
#include <vector>

namespace {

cv::Mat onePixel(const cv::Vec3d& xyz) {
  return cv::Mat(1, 1, CV_32FC3, cv::Scalar(xyz[0], xyz[1], xyz[2]));
}

/// XYZ (D65) of a linear sRGB colour.
cv::Vec3d xyzOfLinearSrgb(const cv::Vec3d& rgb) { return solo::xyzToLinearSrgbMatrix().inv() * rgb; }

double luminance(const cv::Vec3f& rgb) {
  const cv::Vec3d w = solo::linearSrgbLuminanceWeights();
  return w[0] * rgb[0] + w[1] * rgb[1] + w[2] * rgb[2];
}

/// CIELAB (D65 white) lightness, chroma and hue angle in degrees [0, 360) of XYZ relative to D65.
struct Lch {
  double lightness, chroma, hue_deg;
};
Lch cielab(const cv::Vec3d& xyz) {
  auto f = [](double t) { return t > 216.0 / 24389.0 ? std::cbrt(t) : (24389.0 / 27.0 * t + 16.0) / 116.0; };
  const double fx = f(xyz[0] / solo::kWhitePointD65[0]), fy = f(xyz[1]), fz = f(xyz[2] / solo::kWhitePointD65[2]);
  const double a = 500 * (fx - fy), b = 200 * (fy - fz);
  const double hue = std::atan2(b, a) * 180 / CV_PI;
  return {116 * fy - 16, std::hypot(a, b), hue < 0 ? hue + 360 : hue};
}

double hueDifferenceDeg(double a, double b) { return std::abs(std::remainder(a - b, 360.0)); }

/// Lab of an encoded (gamma 2.2) sRGB colour.
Lch cielabOfEncoded(const cv::Vec3f& encoded) {
  cv::Vec3d linear;
  for (int c = 0; c < 3; ++c) linear[c] = solo::decodeTransfer(encoded[c], solo::TransferCurve::Gamma22);
  return cielab(xyzOfLinearSrgb(linear));
}

/// HSV saturation (max - min) / max of an encoded colour.
double hsvSaturation(const cv::Vec3f& c) {
  const double hi = std::max({c[0], c[1], c[2]}), lo = std::min({c[0], c[1], c[2]});
  return hi > 0 ? (hi - lo) / hi : 0;
}

cv::Vec3d xyzOfChromaticity(double x, double y) { return {x / y, 1.0, (1 - x - y) / y}; }

struct Lamp {
  const char* name;
  cv::Vec3d xyz;  ///< XYZ relative to D65, any scale
};

/// Signal colours from data/illuminants/signal_light_chromaticity_regions.csv (a point inside
/// each region) and the sRGB blue primary: all but the blue lie outside the sRGB gamut.
std::vector<Lamp> saturatedLamps() {
  return {{"red (SAE J578 tail/stop)", xyzOfChromaticity(0.700, 0.290)},
          {"amber (SAE J578 turn)", xyzOfChromaticity(0.575, 0.415)},
          {"green (ITE traffic green)", xyzOfChromaticity(0.100, 0.550)},
          {"blue (sRGB primary)", xyzOfChromaticity(0.150, 0.060)}};
}

/// The lamp's XYZ scaled so that its largest linear sRGB channel after gamut handling is 1:
/// intensity 1 is where the lamp starts to exceed the encodable range.
cv::Vec3d lampAtClipLevel(const Lamp& lamp) {
  const solo::ColourEncodingResult r = solo::encodeXyzToSrgb(onePixel(lamp.xyz), {});
  const cv::Vec3f rgb = r.linear_rgb.at<cv::Vec3f>(0, 0);
  return lamp.xyz / static_cast<double>(std::max({rgb[0], rgb[1], rgb[2]}));
}

}  // namespace

TEST(ColourEncoding, MatrixMatchesThePublishedSrgbMatrix) {
  // Lindbloom's XYZ (D65) -> linear sRGB matrix, 7 decimals.
  const cv::Matx33d published{3.2404542, -1.5371385, -0.4985314,  //
                              -0.9692660, 1.8760108, 0.0415560,   //
                              0.0556434, -0.2040259, 1.0572252};
  const cv::Matx33d m = solo::xyzToLinearSrgbMatrix();
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(m(r, c), published(r, c), 1e-6) << "entry " << r << c;
  const cv::Vec3d w = solo::linearSrgbLuminanceWeights();
  EXPECT_NEAR(w[0], 0.2126729, 1e-6);
  EXPECT_NEAR(w[1], 0.7151522, 1e-6);
  EXPECT_NEAR(w[2], 0.0721750, 1e-6);
}

TEST(ColourEncoding, D65WhiteIsSrgbWhite) {
  for (const solo::TransferCurve curve :
       {solo::TransferCurve::Gamma22, solo::TransferCurve::Srgb, solo::TransferCurve::Linear}) {
    solo::ColourEncodingOptions options;
    options.curve = curve;
    const solo::ColourEncodingResult r = solo::encodeXyzToSrgb(onePixel(solo::kWhitePointD65), options);
    for (int c = 0; c < 3; ++c) {
      EXPECT_NEAR(r.linear_rgb.at<cv::Vec3f>(0, 0)[c], 1.0, 1e-6);
      EXPECT_NEAR(r.encoded.at<cv::Vec3f>(0, 0)[c], 1.0, 1e-6);
    }
  }
}

TEST(ColourEncoding, TransferCurvesMatchTheirDefinitions) {
  using solo::TransferCurve;
  EXPECT_NEAR(solo::encodeTransfer(0.18f, TransferCurve::Gamma22), std::pow(0.18, 1 / 2.2), 1e-6);
  EXPECT_NEAR(solo::encodeTransfer(0.5f, TransferCurve::Srgb), 1.055 * std::pow(0.5, 1 / 2.4) - 0.055, 1e-6);
  EXPECT_NEAR(solo::encodeTransfer(0.002f, TransferCurve::Srgb), 12.92 * 0.002, 1e-7);
  // The two pieces of the sRGB curve meet at 0.0031308 -> 0.04045.
  EXPECT_NEAR(solo::encodeTransfer(0.0031308f, TransferCurve::Srgb), 0.04045, 1e-5);
  EXPECT_EQ(solo::encodeTransfer(-0.5f, TransferCurve::Gamma22), 0.f);
  EXPECT_EQ(solo::encodeTransfer(7.f, TransferCurve::Srgb), 1.f);
  for (const float v : {0.0f, 0.001f, 0.05f, 0.18f, 0.7f, 1.0f})
    for (const TransferCurve c : {TransferCurve::Gamma22, TransferCurve::Srgb, TransferCurve::Linear})
      EXPECT_NEAR(solo::decodeTransfer(solo::encodeTransfer(v, c), c), v, 2e-6);
  // The whole image path (vectorised power) agrees with the scalar one.
  const solo::ColourEncodingResult grey =
      solo::encodeXyzToSrgb(onePixel(solo::kWhitePointD65 * 0.18), solo::ColourEncodingOptions{});
  EXPECT_NEAR(grey.encoded.at<cv::Vec3f>(0, 0)[1], std::pow(0.18, 1 / 2.2), 1e-5);
}

TEST(ColourEncoding, DesaturatingKeepsLuminanceAndHueLine) {
  const cv::Vec3d rgb{-0.2, 0.5, 0.3};  // outside the gamut: red is negative
  const solo::ColourEncodingResult r = solo::encodeXyzToSrgb(onePixel(xyzOfLinearSrgb(rgb)), {});
  const cv::Vec3f out = r.linear_rgb.at<cv::Vec3f>(0, 0);
  const double y = 0.2126729 * rgb[0] + 0.7151522 * rgb[1] + 0.0721750 * rgb[2];
  EXPECT_NEAR(out[0], 0.0, 1e-6);
  EXPECT_NEAR(luminance(out), y, 1e-6);
  // On the line from grey (y, y, y) through the original colour: one common factor t.
  const double t = y / (y - rgb[0]);
  EXPECT_NEAR(out[1], y + t * (rgb[1] - y), 1e-6);
  EXPECT_NEAR(out[2], y + t * (rgb[2] - y), 1e-6);
  EXPECT_EQ(std::get<std::int64_t>(*r.report.find("out_of_gamut_pixels")), 1);
}

TEST(ColourEncoding, ClippingSetsOnlyTheNegativeChannelToZero) {
  solo::ColourEncodingOptions options;
  options.negatives = solo::NegativeHandling::Clip;
  const solo::ColourEncodingResult r = solo::encodeXyzToSrgb(onePixel(xyzOfLinearSrgb({-0.2, 0.5, 0.3})), options);
  const cv::Vec3f out = r.linear_rgb.at<cv::Vec3f>(0, 0);
  EXPECT_EQ(out[0], 0.f);
  EXPECT_NEAR(out[1], 0.5, 1e-6);
  EXPECT_NEAR(out[2], 0.3, 1e-6);
}

TEST(ColourEncoding, NegativeLuminanceBecomesBlackAndOverRangeIsCountedAndClipped) {
  cv::Mat xyz(1, 2, CV_32FC3);
  const cv::Vec3d negative = xyzOfLinearSrgb({-0.5, 0.1, -0.2});
  const cv::Vec3d bright = solo::kWhitePointD65 * 4.0;
  xyz.at<cv::Vec3f>(0, 0) = cv::Vec3f(negative);
  xyz.at<cv::Vec3f>(0, 1) = cv::Vec3f(bright);
  const solo::ColourEncodingResult r = solo::encodeXyzToSrgb(xyz, {});
  EXPECT_EQ(r.linear_rgb.at<cv::Vec3f>(0, 0), cv::Vec3f(0, 0, 0));
  EXPECT_EQ(std::get<std::int64_t>(*r.report.find("negative_luminance_pixels")), 1);
  EXPECT_NEAR(r.linear_rgb.at<cv::Vec3f>(0, 1)[1], 4.0, 1e-5);  // linear output keeps the highlight
  EXPECT_EQ(r.encoded.at<cv::Vec3f>(0, 1), cv::Vec3f(1, 1, 1));
  EXPECT_EQ(std::get<std::int64_t>(*r.report.find("over_range_pixels")), 1);
}

TEST(ColourEncoding, QuantisationRoundsToTheNearestCode) {
  cv::Mat encoded(1, 1, CV_32FC3, cv::Scalar(0.0, 0.2, 1.0));
  const cv::Mat eight = solo::quantiseEncoded(encoded, 8);
  EXPECT_EQ(eight.type(), CV_8UC3);
  EXPECT_EQ(eight.at<cv::Vec3b>(0, 0), cv::Vec3b(0, 51, 255));
  const cv::Mat sixteen = solo::quantiseEncoded(encoded, 16);
  EXPECT_EQ(sixteen.type(), CV_16UC3);
  EXPECT_EQ(sixteen.at<cv::Vec3w>(0, 0), cv::Vec3w(0, 13107, 65535));
  EXPECT_THROW(solo::quantiseEncoded(encoded, 10), std::invalid_argument);
}

TEST(ColourEncodingHighlights, SaturatedLampsKeepTheirHueAndTurnWhiteMonotonically) {
  // Intensities from 0.5x to 1000x the level where the lamp's largest channel reaches 1, in
  // steps of 2 %. Hue: CIELAB (D65) hue angle of the encoded output, against the hue of the
  // lamp's own XYZ.
  for (const Lamp& lamp : saturatedLamps()) {
    const cv::Vec3d unit = lampAtClipLevel(lamp);
    const double lamp_hue = cielab(lamp.xyz).hue_deg;
    double previous_saturation = 2, worst_hue_error = 0;
    int coloured = 0;
    for (double k = 0.5; k <= 1000; k *= 1.02) {
      const cv::Vec3f out = solo::encodeXyzToSrgb(onePixel(unit * k), {}).encoded.at<cv::Vec3f>(0, 0);
      const double saturation = hsvSaturation(out);
      // 1e-3: float rounding leaves ~1e-9 in a zero channel, which the curve lifts to ~1e-4.
      EXPECT_LE(saturation, previous_saturation + 1e-3) << lamp.name << " at " << k;
      previous_saturation = saturation;
      if (std::min({out[0], out[1], out[2]}) >= 1.f) continue;  // white: no hue
      ++coloured;
      worst_hue_error = std::max(worst_hue_error, hueDifferenceDeg(cielabOfEncoded(out).hue_deg, lamp_hue));
    }
    EXPECT_LE(worst_hue_error, 30.0) << lamp.name;
    EXPECT_GT(coloured, 20) << lamp.name;
    // Saturated at half the clip level, white well before 1000x.
    const cv::Vec3f dim = solo::encodeXyzToSrgb(onePixel(unit * 0.5), {}).encoded.at<cv::Vec3f>(0, 0);
    EXPECT_GT(hsvSaturation(dim), 0.6) << lamp.name;
    const cv::Vec3f burnt = solo::encodeXyzToSrgb(onePixel(unit * 1000), {}).encoded.at<cv::Vec3f>(0, 0);
    EXPECT_EQ(burnt, cv::Vec3f(1, 1, 1)) << lamp.name;
  }
}

TEST(ColourEncodingHighlights, ClippingPerChannelRotatesTheRedLampsHue) {
  // The Clip option, kept for comparison: the red lamp's gamut-mapped colour carries a little
  // more blue than green, so clipping red alone leaves a magenta core (CIELAB hue past 0 deg).
  const Lamp red = saturatedLamps()[0];
  const cv::Vec3d unit = lampAtClipLevel(red);
  solo::ColourEncodingOptions clip;
  clip.highlights = solo::HighlightHandling::Clip;
  const cv::Vec3f clipped = solo::encodeXyzToSrgb(onePixel(unit * 8), clip).encoded.at<cv::Vec3f>(0, 0);
  EXPECT_EQ(clipped[0], 1.f);
  EXPECT_GT(clipped[2], clipped[1]);
  EXPECT_GT(hueDifferenceDeg(cielabOfEncoded(clipped).hue_deg, cielab(red.xyz).hue_deg), 30.0);
  const solo::ColourEncodingResult kept = solo::encodeXyzToSrgb(onePixel(unit * 3), {});  // white from 4.6x
  EXPECT_LE(hueDifferenceDeg(cielabOfEncoded(kept.encoded.at<cv::Vec3f>(0, 0)).hue_deg, cielab(red.xyz).hue_deg),
            30.0);
  EXPECT_EQ(std::get<std::int64_t>(*kept.report.find("desaturated_highlight_pixels")), 1);
}

TEST(ColourEncodingHighlights, DesaturationKeepsLuminanceAndTheHueLine) {
  // c = (1.6, 0.4, 0.1): Y = 0.2126729 * 1.6 + 0.7151522 * 0.4 + 0.0721750 * 0.1 = 0.63356,
  // u = (1.6 - Y) / (1 - Y) = 2.6374; with knee 0.8, s(u) = 0.8 + 0.2 (1 - exp(-9.187)) =
  // 0.99998 and t = s(u) / u = 0.37916.
  const cv::Vec3f c{1.6f, 0.4f, 0.1f};
  const double y = 0.2126729 * 1.6 + 0.7151522 * 0.4 + 0.0721750 * 0.1;
  const double u = (1.6 - y) / (1 - y);
  const double t = (0.8 + 0.2 * (1 - std::exp(-(u - 0.8) / 0.2))) / u;
  EXPECT_NEAR(t, 0.37916, 1e-5);
  const cv::Vec3f out = solo::desaturateHighlight(c, 0.8);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(out[k], y + t * (c[k] - y), 1e-6) << k;
  EXPECT_NEAR(luminance(out), y, 1e-6);
  EXPECT_LT(out[0], 1.f);
  // HSV hue: (mid - min) / (max - min) is unchanged.
  EXPECT_NEAR((out[1] - out[2]) / (out[0] - out[2]), (0.4 - 0.1) / (1.6 - 0.1), 1e-6);
  // The hard shoulder puts the largest channel exactly at 1.
  const cv::Vec3f hard = solo::desaturateHighlight(c, 1.0);
  EXPECT_NEAR(hard[0], 1.0, 1e-6);
  EXPECT_NEAR(luminance(hard), y, 1e-6);
  // Luminance at or above 1: white.
  EXPECT_EQ(solo::desaturateHighlight({3.f, 0.8f, 0.5f}, 0.8), cv::Vec3f(1, 1, 1));
  EXPECT_THROW(solo::desaturateHighlight(c, 1.5), std::invalid_argument);
  solo::ColourEncodingOptions bad;
  bad.highlight_knee = -0.1;
  EXPECT_THROW(solo::encodeXyzToSrgb(onePixel({0.5, 0.5, 0.5}), bad), std::invalid_argument);
}

TEST(ColourEncodingHighlights, ColoursInsideTheRangeStayUnchanged) {
  // A grid of linear sRGB colours in [0, 1]^3: the hard shoulder (knee 1) leaves every one
  // exactly as it is; the default knee 0.8 every one whose largest channel uses at most 80 % of
  // its headroom, max <= Y + 0.8 (1 - Y).
  const float steps[] = {0.f, 0.01f, 0.2f, 0.5f, 0.8f, 0.95f, 1.f};
  int below_knee = 0;
  for (float r : steps)
    for (float g : steps)
      for (float b : steps) {
        const cv::Vec3f c{r, g, b};
        EXPECT_EQ(solo::desaturateHighlight(c, 1.0), c);
        const double y = luminance(c);
        if (std::max({r, g, b}) > y + 0.8 * (1 - y)) continue;
        ++below_knee;
        EXPECT_EQ(solo::desaturateHighlight(c, 0.8), c);
      }
  EXPECT_EQ(below_knee, 155);  // of the 343 grid colours
  // Through the whole encoding: an in-range colour comes out as with per-channel clipping.
  solo::ColourEncodingOptions clip;
  clip.highlights = solo::HighlightHandling::Clip;
  const cv::Mat pixel = onePixel(xyzOfLinearSrgb({0.8, 0.3, 0.05}));
  const solo::ColourEncodingResult soft = solo::encodeXyzToSrgb(pixel, {});
  EXPECT_EQ(soft.encoded.at<cv::Vec3f>(0, 0), solo::encodeXyzToSrgb(pixel, clip).encoded.at<cv::Vec3f>(0, 0));
  EXPECT_EQ(std::get<std::int64_t>(*soft.report.find("desaturated_highlight_pixels")), 0);
}

TEST(ColourEncodingHighlights, TheShoulderEasesInWithoutAKink) {
  // Along a ray of growing intensity the desaturation 1 - t starts from 0 with zero slope at
  // the knee (quadratically: 1 - t = d^2 / (2 (1 - knee) (knee + d)) + O(d^3), d = u - knee),
  // while the hard shoulder starts with a finite slope.
  auto desaturation = [](double u, double knee) {
    // A colour (a, 0, 0) with headroom share u: u = (a - Y) / (1 - Y), Y = 0.2126729 a.
    const double w = 0.2126729, a = u / (1 - w + u * w);
    const cv::Vec3f out = solo::desaturateHighlight({static_cast<float>(a), 0.f, 0.f}, knee);
    const double y = w * a;
    return 1 - (out[0] - y) / (a - y);
  };
  const double d = 0.01;
  EXPECT_NEAR(desaturation(0.8 + d, 0.8) / desaturation(0.8 + 2 * d, 0.8), 0.25 * (0.8 + 2 * d) / (0.8 + d), 0.01);
  EXPECT_NEAR(desaturation(0.8 + d, 0.8), d * d / (2 * 0.2 * (0.8 + d)), 2e-5);
  EXPECT_NEAR(desaturation(1 + d, 1.0), d / (1 + d), 1e-5);
}

TEST(ColourEncodingKnee, VideoKneeCompressesAboveTheKneePointAndReachesWhiteAtTheClip) {
  // Knee point 0.7 (encoded), white clip 8: slope = 0.3 / (8^(1/2.2) - 0.7).
  const double slope = 0.3 / (std::pow(8.0, 1 / 2.2) - 0.7);
  const double below = std::pow(0.6, 2.2);  // encodes to 0.6 < 0.7: unchanged
  EXPECT_DOUBLE_EQ(solo::luminanceRolloff(below, 8, 0.7), below);
  // Linear 1 encodes to 1 and becomes 0.7 + 0.3 slope.
  EXPECT_NEAR(solo::luminanceRolloff(1.0, 8, 0.7), std::pow(0.7 + 0.3 * slope, 2.2), 1e-12);
  EXPECT_NEAR(solo::luminanceRolloff(8.0, 8, 0.7), 1.0, 1e-12);
  EXPECT_DOUBLE_EQ(solo::luminanceRolloff(1e6, 8, 0.7), 1.0);
  // Monotone and continuous at the knee.
  const double at_knee = std::pow(0.7, 2.2);
  EXPECT_NEAR(solo::luminanceRolloff(at_knee * (1 + 1e-9), 8, 0.7), at_knee, 1e-9);
  double previous = 0;
  for (double y = 0; y < 10; y += 0.01) {
    const double v = solo::luminanceRolloff(y, 8, 0.7);
    EXPECT_GE(v, previous);
    previous = v;
  }
  // White clip 1: the identity (the encoding then clips at 1).
  EXPECT_DOUBLE_EQ(solo::luminanceRolloff(3.0, 1, 0.7), 3.0);
  EXPECT_THROW(solo::luminanceRolloff(1.0, 0.5, 0.7), std::invalid_argument);
  EXPECT_THROW(solo::luminanceRolloff(1.0, 8, 1.0), std::invalid_argument);
}

TEST(ColourEncodingKnee, AWindowTwiceAsBrightAsWhiteStaysBelowFullWhiteWithItsChromaticity) {
  // A warm window at twice sensor white: with the knee it encodes below 1 in every channel and
  // keeps its chromaticity (the ratio of its channels); without it, it clips to white.
  const cv::Vec3d rgb(2.0, 1.6, 1.0);
  solo::ColourEncodingOptions knee;
  knee.white_clip = 8;
  knee.knee_point = 0.7;
  knee.highlight_knee = 1;  // isolate the luminance knee from the chroma shoulder
  const cv::Vec3f kneed = solo::encodeXyzToSrgb(onePixel(xyzOfLinearSrgb(rgb)), knee).encoded.at<cv::Vec3f>(0, 0);
  for (int k = 0; k < 3; ++k) EXPECT_LT(kneed[k], 1.f);
  const auto linear = [](float e) { return std::pow(e, 2.2); };
  EXPECT_NEAR(linear(kneed[1]) / linear(kneed[0]), 0.8, 2e-3);
  EXPECT_NEAR(linear(kneed[2]) / linear(kneed[0]), 0.5, 2e-3);
  const cv::Vec3f clipped = solo::encodeXyzToSrgb(onePixel(xyzOfLinearSrgb(rgb)), {}).encoded.at<cv::Vec3f>(0, 0);
  EXPECT_EQ(clipped, cv::Vec3f(1.f, 1.f, 1.f));
}
