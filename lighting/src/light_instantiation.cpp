#include "solo/lighting/light_instantiation.h"

#include "solo/lighting/colorimetry.h"

#include <solo/core/srgb.h>

#include <Eigen/Dense>

#include <cmath>
#include <map>
#include <random>
#include <stdexcept>

namespace solo {

namespace {

/// splitmix64's finaliser: a bijective 64-bit mix.
std::uint64_t mix64(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

/// A seeded stream with portable uniform variates.
class Stream {
 public:
  Stream(std::uint64_t run_seed, std::uint64_t a, std::uint64_t b) : rng_(mix64(mix64(mix64(run_seed) ^ a) ^ b)) {}
  /// Uniform in [0, 1) from the top 53 bits.
  double uniform() { return static_cast<double>(rng_() >> 11) * 0x1.0p-53; }
  double uniform(double low, double high) { return low + (high - low) * uniform(); }
  /// Uniform integer in [0, n).
  int index(int n) { return std::min(n - 1, static_cast<int>(uniform() * n)); }

 private:
  std::mt19937_64 rng_;
};

constexpr std::uint64_t kGroupStream = 0x67726f7570ULL;  // "group"
constexpr std::uint64_t kRootStream = 0x726f6f74ULL;     // "root"

}  // namespace

const char* strengthUnitName(StrengthUnit unit) { return unit == StrengthUnit::FluxLm ? "lm" : "cd/m2"; }

StrengthUnit strengthUnitFromName(const std::string& name) {
  if (name == "lm") return StrengthUnit::FluxLm;
  if (name == "cd/m2") return StrengthUnit::LuminanceCdPerM2;
  throw std::invalid_argument("unknown strength unit \"" + name + "\" (cd/m2 or lm)");
}

StrengthInterval defaultStrength(LightCategory category) {
  using C = LightCategory;
  constexpr StrengthUnit L = StrengthUnit::LuminanceCdPerM2;
  constexpr StrengthUnit F = StrengthUnit::FluxLm;
  switch (category) {
    case C::WindowBuilding: return {5, 70, L};
    case C::WindowParked: return {1, 3, L};
    case C::WindowTransport: return {15, 30, L};
    case C::TrafficLightRed:
    case C::TrafficLightOrange:
    case C::TrafficLightGreen: return {6000, 25000, L};
    case C::StreetLightHighCct:
    case C::StreetLightLowCct: return {4000, 16000, F};
    case C::ParkedFront:
    case C::MovingFront: return {700, 1500, F};
    case C::ParkedRear:
    case C::MovingRear: return {12, 55, F};
    case C::Advertisement: return {100, 800, L};
    case C::Clock: return {50, 300, L};
    case C::Inferred: return {50, 500, L};
  }
  throw std::invalid_argument("light category out of range");
}

std::array<StrengthInterval, kLastLightCategory + 1> InstantiationOptions::defaultStrengths() {
  std::array<StrengthInterval, kLastLightCategory + 1> out{};
  for (int c = kFirstLightCategory; c <= kLastLightCategory; ++c) out[c] = defaultStrength(static_cast<LightCategory>(c));
  return out;
}

EmissionProfile emissionProfile(LightCategory c) {
  using C = LightCategory;
  if (c == C::ParkedFront || c == C::MovingFront || c == C::StreetLightHighCct || c == C::StreetLightLowCct)
    return EmissionProfile::CosineLobe;
  if (c == C::TrafficLightRed || c == C::TrafficLightOrange || c == C::TrafficLightGreen)
    return EmissionProfile::SignalBeam;
  return EmissionProfile::Uniform;
}

const char* emissionProfileName(EmissionProfile profile) {
  switch (profile) {
    case EmissionProfile::CosineLobe: return "cosine_lobe";
    case EmissionProfile::SignalBeam: return "signal_beam";
    case EmissionProfile::Uniform: break;
  }
  return "uniform";
}

double profileProjectedSolidAngle(EmissionProfile profile) {
  // Uniform: integral of cos over the hemisphere = pi. Lobe: g = cos(pi (mu - 1) / 2) =
  // sin(pi mu / 2), and 2 pi * integral_0^1 mu sin(pi mu / 2) d mu = 2 pi * 4 / pi^2 = 8 / pi.
  // Beam along the normal: 2 pi * integral_0^1 mu^k mu d mu = 2 pi / (k + 2).
  switch (profile) {
    case EmissionProfile::CosineLobe: return 8.0 / M_PI;
    case EmissionProfile::SignalBeam: return 2.0 * M_PI / (kSignalBeamExponent + 2.0);
    case EmissionProfile::Uniform: break;
  }
  return M_PI;
}

LightInstantiation instantiateLights(const LightGroupTree& tree, const IlluminantTable& table,
                                     const InstantiationOptions& options,
                                     const std::vector<std::optional<Eigen::Vector2d>>& inferred_xy) {
  LightInstantiation result;
  result.lights.resize(tree.lights.size());
  std::map<LightCategory, std::vector<IlluminantSample>> samples;
  for (int c = kFirstLightCategory; c <= kLastLightCategory; ++c)
    samples[static_cast<LightCategory>(c)] = table.samplesFor(static_cast<LightCategory>(c));

  if (options.ablation) {
    for (LightState& s : result.lights) {
      s.on = true;
      s.activation = 1;
      s.xy = whiteE();
      s.strength = options.ablation_luminance_cd_m2;
      s.unit = StrengthUnit::LuminanceCdPerM2;
      s.colour_source = "ablation: white E";
    }
    return result;
  }

  // One draw: activation, colour, strength of a category, from a stream.
  const auto draw = [&](Stream& stream, int group, int light, LightCategory category, const Light& example) {
    const ActivationBounds bounds =
        activationBounds(tree.groups[group].kind, category).value_or(ActivationBounds{1, 1});
    GroupDraw d;
    d.group = group;
    d.light = light;
    d.category = category;
    d.activation = stream.uniform(bounds.low, bounds.high);
    const std::vector<IlluminantSample>& options_xy = samples[category];
    if (category == LightCategory::Inferred) {
      const std::size_t index = static_cast<std::size_t>(example.id - 1);
      if (index < inferred_xy.size() && inferred_xy[index]) d.xy = *inferred_xy[index];
    } else if (!options_xy.empty()) {
      d.sample = stream.index(static_cast<int>(options_xy.size()));
      d.xy = options_xy[d.sample].xy;
    }
    const StrengthInterval& interval = options.strengths[static_cast<int>(category)];
    d.strength = stream.uniform(interval.low, interval.high);
    return d;
  };
  const auto apply = [&](const GroupDraw& d, Stream& stream, const Light& light) {
    LightState& s = result.lights[light.id - 1];
    const std::vector<IlluminantSample>& options_xy = samples[light.category];
    s.emits = light.category == LightCategory::Inferred || !options_xy.empty();
    s.activation = d.activation;
    s.xy = d.xy;
    s.strength = d.strength;
    s.unit = options.strengths[static_cast<int>(light.category)].unit;
    const bool trial = stream.uniform() < d.activation;  // drawn even when it cannot emit: streams stay aligned
    s.on = s.emits && trial;
    if (light.category == LightCategory::Inferred)
      s.colour_source = d.xy == whiteE() ? "white E (no day-image colour)" : "day image";
    else if (d.sample >= 0)
      s.colour_source = options_xy[d.sample].source;
    else
      s.colour_source = "no illuminant samples for " + std::string(lightCategoryName(light.category)) + ": never emits";
  };

  for (const LightGroup& group : tree.groups) {
    if (group.kind == LightGroupKind::Root) {
      for (int id : group.lights) {
        const Light& light = tree.lights[id - 1];
        Stream stream(options.seed, kRootStream,
                      (static_cast<std::uint64_t>(light.map_id) << 32) | static_cast<std::uint32_t>(light.component));
        const GroupDraw d = draw(stream, 0, id, light.category, light);
        result.draws.push_back(d);
        apply(d, stream, light);
      }
      continue;
    }
    Stream stream(options.seed, kGroupStream ^ static_cast<std::uint64_t>(group.kind),
                  static_cast<std::uint64_t>(static_cast<std::uint32_t>(group.source_id)));
    std::map<LightCategory, std::vector<int>> by_category;
    for (int id : group.lights) by_category[tree.lights[id - 1].category].push_back(id);
    for (const auto& [category, ids] : by_category) {
      const GroupDraw d = draw(stream, group.id, 0, category, tree.lights[ids.front() - 1]);
      result.draws.push_back(d);
      for (int id : ids) apply(d, stream, tree.lights[id - 1]);
    }
  }
  return result;
}

std::vector<std::optional<Eigen::Vector2d>> inferredChromaticities(const LightGroupTree& tree, const cv::Mat& day_image) {
  std::vector<std::optional<Eigen::Vector2d>> out(tree.lights.size());
  if (day_image.empty()) return out;
  CV_Assert(day_image.type() == CV_32FC3 && day_image.cols == tree.width && day_image.rows == tree.height);
  const Eigen::Matrix3d linear_srgb_to_xyz = xyzToLinearSrgb().inverse();
  const Eigen::Matrix3d d65_to_e = bradfordEToD65().inverse();
  for (std::size_t i = 0; i < tree.lights.size(); ++i) {
    const Light& light = tree.lights[i];
    if (light.category != LightCategory::Inferred) continue;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (const PixelRun& run : light.runs)
      for (int x = run.first_col; x <= run.last_col; ++x) {
        const cv::Vec3d rgb = day_image.at<cv::Vec3f>(run.row, x);  // decoded in double precision
        sum += Eigen::Vector3d(srgbToLinear(rgb[0]), srgbToLinear(rgb[1]), srgbToLinear(rgb[2]));
      }
    const Eigen::Vector3d xyz = d65_to_e * (linear_srgb_to_xyz * sum);
    if (xyz.sum() > 1e-9 && xyz.y() > 0) out[i] = chromaticity(xyz);
  }
  return out;
}

double emittedLuminance(const LightState& state, LightCategory category, double area_m2) {
  if (!state.on) return 0;
  if (state.unit == StrengthUnit::LuminanceCdPerM2) return state.strength;
  if (!(area_m2 > 0)) return 0;
  return state.strength / (area_m2 * profileProjectedSolidAngle(emissionProfile(category)));
}

}  // namespace solo
