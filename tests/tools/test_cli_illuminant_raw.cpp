// `solo illuminant add --raw` end to end on a synthetic DNG of a gray card under illuminant A.

#include <solo/lighting/illuminant_table.h>

#include "synthetic_dng.h"
#include "test_support.h"

using solo::test::runSolo;
using solo::test::TempDir;

namespace {

std::string quoted(const std::filesystem::path& p) { return "\"" + p.string() + "\""; }

// Camera RGB above black of a card lit by CIE A (xy 0.4476, 0.4074) through `matrix`
// (XYZ -> camera), scaled so the largest channel is `peak` raw units.
cv::Scalar cameraUnderA(const Eigen::Matrix3d& matrix, double peak, double black) {
  const Eigen::Vector3d xyz(0.4476 / 0.4074, 1.0, (1 - 0.4476 - 0.4074) / 0.4074);
  Eigen::Vector3d camera = matrix * xyz;
  camera *= peak / camera.maxCoeff();
  return {std::round(camera.x()) + black, std::round(camera.y()) + black, std::round(camera.z()) + black};
}

solo::test::SyntheticDng grayCard(bool saturated) {
  solo::test::SyntheticDng dng;
  dng.layout = solo::test::SyntheticDng::Layout::kBayerRggb;
  dng.color_matrix << 0.70, -0.10, -0.10, -0.40, 1.20, 0.20, -0.05, 0.20, 0.60;
  dng.black_level = 128;
  dng.white_level = 4095;
  dng.camera_raw = cv::Mat(64, 96, CV_16UC3, cameraUnderA(dng.color_matrix, saturated ? 4095 - 128 : 2500, 128));
  return dng;
}

}  // namespace

TEST(IlluminantRawCli, AddsTheGrayCardChromaticityToTheTable) {
  TempDir dir;
  solo::test::writeSyntheticDng(dir / "card.dng", grayCard(false));
  const std::filesystem::path table = dir / "my_city.csv";
  const auto r = runSolo("illuminant add " + quoted(table) + " --category street_light_HT --raw " +
                         quoted(dir / "card.dng") + " --roi 20,10,40,30 --source \"Rue X\"");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output.find("saturated"), std::string::npos) << r.output;
  const solo::IlluminantTable t = solo::readIlluminantTable(table);
  ASSERT_EQ(t.samples.size(), 1u);
  EXPECT_EQ(t.samples[0].category, solo::LightCategory::StreetLightHighCct);
  EXPECT_NEAR(t.samples[0].xy.x(), 0.4476, 1e-3);
  EXPECT_NEAR(t.samples[0].xy.y(), 0.4074, 1e-3);
  EXPECT_NE(t.samples[0].source.find("Rue X"), std::string::npos) << t.samples[0].source;
  EXPECT_NE(t.samples[0].source.find("card.dng: gray card, 1200 px at 20,10,40,30"), std::string::npos)
      << t.samples[0].source;
}

TEST(IlluminantRawCli, WarnsAboutASaturatedCardAndRejectsARegionOutsideTheImage) {
  TempDir dir;
  solo::test::writeSyntheticDng(dir / "card.dng", grayCard(true));
  const std::filesystem::path table = dir / "t.csv";
  auto r = runSolo("illuminant add " + quoted(table) + " --category street_light_HT --raw " + quoted(dir / "card.dng") +
                   " --roi 20,10,40,30");
  EXPECT_NE(r.output.find("1200 of 1200 pixels in the region are saturated"), std::string::npos) << r.output;
  r = runSolo("illuminant add " + quoted(dir / "u.csv") + " --category street_light_HT --raw " +
              quoted(dir / "card.dng") + " --roi 80,10,40,30");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("card.dng: region 80,10 40x30 is empty or outside the 96x64 image"), std::string::npos)
      << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "u.csv"));
}
