// The night-illuminant table: coverage, reproducibility from its recipe, the signal-lamp
// chromaticity regions (including the check of the reconstructed ITE inequalities), errors.

#include <solo/core/error.h>
#include <solo/lighting/chromaticity_region.h>
#include <solo/lighting/colorimetry.h>
#include <solo/lighting/illuminant_recipe.h>
#include <solo/lighting/illuminant_table.h>

#include "test_support.h"

namespace {

const std::filesystem::path kData = SOLO_PROJECT_DATA_DIR;

const solo::ColorMatchingFunctions& cmf() {
  static const solo::ColorMatchingFunctions functions =
      solo::readColorMatchingFunctions(kData / "colorimetry" / "cie1931_2deg_cmf_1nm.csv");
  return functions;
}

const std::vector<solo::ChromaticityRegion>& regions() {
  static const std::vector<solo::ChromaticityRegion> r =
      solo::readChromaticityRegions(kData / "illuminants" / "signal_light_chromaticity_regions.csv");
  return r;
}

const solo::ChromaticityRegion& region(const std::string& key) {
  return solo::findRegion(regions(), key, "regions");
}

Eigen::Vector2d led(double peak_nm, double fwhm_nm) {
  return solo::chromaticity(solo::tristimulus(solo::gaussianLedSpectrum(peak_nm, fwhm_nm), cmf()));
}

/// Share of a 0.002-spaced xy grid inside the spectral locus that a region holds.
int realisableGridPoints(const solo::ChromaticityRegion& r) {
  const auto locus = solo::spectralLocus(cmf());
  int n = 0;
  for (double x = 0; x <= 0.75; x += 0.002)
    for (double y = 0; y <= 0.85; y += 0.002)
      if (r.contains({x, y}) && solo::insidePolygon({x, y}, locus)) ++n;
  return n;
}

const std::string kIteRed = "ITE VTCSH (1985/1998)/traffic red";
const std::string kIteYellow = "ITE VTCSH (1985/1998)/traffic yellow";
const std::string kIteGreen = "ITE VTCSH (1985/1998)/traffic green";

}  // namespace

TEST(IlluminantTable, BundledTableHasFiveSamplesPerEmittingCategoryInsideTheSpectralLocus) {
  const solo::IlluminantTable table = solo::readIlluminantTable(kData / "illuminants" / "night_illuminants.csv");
  const auto locus = solo::spectralLocus(cmf());
  for (int c = solo::kFirstLightCategory; c <= solo::kLastLightCategory; ++c) {
    const auto category = static_cast<solo::LightCategory>(c);
    const auto samples = table.samplesFor(category);
    const bool emits = category != solo::LightCategory::Advertisement && category != solo::LightCategory::Clock &&
                       category != solo::LightCategory::Inferred;
    if (emits) EXPECT_GE(samples.size(), 5u) << solo::lightCategoryName(category);
    else EXPECT_EQ(samples.size(), 0u) << solo::lightCategoryName(category) << " has no table colours by design";
    for (const auto& s : samples) {
      EXPECT_TRUE(solo::insidePolygon(s.xy, locus)) << s.source;
      EXPECT_FALSE(s.source.empty());
    }
  }
}

TEST(IlluminantTable, BundledTableIsExactlyWhatItsRecipeRegenerates) {
  const solo::IlluminantTable rebuilt =
      solo::buildIlluminantTable(kData / "illuminants" / "recipe.csv", cmf(), regions());
  EXPECT_EQ(solo::illuminantTableCsv(rebuilt), solo::test::readText(kData / "illuminants" / "night_illuminants.csv"));
}

TEST(IlluminantTable, SignalSamplesLieInTheirStandardsRegions) {
  const solo::IlluminantTable table = solo::readIlluminantTable(kData / "illuminants" / "night_illuminants.csv");
  const auto check = [&](solo::LightCategory category, const std::string& key) {
    for (const auto& s : table.samplesFor(category)) EXPECT_TRUE(region(key).contains(s.xy)) << key << ": " << s.source;
  };
  check(solo::LightCategory::TrafficLightRed, kIteRed);
  check(solo::LightCategory::TrafficLightOrange, kIteYellow);
  check(solo::LightCategory::TrafficLightGreen, kIteGreen);
  check(solo::LightCategory::MovingRear, "SAE J578 (2020)/red (tail/stop)");
  check(solo::LightCategory::MovingFront, "SAE J578 (2020)/white (head/reversing)");
}

