// `solo night`: quality presets, the config file (read, written, errors), the contact sheet and
// the notes for effects skipped. Runs on a small `solo synth` scene with the draft preset.

#include <solo/core/image_io.h>
#include <solo/render/contact_sheet.h>

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <memory>
#include <regex>
#include <set>
#include <sstream>

#include "test_support.h"

using solo::test::readText;
using solo::test::runSolo;
using solo::test::TempDir;
using solo::test::writeText;

namespace {

std::string q(const std::filesystem::path& p) { return "\"" + p.string() + "\""; }

nlohmann::json readJson(const std::filesystem::path& file) { return nlohmann::json::parse(readText(file)); }

const nlohmann::json& stage(const nlohmann::json& report, const std::string& name) {
  for (const auto& s : report["stages"])
    if (s["name"] == name) return s;
  throw std::runtime_error("no stage " + name);
}

bool hasNote(const nlohmann::json& s, const std::string& note) {
  for (const auto& n : s["notes"])
    if (n.get<std::string>() == note) return true;
  return false;
}

bool hasWarning(const nlohmann::json& s, const std::string& warning) {
  if (!s.contains("warnings")) return false;
  for (const auto& w : s["warnings"])
    if (w.get<std::string>() == warning) return true;
  return false;
}

// key -> value lines of the [night] section of a config file.
std::map<std::string, std::string> configValues(const std::string& text) {
  std::map<std::string, std::string> values;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    const auto eq = line.find(" = ");
    if (line.empty() || line[0] == '#' || line[0] == '[' || eq == std::string::npos) continue;
    values[line.substr(0, eq)] = line.substr(eq + 3);
  }
  return values;
}

// A 160x90 synthetic street shared by the tests (made once: `solo synth` takes a second).
class NightCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    data_ = std::make_unique<TempDir>();
    const auto r = runSolo("synth -o " + q(data_->path() / "street") + " --size 160x90 --seed 4");
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }
  static void TearDownTestSuite() { data_.reset(); }
  static std::filesystem::path scene() { return data_->path() / "street" / "scene.json"; }
  static std::filesystem::path sceneDir() { return data_->path() / "street"; }

  TempDir dir;
  static std::unique_ptr<TempDir> data_;
};
std::unique_ptr<TempDir> NightCli::data_;

}  // namespace

TEST_F(NightCli, DraftPresetSetsItsKnobsAndTheReportNamesIt) {
  const auto r = runSolo("night " + q(scene()) + " -o " + q(dir / "n.png") + " --preset draft");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("preset: draft"), std::string::npos) << "terminal summary names the preset:\n" << r.output;
  const auto j = readJson(dir / "n.report.json");
  EXPECT_EQ(j["preset"], "draft");
  // docs/presets.md: draft renders at most 2 samples per pixel and optimises 3 iterations.
  EXPECT_EQ(stage(j, "render")["metrics"]["samples_per_pixel_max"], 2);
  EXPECT_LE(stage(j, "optimize")["metrics"]["iterations"].get<int>(), 3);
  // ... and meshes the depth downsampled 2x and renders at half the image size, upsampled.
  const int width = stage(j, "upsample")["metrics"]["image_width"]["value"].get<int>();
  const int height = stage(j, "upsample")["metrics"]["image_height"]["value"].get<int>();
  EXPECT_EQ(stage(j, "mesh")["metrics"]["depth_width"]["value"].get<int>(), width / 2);
  EXPECT_EQ(stage(j, "render")["metrics"]["render_width"]["value"].get<int>(), width / 2);
  EXPECT_EQ(stage(j, "render")["metrics"]["render_height"]["value"].get<int>(), height / 2);
  const cv::Mat night = cv::imread((dir / "n.png").string(), cv::IMREAD_UNCHANGED);
  EXPECT_EQ(night.cols, width);
  EXPECT_EQ(night.rows, height);
}

TEST_F(NightCli, OptionsGivenExplicitlyBeatThePreset) {
  const auto r = runSolo("night " + q(scene()) + " -o " + q(dir / "n.png") +
                         " --preset draft --min-spp 3 --max-spp 3 --no-optimize");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = readJson(dir / "n.report.json");
  EXPECT_EQ(j["preset"], "draft");
  EXPECT_EQ(stage(j, "render")["metrics"]["samples_per_pixel_max"], 3);
  EXPECT_DOUBLE_EQ(stage(j, "render")["metrics"]["samples_per_pixel_mean"].get<double>(), 3.0);
  EXPECT_TRUE(stage(j, "optimize")["skipped"].get<bool>());
}

