// The solo binary end to end: exit codes, messages that name the file, no partial output.

#include <solo/core/image_io.h>

#include <nlohmann/json.hpp>

#include <algorithm>

#include "test_support.h"

using solo::test::runSolo;
using solo::test::TempDir;

TEST(Cli, VersionListsTheLibrariesItWasBuiltAgainst) {
  const auto r = runSolo("--version");
  EXPECT_EQ(r.exit_code, 0);
  for (const char* library : {"solo 0.", "CGAL 5.", "OpenMesh 9.", "Eigen 3.", "Ceres 2.", "Embree 3.", "OpenCV 4.",
                              "OpenImageIO 2.", "TBB ", "CLI11 2.", "nlohmann_json 3."})
    EXPECT_NE(r.output.find(library), std::string::npos) << library << " missing in:\n" << r.output;
}

TEST(Cli, InfoPrintsWhatWasRead) {
  TempDir dir;
  solo::writeImage(dir / "day.png", cv::Mat(6, 8, CV_8UC3));
  cv::Mat d(6, 8, CV_32F, cv::Scalar(2));
  d.at<float>(0, 0) = -1;
  solo::writeImage(dir / "d.pfm", d);
  solo::test::writeText(dir / "s.json", R"({"image": "day.png", "depth": "d.pfm"})");
  const auto r = runSolo("info --json \"" + (dir / "s.json").string() + "\"");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = nlohmann::json::parse(r.output);
  EXPECT_EQ(j["stages"][0]["metrics"]["depth_valid"], 47);
  EXPECT_EQ(j["stages"][0]["metrics"]["depth_negative"], 1);
}

TEST(Cli, BadSceneExitsNonZeroNamingTheFileAndWritesNothing) {
  TempDir dir;
  solo::test::writeText(dir / "s.json", R"({"image": "day.png", "depth": "d.pfm"})");
  const auto r = runSolo("night \"" + (dir / "s.json").string() + "\" -o \"" + (dir / "out/night.png").string() + "\"");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("day.png: file not found"), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "out")) << "no partial output";
}

TEST(Cli, NightOnTheEmbeddedDefaultWritesTheImageAndAReport) {
  TempDir dir;
  // A small budget: this checks the plumbing and the report, not the image quality.
  const auto r = runSolo("night -o \"" + (dir / "night.png").string() +
                         "\" --seed 7 --min-spp 2 --max-spp 2 --no-optimize --no-solids");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const solo::ImageFileInfo info = solo::probeImage(dir / "night.png");
  EXPECT_EQ(info.width, 960);
  EXPECT_EQ(info.height, 540);
  EXPECT_EQ(info.channels, 3);
  EXPECT_EQ(info.pixel_type, "uint8");
  const auto j = nlohmann::json::parse(solo::test::readText(dir / "night.report.json"));
  EXPECT_EQ(j["seed"], 7);
  std::vector<std::string> stages;
  for (const auto& s : j["stages"]) stages.push_back(s["name"]);
  for (const char* expected : {"input", "upsample", "filter", "uncertain", "optimize", "mesh", "lights", "scene",
                               "render", "post"})
    EXPECT_NE(std::find(stages.begin(), stages.end(), expected), stages.end()) << expected;
  for (const auto& s : j["stages"]) {
    EXPECT_GE(s["seconds"].get<double>(), 0.0) << s["name"];
    if (s["name"] == "optimize") {
      EXPECT_TRUE(s["skipped"].get<bool>()) << "--no-optimize";
    }
    if (s["name"] == "render") {
      EXPECT_EQ(s["metrics"]["samples_per_pixel_max"], 2);
    }
  }
  EXPECT_TRUE(j["versions"].contains("Embree"));
  EXPECT_EQ(solo::test::listFolder(dir.path()), (std::vector<std::string>{"night.png", "night.report.json"}))
      << "no stray temporary files";
}

TEST(Cli, ConvertDepthBetweenFormats) {
  TempDir dir;
  cv::Mat codes(3, 3, CV_16U, cv::Scalar(512));
  codes.at<uint16_t>(1, 1) = 0;
  solo::writeImage(dir / "kitti.png", codes);
  auto r = runSolo("convert depth \"" + (dir / "kitti.png").string() + "\" \"" + (dir / "d.npy").string() +
                   "\" --input-scale 0.00390625");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const cv::Mat d = solo::readDepth(dir / "d.npy", 0);
  EXPECT_FLOAT_EQ(d.at<float>(0, 0), 2.f);
  EXPECT_FLOAT_EQ(d.at<float>(1, 1), 0.f);
  r = runSolo("convert depth \"" + (dir / "kitti.png").string() + "\" \"" + (dir / "d.exr").string() + "\"");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("kitti.png: uint16 depth needs a scale"), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "d.exr"));
}
