#include <solo/render/chromatic_adaptation.h>
#include <solo/render/colour_encoding.h>

#include "test_support.h"

#include <cmath>

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