TEST_F(NightCli, UnknownPresetIsRejectedBeforeAnyWork) {
  const auto r = runSolo("night " + q(scene()) + " -o " + q(dir / "n.png") + " --preset fastest");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("fastest"), std::string::npos) << r.output;
  EXPECT_TRUE(solo::test::listFolder(dir.path()).empty());
}

TEST_F(NightCli, ConfigFileValuesLandInTheRunAndTheCommandLineBeatsThem) {
  writeText(dir / "run.toml", "# a run\n[night]\npreset = \"draft\"\nseed = 11\nmin-spp = 3\nmax-spp = 3\n"
                              "glare = false\n");
  auto r = runSolo("night " + q(scene()) + " -o " + q(dir / "a.png") + " --config " + q(dir / "run.toml"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  auto j = readJson(dir / "a.report.json");
  EXPECT_EQ(j["seed"], 11);
  EXPECT_EQ(j["preset"], "draft");
  EXPECT_EQ(stage(j, "render")["metrics"]["samples_per_pixel_max"], 3);
  EXPECT_TRUE(hasNote(stage(j, "post"), "glare switched off (--no-glare)"));

  // The command line overrides the file (the file overrides the preset).
  r = runSolo("night " + q(scene()) + " -o " + q(dir / "b.png") + " --config " + q(dir / "run.toml") +
              " --seed 12 --max-spp 4 --glare");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  j = readJson(dir / "b.report.json");
  EXPECT_EQ(j["seed"], 12);
  EXPECT_EQ(stage(j, "render")["metrics"]["samples_per_pixel_max"], 4);
  EXPECT_FALSE(hasNote(stage(j, "post"), "glare switched off (--no-glare)"));
}

TEST_F(NightCli, TheExampleConfigOfTheDocsIsReadAsDocumented) {
  const std::filesystem::path example = std::filesystem::path(SOLO_PROJECT_SOURCE_DIR) / "docs/night.example.toml";
  // The preset and samples overridden on the command line keep the test fast.
  const auto r = runSolo("night " + q(scene()) + " -o " + q(dir / "n.png") + " --config " + q(example) +
                         " --preset draft --max-spp 2 --write-config " + q(dir / "n.toml"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto values = configValues(readText(dir / "n.toml"));
  EXPECT_EQ(values.at("seed"), "42");
  EXPECT_EQ(values.at("headlight-flux"), "1000.0");
  EXPECT_EQ(values.at("max-spp"), "2") << "the command line beats the file";
  EXPECT_EQ(values.at("preset"), "\"draft\"");
  EXPECT_EQ(readJson(dir / "n.report.json")["seed"], 42);
}

TEST_F(NightCli, WithoutAnAlbedoMapTheDayLightIsRemovedOnRequestWithTheImagesShadowsByDefault) {
  auto manifest = nlohmann::json::parse(readText(scene()));
  manifest.erase("albedo");
  const auto no_albedo = sceneDir() / "no_albedo.json";
  writeText(no_albedo, manifest.dump());
  const auto night = [&](const std::string& name, const std::string& flags) {
    const auto r = runSolo("night " + q(no_albedo) + " -o " + q(dir / (name + ".png")) + " --preset draft " + flags);
    EXPECT_EQ(r.exit_code, 0) << r.output;
    return stage(readJson(dir / (name + ".report.json")), "scene");
  };
  const auto kept = night("kept", "");
  EXPECT_TRUE(hasNote(kept, "no albedo map: the linearised day image stands in for the reflectance"));
  EXPECT_FALSE(kept["metrics"].contains("day_light_shadows"));
  const auto from_image = night("image", "--remove-day-light");
  EXPECT_EQ(from_image["metrics"]["day_light_shadows"], "image");
  EXPECT_GT(from_image["metrics"]["day_light_seconds"]["value"].get<double>(), 0.0);
  const auto rays = night("rays", "--remove-day-light --day-shadows-from-rays");
  EXPECT_EQ(rays["metrics"]["day_light_shadows"], "rays");
  // Each names how the day was lit; the removal ran on the same geometry both times.
  for (const auto& s : {from_image, rays}) {
    const std::string method = s["metrics"]["day_light_method"];
    EXPECT_TRUE(method == "sun-and-sky" || method == "sky-only" || method == "day-image") << method;
  }
}

TEST_F(NightCli, ConfigFileErrorsNameTheFileAndWriteNothing) {
  const auto out = dir / "out";
  std::filesystem::create_directory(out);
  const auto run = [&](const std::string& name, const std::string& text) {
    writeText(dir / name, text);
    return runSolo("night " + q(scene()) + " -o " + q(out / "n.png") + " --config " + q(dir / name));
  };
  auto r = run("unknown.toml", "[night]\nseed = 3\nmax-ssp = 8\n");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("unknown.toml"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("max-ssp"), std::string::npos) << r.output;

  r = run("flat.toml", "seed = 3\n");  // keys belong under [night]
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("flat.toml"), std::string::npos) << r.output;

  r = run("garbage.toml", "[night\nseed 3\n");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("garbage.toml"), std::string::npos) << r.output;

  r = run("badvalue.toml", "[night]\nmax-spp = many\n");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("max-spp"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("badvalue.toml"), std::string::npos) << r.output;

  r = runSolo("night " + q(scene()) + " -o " + q(out / "n.png") + " --config " + q(dir / "absent.toml"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("absent.toml"), std::string::npos) << r.output;

  EXPECT_TRUE(solo::test::listFolder(out).empty()) << "no partial output";
}

TEST_F(NightCli, WrittenConfigHoldsEveryOptionAndReproducesTheRun) {
  // A light record, so that --lights (an optional path) is set too.
  auto r = runSolo("lights " + q(scene()) + " -o " + q(dir / "lights.json"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = runSolo("night " + q(scene()) + " -o " + q(dir / "a.png") + " --preset draft --seed 5 --max-spp 3 --no-noise" +
              " --lights " + q(dir / "lights.json") + " --report " + q(dir / "a.json") + " --render-exr " +
              q(dir / "a.exr") + " --contact-sheet " + q(dir / "a.sheet.png") + " --write-config " +
              q(dir / "a.toml"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto written = configValues(readText(dir / "a.toml"));
  EXPECT_EQ(written.at("preset"), "\"draft\"");
  EXPECT_EQ(written.at("seed"), "5");
  EXPECT_EQ(written.at("max-spp"), "3");
  EXPECT_EQ(written.at("min-spp"), "1") << "from the preset";
  EXPECT_EQ(written.at("noise"), "false");

  // Every long option of `solo night --help` is in the file, except those that are not
  // settings of one run (help, writing the config, the batch driver's own).
  const auto help = runSolo("night --help");
  ASSERT_EQ(help.exit_code, 0);
  const std::set<std::string> not_settings = {"help",  "write-config", "verbose",       "batch",
                                              "shard", "jobs",         "scene-timeout", "layout"};
  const std::regex option_line(R"(^\s+(?:-\w,)?--([\w-]+))");
  int options = 0;
  std::istringstream lines(help.output);
  for (std::string line; std::getline(lines, line);) {
    std::smatch m;
    if (!std::regex_search(line, m, option_line) || not_settings.count(m[1])) continue;
    ++options;
    EXPECT_TRUE(written.count(m[1])) << "--" << m[1] << " is not in the written config";
  }
  EXPECT_GE(options, 25);
  EXPECT_TRUE(written.count("scene"));

  // Read back, it gives the same run: same config, same image.
  r = runSolo("night --config " + q(dir / "a.toml") + " -o " + q(dir / "b.png") + " --report " + q(dir / "b.json") +
              " --render-exr " + q(dir / "b.exr") + " --contact-sheet " + q(dir / "b.sheet.png") +
              " --write-config " + q(dir / "b.toml"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  auto again = configValues(readText(dir / "b.toml"));
  for (const char* key : {"output", "report", "render-exr", "contact-sheet"}) again[key] = written.at(key);
  EXPECT_EQ(again, written);
  const cv::Mat a = cv::imread((dir / "a.png").string()), b = cv::imread((dir / "b.png").string());
  ASSERT_FALSE(a.empty());
  EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0.0) << "same seed, same options: the same night";
}

TEST_F(NightCli, ContactSheetTilesHoldTheStagesPictures) {
  const auto r = runSolo("night " + q(scene()) + " -o " + q(dir / "n.png") + " --preset draft --contact-sheet " +
                         q(dir / "sheet.png"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const cv::Mat sheet = cv::imread((dir / "sheet.png").string());  // BGR, as the others below
  const cv::Mat night = cv::imread((dir / "n.png").string());
  const cv::Mat day = cv::imread((sceneDir() / "day.png").string());
  ASSERT_FALSE(sheet.empty());
  // Six tiles in a 3 x 2 grid of 160x90 tiles (images narrower than 480 px keep their size).
  const solo::ContactSheetLayout layout = solo::contactSheetLayout(day.size(), 6);
  EXPECT_EQ(layout.tile, cv::Size(160, 90));
  EXPECT_EQ(sheet.size(), layout.sheet);
  EXPECT_EQ(sheet.size(), cv::Size(6 + 3 * (160 + 6), 6 + 2 * (22 + 90 + 6)));
  EXPECT_EQ(cv::norm(sheet(layout.tiles[0]), day, cv::NORM_INF), 0.0) << "day tile";
  EXPECT_EQ(cv::norm(sheet(layout.tiles[5]), night, cv::NORM_INF), 0.0) << "night tile";

  // Removed faces: the day image except at cut pixels, painted in the criterion colours; the
  // mesh stage removed faces, so some are painted.
  const cv::Mat removed = sheet(layout.tiles[3]);
  const std::set<std::array<int, 3>> colours = {{0, 0, 255}, {0, 230, 255}, {255, 230, 0}, {255, 0, 255}};  // BGR
  int painted = 0, wrong = 0;
  for (int y = 0; y < removed.rows; ++y)
    for (int x = 0; x < removed.cols; ++x) {
      const cv::Vec3b p = removed.at<cv::Vec3b>(y, x);
      if (p == day.at<cv::Vec3b>(y, x)) continue;
      ++painted;
      wrong += !colours.count({p[0], p[1], p[2]});
    }
  EXPECT_GT(painted, 50);
  EXPECT_EQ(wrong, 0);
  const auto j = readJson(dir / "n.report.json");
  EXPECT_GT(stage(j, "mesh")["metrics"]["spurious_faces_removed"].get<int>(), 0);

  // Depth tiles: sky (no depth) is black in both; elsewhere colours of the turbo map.
  const cv::Mat raw = sheet(layout.tiles[1]), refined = sheet(layout.tiles[2]);
  EXPECT_EQ(raw.at<cv::Vec3b>(0, 80), cv::Vec3b(0, 0, 0)) << "top centre is sky in solo synth streets";
  EXPECT_EQ(refined.at<cv::Vec3b>(0, 80), cv::Vec3b(0, 0, 0));
  EXPECT_NE(refined.at<cv::Vec3b>(85, 80), cv::Vec3b(0, 0, 0)) << "the road in front has depth";

  // Labels are drawn in their strips (light text on the dark background).
  for (const cv::Rect& label : layout.labels) {
    double top = 0;
    cv::minMaxLoc(sheet(label).reshape(1), nullptr, &top);
    EXPECT_GT(top, 150);
  }
}

// Pixels of an 8-bit BGR image in exactly the overlay's proposed-light frame colour, magenta.
static int magentaPixels(const cv::Mat& bgr) {
  int count = 0;
  for (int y = 0; y < bgr.rows; ++y)
    for (int x = 0; x < bgr.cols; ++x) count += bgr.at<cv::Vec3b>(y, x) == cv::Vec3b(255, 0, 255);
  return count;
}

TEST_F(NightCli, ContactSheetFramesProposedLightsInMagentaAndSaysSo) {
  // The same street without its light map: `night` proposes lights from the labels.
  auto manifest = readJson(scene());
  manifest.erase("lights");
  manifest.erase("light_groups");
  const auto unlit = sceneDir() / "no_light_map.json";
  writeText(unlit, manifest.dump(2));
  auto r = runSolo("night " + q(unlit) + " -o " + q(dir / "p.png") + " --preset draft --contact-sheet " +
                   q(dir / "p_sheet.png"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_GT(stage(readJson(dir / "p.report.json"), "light_proposals")["metrics"]["lights"].get<int>(), 0);
  r = runSolo("night " + q(scene()) + " -o " + q(dir / "g.png") + " --preset draft --contact-sheet " +
              q(dir / "g_sheet.png"));
  ASSERT_EQ(r.exit_code, 0) << r.output;

  const cv::Mat proposed = cv::imread((dir / "p_sheet.png").string());
  const cv::Mat given = cv::imread((dir / "g_sheet.png").string());
  ASSERT_FALSE(proposed.empty());
  ASSERT_EQ(proposed.size(), given.size());
  const solo::ContactSheetLayout layout = solo::contactSheetLayout(cv::Size(160, 90), 6);
  EXPECT_GT(magentaPixels(proposed(layout.tiles[4])), 20) << "proposed lights are framed";
  EXPECT_EQ(magentaPixels(given(layout.tiles[4])), 0) << "lights of a light map are not";
  // "lights: proposed from labels (N)" against "lights: bright on, dim off".
  EXPECT_GT(cv::norm(proposed(layout.labels[4]), given(layout.labels[4]), cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(proposed(layout.labels[0]), given(layout.labels[0]), cv::NORM_INF), 0.0) << "day label";
}

// --denoise-passes and --denoise-fine-passes set the filter's a-trous passes: 2 passes, taps 1
// and 2 px apart, and no fine pass reach 2 (2^2 - 1) = 6 px; the default 5 and 2 reach
// 62 + 6 = 68 px. 0 passes or 11 fine passes are refused before anything is written.
TEST_F(NightCli, DenoisePassesAndFinePassesReachTheFilterAndOutOfRangeIsRefused) {
  auto r = runSolo("night " + q(scene()) + " -o " + q(dir / "n.png") + " --preset draft --max-spp 1");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  auto denoise = stage(readJson(dir / "n.report.json"), "denoise")["metrics"];
  EXPECT_EQ(denoise["iterations"], 5);
  EXPECT_EQ(denoise["fine_passes"], 2);
  EXPECT_EQ(denoise["footprint_radius"]["value"], 68);
  r = runSolo("night " + q(scene()) + " -o " + q(dir / "p.png") +
              " --preset draft --max-spp 1 --denoise-passes 2 --denoise-fine-passes 0");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  denoise = stage(readJson(dir / "p.report.json"), "denoise")["metrics"];
  EXPECT_EQ(denoise["iterations"], 2);
  EXPECT_EQ(denoise["fine_passes"], 0);
  EXPECT_EQ(denoise["footprint_radius"]["value"], 6);
  const cv::Mat a = cv::imread((dir / "n.png").string()), b = cv::imread((dir / "p.png").string());
  ASSERT_FALSE(a.empty());
  EXPECT_GT(cv::norm(a, b, cv::NORM_INF), 0.0) << "a narrower filter, another image";
  const auto out = dir / "out";
  std::filesystem::create_directory(out);
  r = runSolo("night " + q(scene()) + " -o " + q(out / "z.png") + " --denoise-passes 0");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("--denoise-passes"), std::string::npos) << r.output;
  r = runSolo("night " + q(scene()) + " -o " + q(out / "z.png") + " --denoise-fine-passes 11");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("--denoise-fine-passes"), std::string::npos) << r.output;
  EXPECT_TRUE(solo::test::listFolder(out).empty());
}

// --no-pixel-texture: camera rays take their faces' material and light (the render says so);
// the image changes at the edges between materials.
TEST_F(NightCli, PixelTextureIsOnByDefaultAndCanBeSwitchedOff) {
  auto r = runSolo("night " + q(scene()) + " -o " + q(dir / "t.png") + " --preset draft --max-spp 1");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(stage(readJson(dir / "t.report.json"), "render")["metrics"]["pixel_texture"], true);
  r = runSolo("night " + q(scene()) + " -o " + q(dir / "f.png") + " --preset draft --max-spp 1 --no-pixel-texture");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto render = stage(readJson(dir / "f.report.json"), "render");
  EXPECT_EQ(render["metrics"]["pixel_texture"], false);
  bool said = false;
  for (const auto& note : render["notes"]) said = said || note.get<std::string>().rfind("pixel texture off", 0) == 0;
  EXPECT_TRUE(said) << render["notes"];
  const cv::Mat a = cv::imread((dir / "t.png").string()), b = cv::imread((dir / "f.png").string());
  ASSERT_FALSE(a.empty());
  EXPECT_GT(cv::norm(a, b, cv::NORM_INF), 0.0);
}

TEST_F(NightCli, SamplerOptionReachesTheRendererAndUnknownSamplersAreRefused) {
  auto r = runSolo("night " + q(scene()) + " -o " + q(dir / "n.png") + " --preset draft");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(stage(readJson(dir / "n.report.json"), "render")["metrics"]["sampler"], "sobol") << "the default";
  r = runSolo("night " + q(scene()) + " -o " + q(dir / "i.png") + " --preset draft --sampler independent");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(stage(readJson(dir / "i.report.json"), "render")["metrics"]["sampler"], "independent");
  const auto out = dir / "out";
  std::filesystem::create_directory(out);
  r = runSolo("night " + q(scene()) + " -o " + q(out / "h.png") + " --preset draft --sampler halton");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("--sampler"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("halton"), std::string::npos) << r.output;
  EXPECT_TRUE(solo::test::listFolder(out).empty());
}

TEST_F(NightCli, ContactSheetWithAnUnsupportedFormatFailsBeforeAnyWork) {
  const auto r = runSolo("night " + q(scene()) + " -o " + q(dir / "n.png") + " --preset draft --contact-sheet " +
                         q(dir / "sheet.bmp"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("sheet.bmp"), std::string::npos) << r.output;
  EXPECT_TRUE(solo::test::listFolder(dir.path()).empty());
}

TEST_F(NightCli, EveryLightOffSkipsGlareAndSaysNoActiveLightInView) {
  auto r = runSolo("lights " + q(scene()) + " -o " + q(dir / "lights.json"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  auto record = readJson(dir / "lights.json");
  ASSERT_GT(record["lights"].size(), 0u);
  for (auto& light : record["lights"]) light["on"] = false;
  writeText(dir / "off.json", record.dump());
  r = runSolo("night " + q(scene()) + " -o " + q(dir / "n.png") + " --preset draft --no-headlights --lights " +
              q(dir / "off.json"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = readJson(dir / "n.report.json");
  EXPECT_TRUE(hasWarning(stage(j, "scene"), "no active light in view"));
  EXPECT_EQ(stage(j, "scene")["metrics"]["emitters"], 0);
  EXPECT_TRUE(hasNote(stage(j, "post"), "no light above glare threshold: glare skipped"));
  // The terminal: the warning on a line of its own; the skipped glare in the report (its count).
  EXPECT_NE(r.output.find("warning: no active light in view"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("no light above glare threshold: glare skipped"), std::string::npos) << r.output;

  // With the lights as drawn (some on) neither note appears.
  r = runSolo("night " + q(scene()) + " -o " + q(dir / "on.png") + " --preset draft --lights " +
              q(dir / "lights.json"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto on = readJson(dir / "on.report.json");
  EXPECT_FALSE(hasWarning(stage(on, "scene"), "no active light in view"));
  EXPECT_FALSE(hasNote(stage(on, "post"), "no light above glare threshold: glare skipped"));
}

// The composition itself, hand-computed.
TEST(ContactSheet, LayoutOfSixTilesOfA960x540Image) {
  const solo::ContactSheetLayout l = solo::contactSheetLayout({960, 540}, 6);
  EXPECT_EQ(l.tile, cv::Size(480, 270));
  EXPECT_EQ(l.sheet, cv::Size(6 + 3 * 486, 6 + 2 * (22 + 270 + 6)));
  EXPECT_EQ(l.labels[0], cv::Rect(6, 6, 480, 22));
  EXPECT_EQ(l.tiles[0], cv::Rect(6, 28, 480, 270));
  EXPECT_EQ(l.tiles[4], cv::Rect(6 + 486, 6 + 298 + 22, 480, 270));
  for (std::size_t i = 0; i < l.tiles.size(); ++i)
    for (std::size_t k = i + 1; k < l.tiles.size(); ++k) EXPECT_TRUE((l.tiles[i] & l.tiles[k]).empty());
}

TEST(ContactSheet, TilesAreAreaAveragedIntoPlace) {
  // A 4x2 image of one bright and one dark half, composed at a 2 px tile width: each tile pixel
  // is the mean of a 2x2 block.
  cv::Mat image(2, 4, CV_8UC3, cv::Scalar(0, 0, 0));
  image(cv::Rect(0, 0, 2, 2)).setTo(cv::Scalar(200, 100, 40));
  solo::ContactSheetOptions options;
  options.max_tile_width = 2;
  options.columns = 1;
  const cv::Mat sheet = solo::composeContactSheet({{"a", image}}, options);
  const solo::ContactSheetLayout l = solo::contactSheetLayout(image.size(), 1, options);
  EXPECT_EQ(l.tile, cv::Size(2, 1));
  EXPECT_EQ(sheet.at<cv::Vec3b>(l.tiles[0].y, l.tiles[0].x), cv::Vec3b(200, 100, 40));
  EXPECT_EQ(sheet.at<cv::Vec3b>(l.tiles[0].y, l.tiles[0].x + 1), cv::Vec3b(0, 0, 0));
  EXPECT_THROW(solo::composeContactSheet({{"grey", cv::Mat(2, 4, CV_8U)}}), std::invalid_argument);
}

TEST(ContactSheet, DepthColoursAreLogarithmicAndInvalidIsBlack) {
  cv::Mat depth(1, 5, CV_32F);
  depth.at<float>(0) = 2.f;    // near: code 0
  depth.at<float>(1) = 200.f;  // far: code 255
  depth.at<float>(2) = 20.f;   // geometric mean: code 128 (127.5 rounded)
  depth.at<float>(3) = 0.f;    // invalid
  depth.at<float>(4) = std::nanf("");
  const cv::Mat rgb = solo::colourizeDepth(depth, 2.0, 200.0);
  cv::Mat codes(1, 3, CV_8U), turbo;
  codes.at<uchar>(0) = 0, codes.at<uchar>(1) = 255, codes.at<uchar>(2) = 128;
  cv::applyColorMap(codes, turbo, cv::COLORMAP_TURBO);  // BGR
  for (int i = 0; i < 3; ++i) {
    const cv::Vec3b bgr = turbo.at<cv::Vec3b>(i);
    EXPECT_EQ(rgb.at<cv::Vec3b>(i), cv::Vec3b(bgr[2], bgr[1], bgr[0])) << i;
  }
  EXPECT_EQ(rgb.at<cv::Vec3b>(3), cv::Vec3b(0, 0, 0));
  EXPECT_EQ(rgb.at<cv::Vec3b>(4), cv::Vec3b(0, 0, 0));
}

// A user who accepts the completion's guess lowers --min-depth-share: the bundled 0.2 % LiDAR
// sample (4 818 returns in 1936x1216 pixels), refused at the default 1 %, then converts, every
// pixel below the highest return filled (no labels: what has no depth above it is sky, docs/
// depth-refinement.md). A share above 1 is refused before anything is written.
TEST_F(NightCli, MinDepthShareLetsTheSparseLidarSampleThrough) {
  const std::filesystem::path lidar = std::filesystem::path(SOLO_PROJECT_DATA_DIR) / "samples/dgp-real/scene.json";
  auto r = runSolo("night " + q(lidar) + " -o " + q(dir / "n.png") + " --preset draft --max-spp 1 --min-depth-share 0.001");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto report = readJson(dir / "n.report.json");
  EXPECT_EQ(stage(report, "input")["metrics"]["depth_valid"], 4818);
  const auto& complete = stage(report, "complete")["metrics"];
  EXPECT_EQ(complete["sky_rule"], "no depth above (no labels)");
  EXPECT_GT(complete["filled_share"]["value"].get<double>(), 99.0);
  EXPECT_TRUE(std::filesystem::exists(dir / "n.png"));
  const auto out = dir / "out";
  std::filesystem::create_directory(out);
  r = runSolo("night " + q(lidar) + " -o " + q(out / "m.png") + " --min-depth-share 2");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("--min-depth-share"), std::string::npos) << r.output;
  EXPECT_TRUE(solo::test::listFolder(out).empty());
}