TEST(IlluminantTable, ReconstructedIteInequalitiesAreCheckedAgainstPhysics) {
  // 1. Each reconstructed region is realisable (has area inside the spectral locus).
  const int red = realisableGridPoints(region(kIteRed));
  const int yellow = realisableGridPoints(region(kIteYellow));
  const int green = realisableGridPoints(region(kIteGreen));
  EXPECT_GT(red, 0);
  EXPECT_GT(yellow, 0);
  EXPECT_GT(green, 100);
  // 2. Each holds the narrow-band LED of its signal colour and not the others'.
  EXPECT_TRUE(region(kIteRed).contains(led(635, 17)));
  EXPECT_TRUE(region(kIteYellow).contains(led(590, 15)));
  EXPECT_TRUE(region(kIteGreen).contains(led(505, 30)));
  for (const auto& [key, other] : std::vector<std::pair<std::string, Eigen::Vector2d>>{
           {kIteRed, led(590, 15)}, {kIteRed, led(505, 30)}, {kIteYellow, led(635, 17)},
           {kIteYellow, led(505, 30)}, {kIteGreen, led(635, 17)}, {kIteGreen, led(590, 15)}})
    EXPECT_FALSE(region(key).contains(other)) << key;
  // 3. The red and yellow regions agree with the independently transcribed COLREGs
  //    navigation-light regions (they overlap), as signal colours should.
  const auto overlap = [](const solo::ChromaticityRegion& a, const solo::ChromaticityRegion& b) {
    int n = 0;
    for (double x = 0.45; x <= 0.75; x += 0.001)
      for (double y = 0.25; y <= 0.5; y += 0.001) n += a.contains({x, y}) && b.contains({x, y});
    return n;
  };
  EXPECT_GT(overlap(region(kIteRed), region("COLREGs Annex I (navigation lights)/red")), 0);
  EXPECT_GT(overlap(region(kIteYellow), region("COLREGs Annex I (navigation lights)/yellow")), 0);
  // 4. The lost minus signs were restored correctly: with "+ x" instead of "- x" the red
  //    and yellow regions hold no realisable colour at all.
  const auto flipped = [](solo::ChromaticityRegion r) {
    for (auto& q : r.inequalities) q.slope = -q.slope;
    return r;
  };
  EXPECT_EQ(realisableGridPoints(flipped(region(kIteRed))), 0);
  EXPECT_EQ(realisableGridPoints(flipped(region(kIteYellow))), 0);
  // 5. Green is the signal's blue-green: no white, no yellow-green.
  EXPECT_FALSE(region(kIteGreen).contains(solo::whiteE()));
  EXPECT_FALSE(region(kIteGreen).contains({0.3127, 0.3290}));
  EXPECT_FALSE(region(kIteGreen).contains(led(555, 30)));
}

TEST(IlluminantTable, InequalityParser) {
  const auto q = solo::parseChromaticityInequalities("0.411 <= y <= 0.452 ; y >= 0.506 - 0.519x; y <= 0.730 - x");
  ASSERT_EQ(q.size(), 4u);
  EXPECT_FALSE(q[0].y_at_most);
  EXPECT_DOUBLE_EQ(q[0].intercept, 0.411);
  EXPECT_TRUE(q[1].y_at_most);
  EXPECT_DOUBLE_EQ(q[2].slope, -0.519);
  EXPECT_DOUBLE_EQ(q[3].slope, -1.0);
  EXPECT_THROW(solo::parseChromaticityInequalities("x <= 0.3"), std::invalid_argument);
}

TEST(IlluminantTable, WriteReadRoundTripKeepsQuotedProvenance) {
  solo::test::TempDir dir;
  solo::IlluminantTable table;
  table.samples.push_back({solo::LightCategory::StreetLightLowCct, {0.52148, 0.41816}, "HPS, \"Main St\", 2024"});
  solo::writeIlluminantTable(dir / "t.csv", table);
  const auto read = solo::readIlluminantTable(dir / "t.csv");
  ASSERT_EQ(read.samples.size(), 1u);
  EXPECT_EQ(read.samples[0].category, solo::LightCategory::StreetLightLowCct);
  EXPECT_DOUBLE_EQ(read.samples[0].xy.x(), 0.52148);
  EXPECT_EQ(read.samples[0].source, "HPS, \"Main St\", 2024");
}

TEST(IlluminantTable, MalformedTablesNameTheFileAndLine) {
  solo::test::TempDir dir;
  const auto expectError = [&](const std::string& text, const std::string& message) {
    solo::test::writeText(dir / "t.csv", text);
    try {
      solo::readIlluminantTable(dir / "t.csv");
      ADD_FAILURE() << "no error for " << text;
    } catch (const solo::InputError& e) {
      EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
    }
  };
  expectError("category,x,y,source\nlamp_post,0.5,0.4,x\n", "t.csv: line 2: unknown light category \"lamp_post\"");
  expectError("category,x,y,source\nclock,0.7,0.4,x\n", "line 2: chromaticity");
  expectError("category,x,y,source\nclock,0.3,,x\n", "line 2: y is not a finite number");
  expectError("cat,x,y\n", "expected the header category,x,y,source");
}
