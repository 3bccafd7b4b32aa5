// Probabilistic instantiation against the Uniform/Bernoulli model: statistics over many
// seeds with tolerances derived from the sample size, reproducibility, ablation.

#include <solo/lighting/light_instantiation.h>

#include "test_support.h"

#include <algorithm>
#include <cmath>
#include <map>

namespace {

using solo::LightCategory;

const std::filesystem::path kTable = std::filesystem::path(SOLO_PROJECT_DATA_DIR) / "illuminants" / "night_illuminants.csv";

constexpr int kFloors = 99, kWindowsPerFloor = 10;

/// 99 floors of 10 one-pixel windows each; optionally without the floor map (all root).
solo::LightGroupTree floorsTree(bool with_floors, bool with_car = false) {
  cv::Mat lights(kFloors + 2, 2 * kWindowsPerFloor, CV_32S, cv::Scalar(0));
  cv::Mat floors(lights.size(), CV_32S, cv::Scalar(0));
  cv::Mat instances(lights.size(), CV_32S, cv::Scalar(11));
  for (int f = 0; f < kFloors; ++f) {
    floors.row(f).setTo(f + 1);
    for (int k = 0; k < kWindowsPerFloor; ++k) lights.at<int>(f, 2 * k) = 1000 + f * kWindowsPerFloor + k + 1;
  }
  lights.at<int>(kFloors, 0) = 7001;  // two street lights and an advertisement at the root
  lights.at<int>(kFloors, 4) = 8001;
  lights.at<int>(kFloors, 8) = 13001;
  if (with_car) {
    instances.row(kFloors + 1).setTo(26001);
    lights.at<int>(kFloors + 1, 0) = 12001;
  }
  return solo::buildLightGroups(lights, instances, with_floors ? floors : cv::Mat(), "lights");
}

const solo::IlluminantTable& table() {
  static const solo::IlluminantTable t = solo::readIlluminantTable(kTable);
  return t;
}

solo::LightInstantiation run(const solo::LightGroupTree& tree, std::uint64_t seed, bool ablation = false) {
  solo::InstantiationOptions options;
  options.seed = seed;
  options.ablation = ablation;
  return solo::instantiateLights(tree, table(), options);
}

double mean(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x;
  return s / v.size();
}

double variance(const std::vector<double>& v) {
  const double m = mean(v);
  double s = 0;
  for (double x : v) s += (x - m) * (x - m);
  return s / (v.size() - 1);
}

}  // namespace

TEST(LightInstantiation, GroupDrawsFollowTheUniformBernoulliModelOverManySeeds) {
  const solo::LightGroupTree tree = floorsTree(true);
  ASSERT_EQ(tree.groups.size(), static_cast<std::size_t>(kFloors + 1));
  const int seeds = 200;
  std::vector<double> activations, residuals, strengths;
  std::map<int, int> sample_counts;
  for (int seed = 1; seed <= seeds; ++seed) {
    const solo::LightInstantiation result = run(tree, seed);
    for (const solo::GroupDraw& d : result.draws) {
      if (d.group == 0) continue;
      activations.push_back(d.activation);
      strengths.push_back(d.strength);
      ++sample_counts[d.sample];
      int on = 0;
      for (int id : tree.groups[d.group].lights) {
        const solo::LightState& s = result.lights[id - 1];
        on += s.on;
        // Lights of one group and category share every attribute but the switch.
        EXPECT_EQ(s.activation, d.activation);
        EXPECT_EQ(s.xy, d.xy);
        EXPECT_EQ(s.strength, d.strength);
      }
      residuals.push_back(on - kWindowsPerFloor * d.activation);
    }
  }
  const double n = activations.size();
  ASSERT_EQ(n, seeds * kFloors);
  // y ~ Uniform(0.3, 0.6): mean 0.45, sd 0.3 / sqrt(12); 4 standard errors.
  const double sd_y = 0.3 / std::sqrt(12.0);
  EXPECT_NEAR(mean(activations), 0.45, 4 * sd_y / std::sqrt(n));
  EXPECT_NEAR(std::sqrt(variance(activations)), sd_y, 4 * sd_y / std::sqrt(2 * n));
  EXPECT_GE(*std::min_element(activations.begin(), activations.end()), 0.3);
  EXPECT_LE(*std::max_element(activations.begin(), activations.end()), 0.6);
  // Kolmogorov-Smirnov against U(0.3, 0.6): D < 1.95 / sqrt(n) (0.1 % level).
  std::vector<double> sorted = activations;
  std::sort(sorted.begin(), sorted.end());
  double d_max = 0;
  for (std::size_t i = 0; i < sorted.size(); ++i) {
    const double cdf = (sorted[i] - 0.3) / 0.3;
    d_max = std::max({d_max, std::abs(cdf - i / n), std::abs(cdf - (i + 1) / n)});
  }
  EXPECT_LT(d_max, 1.95 / std::sqrt(n));
  // Given y, the count of lit windows is Binomial(10, y): K - 10 y has mean 0 and variance
  // 10 E[y (1 - y)] = 10 * 0.24.
  const double var_k = kWindowsPerFloor * 0.24;
  EXPECT_NEAR(mean(residuals), 0, 4 * std::sqrt(var_k / n));
  EXPECT_NEAR(variance(residuals), var_k, 4 * var_k * std::sqrt(2 / n) * 1.2);
  // Strength ~ Uniform(5, 70) cd/m2.
  EXPECT_NEAR(mean(strengths), 37.5, 4 * 65 / std::sqrt(12 * n));
  // Colour: uniform over the 8 window_building samples; chi-square, 7 dof, 0.1 % critical 24.32.
  const auto samples = table().samplesFor(LightCategory::WindowBuilding).size();
  ASSERT_EQ(sample_counts.size(), samples);
  double chi2 = 0;
  for (const auto& [index, count] : sample_counts) chi2 += std::pow(count - n / samples, 2) / (n / samples);
  EXPECT_LT(chi2, 24.32);
}

