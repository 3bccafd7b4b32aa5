// measureGrayCard on synthetic DNG files whose answer is known by construction: a flat gray card
// lit by a chosen illuminant, its camera RGB made from that illuminant's XYZ with the file's own
// colour matrix (DNG ColorMatrix1 maps XYZ to camera RGB), so decoding must give the
// illuminant's chromaticity back.

#include <solo/core/error.h>
#include <solo/lighting/colorimetry.h>
#include <solo/lighting/raw_gray_card.h>

#include <Eigen/LU>

#include <algorithm>

#include "synthetic_dng.h"
#include "test_support.h"

using solo::test::SyntheticDng;
using solo::test::TempDir;

namespace {

const Eigen::Vector2d kIlluminantA{0.4476, 0.4074};
const Eigen::Vector2d kD65{0.3127, 0.3290};
constexpr int kSize = 64;
constexpr std::uint16_t kWhiteLevel = 4095;  // a 12-bit sensor

// A made-up but camera-like XYZ -> camera matrix: rows R, G, B; green most sensitive, blue least.
Eigen::Matrix3d cameraMatrix() {
  Eigen::Matrix3d m;
  m << 0.70, -0.10, -0.10,  //
      -0.40, 1.20, 0.20,    //
      -0.05, 0.20, 0.60;
  return m;
}

Eigen::Vector3d xyzOf(const Eigen::Vector2d& xy) { return {xy.x() / xy.y(), 1.0, (1 - xy.x() - xy.y()) / xy.y()}; }

// Raw camera values above black of a card lit by light of chromaticity xy, the largest channel at
// `peak` (raw units).
Eigen::Vector3d cameraValues(const Eigen::Vector2d& xy, double peak) {
  const Eigen::Vector3d camera = cameraMatrix() * xyzOf(xy);
  return camera * (peak / camera.maxCoeff());
}

SyntheticDng flatCard(const Eigen::Vector3d& camera_above_black, std::uint16_t black_level,
                      SyntheticDng::Layout layout = SyntheticDng::Layout::kLinearRaw) {
  SyntheticDng dng;
  dng.layout = layout;
  dng.color_matrix = cameraMatrix();
  dng.black_level = black_level;
  dng.white_level = kWhiteLevel;
  const Eigen::Vector3d raw = camera_above_black.array().round() + black_level;
  dng.camera_raw = cv::Mat(kSize, kSize, CV_16UC3, cv::Scalar(raw.x(), raw.y(), raw.z()));
  return dng;
}

// What the decoder should report: XYZ = ColorMatrix^-1 * (raw - black), up to a common scale.
Eigen::Vector2d expectedXy(const Eigen::Vector3d& camera_above_black) {
  return solo::chromaticity(cameraMatrix().inverse() * camera_above_black.array().round().matrix());
}

double distance(const Eigen::Vector2d& a, const Eigen::Vector2d& b) { return (a - b).norm(); }

}  // namespace

TEST(RawGrayCard, LinearRawCardUnderIlluminantAGivesItsChromaticity) {
  TempDir dir;
  const Eigen::Vector3d camera = cameraValues(kIlluminantA, 2000);
  solo::test::writeSyntheticDng(dir / "card.dng", flatCard(camera, 0));
  const solo::GrayCardMeasurement m = solo::measureGrayCard(dir / "card.dng", cv::Rect(16, 8, 32, 24));
  EXPECT_NEAR(m.xy.x(), kIlluminantA.x(), 1e-3);
  EXPECT_NEAR(m.xy.y(), kIlluminantA.y(), 1e-3);
  EXPECT_LT(distance(m.xy, expectedXy(camera)), 2e-4);
  // The whole tristimulus vector, not only its chromaticity: X/Y and Z/Y of illuminant A.
  const Eigen::Vector3d relative = m.xyz / m.xyz.y();
  EXPECT_NEAR(relative.x(), xyzOf(kIlluminantA).x(), 2e-3);
  EXPECT_NEAR(relative.z(), xyzOf(kIlluminantA).z(), 2e-3);
  EXPECT_EQ(m.pixels, 32 * 24);
  EXPECT_EQ(m.clipped, 0);
  EXPECT_EQ(m.camera, "Solo Synthetic gray card");
  // Camera RGB itself is far from neutral: reading it as XYZ would miss by far.
  EXPECT_GT(distance(solo::chromaticity(camera), kIlluminantA), 0.05);
}

