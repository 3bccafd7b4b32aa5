// Every option is checked before any work: seeds without wrap-around, sizes without trailing
// junk or overflow, sample counts in order, finite numbers in range. Bad options exit 2 with
// the option named, and nothing is written.

#include "test_support.h"

#include <solo/core/image_io.h>

#include <gtest/gtest.h>

#include <string>

namespace {

using solo::test::runSolo;
using solo::test::TempDir;

std::string q(const std::filesystem::path& p) { return "'" + p.string() + "'"; }

// Runs `solo <arguments>` in an empty folder and expects exit 2, `option` named, no file made.
void expectRefused(const std::string& arguments, const std::string& option) {
  TempDir dir;
  const auto r = runSolo(arguments + " -o " + q(dir / "out.png"));
  EXPECT_EQ(r.exit_code, 2) << arguments << "\n" << r.output;
  EXPECT_NE(r.output.find(option), std::string::npos) << arguments << "\n" << r.output;
  EXPECT_TRUE(solo::test::listFolder(dir.path()).empty()) << arguments;
}

TEST(CliOptions, SeedsAreWholeNumbersThatDoNotWrap) {
  expectRefused("night --seed -1", "--seed");
  expectRefused("night --seed 18446744073709551616", "--seed");
  expectRefused("night --seed 1.5", "--seed");
  expectRefused("lights --seed -3", "--seed");
}

TEST(CliOptions, SampleCountsMustBePositiveAndInOrder) {
  expectRefused("night --min-spp 0", "--min-spp");
  expectRefused("night --min-spp -5", "--min-spp");
  expectRefused("night --max-spp 0", "--max-spp");
  expectRefused("night --min-spp 10 --max-spp 1", "--min-spp");
}

TEST(CliOptions, NumbersMustBeFiniteAndInRange) {
  expectRefused("night --relative-error nan", "--relative-error");
  expectRefused("night --relative-error -0.1", "--relative-error");
  expectRefused("night --noise-factor nan", "--noise-factor");
  expectRefused("night --optimize-tolerance -1", "--optimize-tolerance");
  expectRefused("night --shadow-roulette nan", "--shadow-roulette");
  expectRefused("night --headlight-flux inf", "--headlight-flux");
  expectRefused("night --headlight-flux 1e300", "--headlight-flux");
  expectRefused("night --sensor-white nan", "--sensor-white");
  expectRefused("night --glare-threshold nan", "--glare-threshold");
}

// Runs `solo <arguments>` in `dir` and expects exit 2, `message` in the output and the folder
// as it was (nothing created).
void expectRefusedIn(const TempDir& dir, const std::string& arguments, const std::string& message) {
  const std::vector<std::string> before = solo::test::listFolder(dir.path());
  const auto r = runSolo(arguments);
  EXPECT_EQ(r.exit_code, 2) << arguments << "\n" << r.output;
  EXPECT_NE(r.output.find(message), std::string::npos) << arguments << "\n" << r.output;
  EXPECT_EQ(solo::test::listFolder(dir.path()), before) << arguments;
}

TEST(CliOptions, PostExposureSettingsAreFiniteAndInRange) {
  TempDir dir;
  solo::writeImage(dir / "xyz.exr", cv::Mat(8, 8, CV_32FC3, cv::Scalar::all(0.25)));
  const std::string base = "post " + q(dir / "xyz.exr") + " -o " + q(dir / "out.png") + " ";
  for (const std::string stops : {"nan", "inf", "-inf", "1e9"})
    expectRefusedIn(dir, base + "--stops " + stops, "solo: error: --stops: must be within [-64, 64]");
  for (const std::string shutter : {"nan", "inf", "0", "-0.1"})
    expectRefusedIn(dir, base + "--shutter " + shutter, "solo: error: --shutter: must be within");
  for (const std::string f_number : {"nan", "inf", "0", "-2"})
    expectRefusedIn(dir, base + "--f-number " + f_number, "solo: error: --f-number: must be within [0.5, 64]");
  for (const std::string iso : {"nan", "inf", "0", "-100"})
    expectRefusedIn(dir, base + "--iso " + iso, "solo: error: --iso: must be within [100, 3200]");
  expectRefusedIn(dir, base + "--shutter 0.01 --iso nan", "solo: error: --iso:");
  expectRefusedIn(dir, base + "--glare-scatter 0", "solo: error: --glare-scatter:");
  expectRefusedIn(dir, base + "--noise-scale nan", "solo: error: --noise-scale:");
}

TEST(CliOptions, FdaBetaIsAShareFromZeroToOne) {
  for (const std::string beta : {"nan", "-0.1", "1.5", "inf"})
    expectRefused("fda --source a.png --target b.png --beta " + beta, "solo: error: --beta: must be within [0, 1]");
}

TEST(CliOptions, LightsAblationLuminanceIsPositiveAndFinite) {
  for (const std::string luminance : {"nan", "-5", "0", "inf"})
    expectRefused("lights --ablation --ablation-luminance " + luminance, "solo: error: --ablation-luminance:");
}

TEST(CliOptions, BatchJobsAndSceneTimeoutAreInRange) {
  TempDir dir;
  solo::test::writeText(dir / "list.txt", "scene.json\n");
  const std::string base = "night --batch " + q(dir / "list.txt") + " -o " + q(dir / "out") + " ";
  for (const std::string timeout : {"nan", "-1", "inf", "1e300"})
    expectRefusedIn(dir, base + "--scene-timeout " + timeout, "solo: error: --scene-timeout: must be within [0, 1e+06]");
  expectRefusedIn(dir, base + "--jobs 100000", "solo: error: --jobs: must be at most 256");
  expectRefusedIn(dir, base + "--jobs 99999999999", "--jobs");
  expectRefusedIn(dir, base + "--shard 99999999999/2", "--shard");
}

TEST(CliOptions, EvalDepthBoundsAndScalesAreNumbersInOrder) {
  TempDir dir;
  solo::writeImage(dir / "d.pfm", cv::Mat(4, 4, CV_32F, cv::Scalar(5)));
  const std::string base = "eval depth --pred " + q(dir / "d.pfm") + " --gt " + q(dir / "d.pfm") + " --csv " +
                           q(dir / "r.csv") + " ";
  expectRefusedIn(dir, base + "--min-depth nan", "solo: error: --min-depth: must be within");
  expectRefusedIn(dir, base + "--min-depth -1", "solo: error: --min-depth: must be within");
  expectRefusedIn(dir, base + "--max-depth inf", "solo: error: --max-depth: must be within");
  expectRefusedIn(dir, base + "--min-depth 10 --max-depth 1", "solo: error: --min-depth: must be below --max-depth");
  expectRefusedIn(dir, base + "--pred-scale -1", "solo: error: --pred-scale: must be within");
  expectRefusedIn(dir, base + "--gt-scale nan", "solo: error: --gt-scale: must be within");
}

TEST(CliOptions, SizesAreTwoWholeNumbersWithNothingAfter) {
  TempDir dir;
  for (const std::string size : {"64x48junk", "4294967360x48", "64", "x48", "-64x48", "64x-48", "0x48", "8193x48"}) {
    const auto r = runSolo("synth -o " + q(dir / "s") + " --size " + size);
    EXPECT_EQ(r.exit_code, 2) << size << "\n" << r.output;
    EXPECT_NE(r.output.find("--size"), std::string::npos) << size << "\n" << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir / "s")) << size;
  }
}

}  // namespace