TEST(LightInstantiation, RootLightsDrawTheirOwn) {
  const solo::LightGroupTree tree = floorsTree(false);
  ASSERT_EQ(tree.groups.size(), 1u);
  std::vector<double> on;
  std::map<double, int> colours;
  for (int seed = 1; seed <= 20; ++seed) {
    const solo::LightInstantiation result = run(tree, seed);
    EXPECT_EQ(result.draws.size(), tree.lights.size()) << "one draw per root light";
    for (std::size_t i = 0; i < tree.lights.size(); ++i) {
      const auto category = tree.lights[i].category;
      if (category == LightCategory::WindowBuilding) {
        on.push_back(result.lights[i].on);
        ++colours[result.lights[i].xy.x()];
      } else if (category == LightCategory::Advertisement) {
        EXPECT_FALSE(result.lights[i].on) << "no illuminant samples: never emits";
        EXPECT_FALSE(result.lights[i].emits);
      } else {
        EXPECT_TRUE(result.lights[i].on) << "street lights: activation (1, 1)";
        EXPECT_EQ(result.lights[i].unit, solo::StrengthUnit::FluxLm);
      }
    }
  }
  // Bernoulli with E[y] = 0.45 per independent light.
  EXPECT_NEAR(mean(on), 0.45, 4 * std::sqrt(0.45 * 0.55 / on.size()));
  EXPECT_EQ(colours.size(), table().samplesFor(LightCategory::WindowBuilding).size()) << "every sample is drawn";
}

TEST(LightInstantiation, SameSeedSameLightsAndGroupsAreIndependentStreams) {
  const solo::LightGroupTree tree = floorsTree(true);
  const auto a = run(tree, 42), b = run(tree, 42), c = run(tree, 43);
  int differences = 0;
  for (std::size_t i = 0; i < tree.lights.size(); ++i) {
    EXPECT_EQ(a.lights[i].on, b.lights[i].on);
    EXPECT_EQ(a.lights[i].xy, b.lights[i].xy);
    EXPECT_EQ(a.lights[i].strength, b.lights[i].strength);
    differences += a.lights[i].strength != c.lights[i].strength;
  }
  EXPECT_GT(differences, static_cast<int>(tree.lights.size()) / 2);
  // A car added to the scene does not change any floor's draw.
  const solo::LightGroupTree with_car = floorsTree(true, true);
  const auto d = run(with_car, 42);
  for (std::size_t i = 0; i < tree.lights.size(); ++i)
    if (tree.lights[i].category == LightCategory::WindowBuilding) {
      ASSERT_EQ(with_car.lights[i].map_id, tree.lights[i].map_id);
      EXPECT_EQ(d.lights[i].strength, a.lights[i].strength);
      EXPECT_EQ(d.lights[i].on, a.lights[i].on);
    }
}

TEST(LightInstantiation, AblationSwitchesEverythingOnWhiteWithOneStrength) {
  const solo::LightGroupTree tree = floorsTree(true, true);
  const auto result = run(tree, 1, true);
  for (const solo::LightState& s : result.lights) {
    EXPECT_TRUE(s.on);
    EXPECT_DOUBLE_EQ(s.xy.x(), 1.0 / 3.0);
    EXPECT_DOUBLE_EQ(s.xy.y(), 1.0 / 3.0);
    EXPECT_DOUBLE_EQ(s.strength, 1000);
    EXPECT_EQ(s.unit, solo::StrengthUnit::LuminanceCdPerM2);
  }
}

