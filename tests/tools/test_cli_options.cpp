// Every option is checked before any work: seeds without wrap-around, sizes without trailing
// junk or overflow, sample counts in order, finite numbers in range. Bad options exit 2 with
// the option named, and nothing is written.

#include "test_support.h"

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

TEST(CliOptions, SizesAreTwoWholeNumbersWithNothingAfter) {
  TempDir dir;
  for (const std::string size : {"64x48junk", "4294967360x48", "64", "x48", "-64x48", "64x-48"}) {
    const auto r = runSolo("synth -o " + q(dir / "s") + " --size " + size);
    EXPECT_EQ(r.exit_code, 2) << size << "\n" << r.output;
    EXPECT_NE(r.output.find("--size"), std::string::npos) << size << "\n" << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir / "s")) << size;
  }
}

}  // namespace