TEST(RawGrayCard, NoWhiteBalanceIsAppliedFromAsShotNeutral) {
  // AsShotNeutral says "daylight"; a camera white balance would pull a D65 card to neutral
  // camera RGB and an A card elsewhere. The measurement must follow only the matrix.
  TempDir dir;
  for (const Eigen::Vector2d& xy : {kD65, kIlluminantA}) {
    const Eigen::Vector3d camera = cameraValues(xy, 1800);
    SyntheticDng dng = flatCard(camera, 0);
    dng.as_shot_neutral = cameraValues(kIlluminantA, 1.0);  // the camera believed it was under A
    solo::test::writeSyntheticDng(dir / "card.dng", dng);
    const solo::GrayCardMeasurement m = solo::measureGrayCard(dir / "card.dng", cv::Rect(0, 0, kSize, kSize));
    EXPECT_NEAR(m.xy.x(), xy.x(), 1e-3);
    EXPECT_NEAR(m.xy.y(), xy.y(), 1e-3);
  }
}

TEST(RawGrayCard, BayerFlatFieldDemosaicsToTheSameChromaticity) {
  TempDir dir;
  const Eigen::Vector3d camera = cameraValues(kIlluminantA, 2000);
  solo::test::writeSyntheticDng(dir / "card.dng", flatCard(camera, 0, SyntheticDng::Layout::kBayerRggb));
  const solo::GrayCardMeasurement m = solo::measureGrayCard(dir / "card.dng", cv::Rect(8, 8, 48, 48));
  EXPECT_NEAR(m.xy.x(), kIlluminantA.x(), 1e-3);
  EXPECT_NEAR(m.xy.y(), kIlluminantA.y(), 1e-3);
  EXPECT_EQ(m.clipped, 0);
}

TEST(RawGrayCard, BlackLevelIsSubtracted) {
  TempDir dir;
  const Eigen::Vector3d camera = cameraValues(kIlluminantA, 2000);
  constexpr std::uint16_t kBlack = 512;
  // Left in, the black level would move the answer far outside the tolerance.
  ASSERT_GT(distance(expectedXy(camera + Eigen::Vector3d::Constant(kBlack)), kIlluminantA), 0.02);
  for (const auto layout : {SyntheticDng::Layout::kLinearRaw, SyntheticDng::Layout::kBayerRggb}) {
    solo::test::writeSyntheticDng(dir / "card.dng", flatCard(camera, kBlack, layout));
    const solo::GrayCardMeasurement m = solo::measureGrayCard(dir / "card.dng", cv::Rect(8, 8, 48, 48));
    EXPECT_NEAR(m.xy.x(), kIlluminantA.x(), 1e-3) << "Bayer: " << (layout == SyntheticDng::Layout::kBayerRggb);
    EXPECT_NEAR(m.xy.y(), kIlluminantA.y(), 1e-3) << "Bayer: " << (layout == SyntheticDng::Layout::kBayerRggb);
    EXPECT_EQ(m.clipped, 0);
  }
}

TEST(RawGrayCard, BrightUnsaturatedCardKeepsItsColour) {
  // LibRaw multiplies each camera channel by its daylight gain 1 / (ColorMatrix * XYZ_D65)_c.
  // Here red's gain is about 2.3 times green's: a red value at 60 % of the range is far from
  // the white level but would exceed it after the gain if the gains were normalised to the
  // smallest one (LibRaw's default highlight mode), and the card would turn green.
  const Eigen::Vector3d white_d65 = cameraMatrix() * xyzOf(kD65);
  const double red_gain_over_smallest = white_d65.maxCoeff() / white_d65.x();
  ASSERT_GT(red_gain_over_smallest * 0.6, 1.2);
  TempDir dir;
  const Eigen::Vector3d camera = cameraValues(kIlluminantA, 1.0) * (0.6 * kWhiteLevel / cameraValues(kIlluminantA, 1.0).x());
  ASSERT_LT(camera.maxCoeff(), 0.95 * kWhiteLevel);
  solo::test::writeSyntheticDng(dir / "card.dng", flatCard(camera, 0));
  const solo::GrayCardMeasurement m = solo::measureGrayCard(dir / "card.dng", cv::Rect(0, 0, kSize, kSize));
  EXPECT_NEAR(m.xy.x(), kIlluminantA.x(), 1e-3);
  EXPECT_NEAR(m.xy.y(), kIlluminantA.y(), 1e-3);
  EXPECT_EQ(m.clipped, 0);
}