TEST(LightInstantiation, EmittedLuminanceFromFluxUsesTheProfilesProjectedSolidAngle) {
  // Numerical check of the closed forms: integral of g(theta) cos(theta) d omega.
  double lobe = 0;
  const int steps = 200000;
  for (int i = 0; i < steps; ++i) {
    const double mu = (i + 0.5) / steps;
    lobe += 2 * M_PI * std::cos(M_PI * (mu - 1) / 2) * mu / steps;
  }
  EXPECT_NEAR(solo::profileProjectedSolidAngle(solo::EmissionProfile::CosineLobe), lobe, 1e-6);
  double beam = 0;
  for (int i = 0; i < steps; ++i) {
    const double mu = (i + 0.5) / steps;
    beam += 2 * M_PI * std::pow(mu, solo::kSignalBeamExponent) * mu / steps;
  }
  EXPECT_NEAR(solo::profileProjectedSolidAngle(solo::EmissionProfile::SignalBeam), beam, 1e-6);
  solo::LightState s;
  s.on = true;
  s.unit = solo::StrengthUnit::FluxLm;
  s.strength = 1000;
  EXPECT_NEAR(solo::emittedLuminance(s, LightCategory::MovingFront, 0.1), 1000 / (0.1 * 8 / M_PI), 1e-9);
  EXPECT_NEAR(solo::emittedLuminance(s, LightCategory::MovingRear, 0.1), 1000 / (0.1 * M_PI), 1e-9);
  s.unit = solo::StrengthUnit::LuminanceCdPerM2;
  EXPECT_DOUBLE_EQ(solo::emittedLuminance(s, LightCategory::WindowBuilding, 3), 1000);
  s.on = false;
  EXPECT_DOUBLE_EQ(solo::emittedLuminance(s, LightCategory::WindowBuilding, 3), 0);
}

TEST(LightInstantiation, InferredLightsTakeTheDayImageColour) {
  cv::Mat lights(4, 4, CV_32S, cv::Scalar(0));
  lights(cv::Rect(0, 0, 2, 2)).setTo(15001);
  const solo::LightGroupTree tree = solo::buildLightGroups(lights, cv::Mat(), cv::Mat(), "lights");
  cv::Mat day(4, 4, CV_32FC3, cv::Scalar(1, 1, 1));  // sRGB white = D65 white
  const auto xy = solo::inferredChromaticities(tree, day);
  ASSERT_TRUE(xy[0].has_value());
  // D65 white adapted to E by the inverse Bradford transform is E itself.
  EXPECT_NEAR(xy[0]->x(), 1.0 / 3.0, 2e-4);
  EXPECT_NEAR(xy[0]->y(), 1.0 / 3.0, 2e-4);
  solo::InstantiationOptions options;
  const std::vector<std::optional<Eigen::Vector2d>> day_colour = {Eigen::Vector2d(0.6, 0.35)};
  const auto result = solo::instantiateLights(tree, table(), options, day_colour);
  EXPECT_TRUE(result.lights[0].on);
  EXPECT_DOUBLE_EQ(result.lights[0].xy.x(), 0.6);
  EXPECT_EQ(result.lights[0].colour_source, "day image");
}

TEST(LightInstantiation, TrafficSignalsEmitABeamAndTheRestKeepTheirProfiles) {
  using C = LightCategory;
  for (const C c : {C::TrafficLightRed, C::TrafficLightOrange, C::TrafficLightGreen})
    EXPECT_EQ(solo::emissionProfile(c), solo::EmissionProfile::SignalBeam);
  for (const C c : {C::MovingFront, C::ParkedFront, C::StreetLightHighCct, C::StreetLightLowCct})
    EXPECT_EQ(solo::emissionProfile(c), solo::EmissionProfile::CosineLobe);
  for (const C c : {C::WindowBuilding, C::MovingRear, C::ParkedRear, C::Inferred})
    EXPECT_EQ(solo::emissionProfile(c), solo::EmissionProfile::Uniform);
  EXPECT_STREQ(solo::emissionProfileName(solo::EmissionProfile::SignalBeam), "signal_beam");
  // The exponent reproduces its source's factor, 0.678 at 10 degrees, and halves at 13.4.
  EXPECT_NEAR(std::pow(std::cos(10 * M_PI / 180), solo::kSignalBeamExponent), 0.678, 0.003);
  EXPECT_NEAR(std::pow(std::cos(13.4 * M_PI / 180), solo::kSignalBeamExponent), 0.5, 0.01);
  // A signal given as a flux spreads it over the beam's projected solid angle.
  solo::LightState s;
  s.on = true;
  s.unit = solo::StrengthUnit::FluxLm;
  s.strength = 10;
  EXPECT_NEAR(solo::emittedLuminance(s, C::TrafficLightRed, 0.05),
              10 / (0.05 * 2 * M_PI / (solo::kSignalBeamExponent + 2)), 1e-9);
}
