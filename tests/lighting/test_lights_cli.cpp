// `solo lights` and `solo illuminant` end to end on the embedded default scene.

#include <solo/core/image_io.h>
#include <solo/lighting/illuminant_table.h>

#include <nlohmann/json.hpp>

#include "test_support.h"

using solo::test::readText;
using solo::test::runSolo;
using solo::test::TempDir;

namespace {
std::string quoted(const std::filesystem::path& p) { return "\"" + p.string() + "\""; }
}  // namespace

TEST(LightsCli, DefaultSceneGivesAReproducibleRecordAndAnOverlay) {
  TempDir dir;
  auto r = runSolo("lights -o " + quoted(dir / "a.json") + " --overlay " + quoted(dir / "a.png") + " --seed 3");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  ASSERT_EQ(runSolo("lights -o " + quoted(dir / "b.json") + " --seed 3").exit_code, 0);
  ASSERT_EQ(runSolo("lights -o " + quoted(dir / "c.json") + " --seed 4").exit_code, 0);
  EXPECT_EQ(readText(dir / "a.json"), readText(dir / "b.json"));
  EXPECT_NE(readText(dir / "a.json"), readText(dir / "c.json"));
  const auto j = nlohmann::json::parse(readText(dir / "a.json"));
  EXPECT_EQ(j["format"], "solo-lights/1");
  EXPECT_EQ(j["image"]["width"], 960);
  int on = 0, street = 0;
  for (const auto& light : j["lights"]) {
    on += light["on"].get<bool>();
    if (light["category"] == "street_light_HT" || light["category"] == "street_light_LT") {
      ++street;
      EXPECT_TRUE(light["on"].get<bool>());
      EXPECT_EQ(light["strength_unit"], "lm");
      EXPECT_GT(light["area_m2"].get<double>(), 0.0);
    }
  }
  EXPECT_GT(street, 0);
  EXPECT_GT(on, 0);
  EXPECT_LT(on, static_cast<int>(j["lights"].size())) << "windows are on with probability 0.3-0.6";
  solo::ImageFileInfo info;
  solo::readImageRaw(dir / "a.png", &info);
  EXPECT_EQ(info.width, 960);
  EXPECT_EQ(info.channels, 3);
}

TEST(LightsCli, AblationAndAnEditedRecordFedBack) {
  TempDir dir;
  ASSERT_EQ(runSolo("lights --ablation -o " + quoted(dir / "abl.json")).exit_code, 0);
  auto j = nlohmann::json::parse(readText(dir / "abl.json"));
  EXPECT_EQ(j["mode"], "ablation");
  for (const auto& light : j["lights"]) {
    EXPECT_TRUE(light["on"].get<bool>());
    EXPECT_DOUBLE_EQ(light["x"].get<double>(), 1.0 / 3.0);
    EXPECT_EQ(light["strength"], 1000.0);
  }
  for (auto& light : j["lights"]) light["on"] = false;
  solo::test::writeText(dir / "edited.json", j.dump());
  const auto r = runSolo("lights --from " + quoted(dir / "edited.json") + " -o " + quoted(dir / "back.json") +
                         " --report " + quoted(dir / "report.json"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto report = nlohmann::json::parse(readText(dir / "report.json"));
  EXPECT_EQ(report["stages"][0]["metrics"]["lights_on"], 0);
  EXPECT_EQ(report["stages"][0]["metrics"]["lights"], j["lights"].size());
}

TEST(LightsCli, MalformedLightMapIsAnErrorNamingTheFile) {
  TempDir dir;
  solo::writeImage(dir / "day.png", cv::Mat(6, 8, CV_8UC3, cv::Scalar(100, 100, 100)));
  solo::writeImage(dir / "d.pfm", cv::Mat(6, 8, CV_32F, cv::Scalar(5)));
  cv::Mat lights(6, 8, CV_16U, cv::Scalar(0));
  lights.at<uint16_t>(2, 3) = 16001;
  solo::writeImage(dir / "lights.png", lights);
  solo::test::writeText(dir / "s.json", R"({"image": "day.png", "depth": "d.pfm", "lights": "lights.png"})");
  const auto r = runSolo("lights " + quoted(dir / "s.json") + " -o " + quoted(dir / "out.json"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("lights.png: light id 16001 at pixel (3, 2)"), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "out.json"));
}

TEST(IlluminantCli, AddsSamplesFromATemperatureAndASpectrum) {
  TempDir dir;
  const std::filesystem::path table = dir / "my_city.csv";
  auto r = runSolo("illuminant add " + quoted(table) + " --category street_light_LT --cct 2856 --source \"Main St\"");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = runSolo("illuminant add " + quoted(table) + " --category window_building --spectrum " +
              quoted(std::filesystem::path(SOLO_PROJECT_DATA_DIR) / "colorimetry" / "cie_illuminant_A.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const solo::IlluminantTable t = solo::readIlluminantTable(table);
  ASSERT_EQ(t.samples.size(), 2u);
  EXPECT_NEAR(t.samples[0].xy.x(), 0.4476, 2e-3);
  EXPECT_NE(t.samples[0].source.find("Main St"), std::string::npos);
  EXPECT_NEAR(t.samples[1].xy.x(), 0.4476, 1e-3);
  EXPECT_NEAR(t.samples[1].xy.y(), 0.4074, 1e-3);
  r = runSolo("illuminant add " + quoted(table) + " --category window_building");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("exactly one of --spectrum, --cct, --raw"), std::string::npos) << r.output;
  r = runSolo("illuminant add " + quoted(table) + " --category lantern --cct 3000");
  EXPECT_EQ(r.exit_code, 2);
  r = runSolo("illuminant add " + quoted(table) + " --category clock --raw " + quoted(dir / "card.dng") +
              " --roi 10,10,20,20");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("card.dng: file not found"), std::string::npos) << r.output;
}

TEST(IlluminantCli, RegenerateReproducesTheBundledTable) {
  TempDir dir;
  const auto r = runSolo("illuminant regenerate -o " + quoted(dir / "t.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(readText(dir / "t.csv"),
            readText(std::filesystem::path(SOLO_PROJECT_DATA_DIR) / "illuminants" / "night_illuminants.csv"));
}