TEST(RawGrayCard, SaturatedPixelsAreCounted) {
  // The left 24 columns have their green channel at the white level.
  TempDir dir;
  const Eigen::Vector3d camera = cameraValues(kIlluminantA, 1500);
  const auto saturateLeft = [](SyntheticDng dng) {
    dng.camera_raw(cv::Rect(0, 0, 24, kSize)).forEach<cv::Vec3w>([](cv::Vec3w& v, const int*) { v[1] = kWhiteLevel; });
    return dng;
  };
  solo::test::writeSyntheticDng(dir / "linear.dng", saturateLeft(flatCard(camera, 0)));
  const solo::GrayCardMeasurement across = solo::measureGrayCard(dir / "linear.dng", cv::Rect(14, 20, 20, 10));
  EXPECT_EQ(across.pixels, 200);
  EXPECT_EQ(across.clipped, 100);
  const solo::GrayCardMeasurement right = solo::measureGrayCard(dir / "linear.dng", cv::Rect(30, 0, 34, kSize));
  EXPECT_EQ(right.clipped, 0);
  EXPECT_NEAR(right.xy.x(), kIlluminantA.x(), 1e-3);
  EXPECT_NEAR(right.xy.y(), kIlluminantA.y(), 1e-3);
  // A Bayer file with a black level (the usual camera raw); demosaicing smears the edge, so the
  // regions keep 4 pixels away from it.
  solo::test::writeSyntheticDng(dir / "bayer.dng",
                                saturateLeft(flatCard(camera, 256, SyntheticDng::Layout::kBayerRggb)));
  EXPECT_EQ(solo::measureGrayCard(dir / "bayer.dng", cv::Rect(2, 2, 18, 40)).clipped, 18 * 40);
  EXPECT_EQ(solo::measureGrayCard(dir / "bayer.dng", cv::Rect(28, 2, 30, 40)).clipped, 0);
}

TEST(RawGrayCard, BadRegionsAndFilesAreErrorsNamingTheFile) {
  TempDir dir;
  solo::test::writeSyntheticDng(dir / "card.dng", flatCard(cameraValues(kD65, 1000), 0));
  const auto message = [&](const std::filesystem::path& file, const cv::Rect& region) -> std::string {
    try {
      solo::measureGrayCard(file, region);
    } catch (const solo::InputError& e) {
      EXPECT_EQ(e.file(), file);
      return e.what();
    }
    return "no error";
  };
  EXPECT_NE(message(dir / "card.dng", cv::Rect(60, 10, 10, 10)).find("card.dng: region 60,10 10x10 is empty or outside the 64x64 image"),
            std::string::npos)
      << message(dir / "card.dng", cv::Rect(60, 10, 10, 10));
  EXPECT_NE(message(dir / "card.dng", cv::Rect(-1, 0, 8, 8)).find("outside the 64x64 image"), std::string::npos);
  EXPECT_NE(message(dir / "card.dng", cv::Rect(0, 0, 0, 8)).find("is empty"), std::string::npos);
  EXPECT_NE(message(dir / "missing.dng", cv::Rect(0, 0, 8, 8)).find("missing.dng: file not found"), std::string::npos);
  solo::test::writeText(dir / "notes.dng", "not a raw photo\n");
  EXPECT_NE(message(dir / "notes.dng", cv::Rect(0, 0, 8, 8)).find("notes.dng: "), std::string::npos);
  solo::test::writeSyntheticDng(dir / "dark.dng", flatCard(Eigen::Vector3d::Zero(), 64));
  EXPECT_NE(message(dir / "dark.dng", cv::Rect(0, 0, 8, 8)).find("dark.dng: the region is black"), std::string::npos)
      << message(dir / "dark.dng", cv::Rect(0, 0, 8, 8));
}
