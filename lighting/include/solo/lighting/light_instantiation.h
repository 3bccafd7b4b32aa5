#pragma once
// Probabilistic light instantiation (reference section 1 step 7, bounds of section 3).
// Per group and light category: activation probability y ~ Uniform(a, b), one chromaticity
// drawn uniformly from the category's illuminant samples, one strength ~ Uniform(interval);
// every light of the group and category then switches on with X ~ Bernoulli(y). Root lights
// draw their own. Each group (and each root light) draws from its own std::mt19937_64
// stream seeded from the run seed and the group's identity, so adding or removing a group
// does not change the others. Uniform variates use the top 53 bits of the generator (not
// std::uniform_real_distribution, whose output differs between standard libraries), so
// a seed gives the same lights on every platform.
//
// Strengths are physical (docs/lighting.md): the luminance of the emitting surface in
// cd/m^2 for extended sources whose mask is the emitting surface (windows, traffic-light
// lenses, advertisements, clocks, inferred lights), the luminous flux in lm for compact
// lamps that the renderer models (street lights, vehicle front and rear lamps).
// Categories without illuminant samples (advertisement and clock in the bundled table)
// never emit, as in the reference; inferred lights take the colour of the day image.

#include "solo/lighting/illuminant_table.h"
#include "solo/lighting/light_groups.h"

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace solo {

enum class StrengthUnit { LuminanceCdPerM2, FluxLm };
/// "cd/m2" or "lm".
const char* strengthUnitName(StrengthUnit unit);
/// Inverse; throws std::invalid_argument.
StrengthUnit strengthUnitFromName(const std::string& name);

struct StrengthInterval {
  double low = 0, high = 0;
  StrengthUnit unit = StrengthUnit::LuminanceCdPerM2;
};
/// Default interval per category (docs/lighting.md gives the derivation of each).
StrengthInterval defaultStrength(LightCategory category);

/// Angular emission profile: front lights and street lights carry the reference's
/// g(v, n) = cos(pi (|v.n| - 1) / 2); traffic signals a beam toward the camera,
/// g = max(0, v.a)^kSignalBeamExponent with a the unit direction from the emitting point to
/// the camera (a signal the image shows lit faces the camera; its lens and visor send its light
/// down the road, not onto the walls beside it); every other light emits uniformly (Lambertian).
enum class EmissionProfile { Uniform, CosineLobe, SignalBeam };
EmissionProfile emissionProfile(LightCategory category);
/// "uniform", "cosine_lobe" or "signal_beam".
const char* emissionProfileName(EmissionProfile profile);
/// The signal beam's exponent k: cos^k falls to 0.678 at 10 degrees off the axis, the horizontal
/// intensity factor of ITE's LED circular signal supplement (VTCSH-LED, 2005, section 4.1.1.4),
/// and to half at 13.4 degrees.
constexpr double kSignalBeamExponent = 25.2;
/// Flux per unit area and unit normal luminance: integral of g(theta) cos(theta) over the
/// hemisphere: pi for Uniform, 8 / pi for CosineLobe, 2 pi / (k + 2) for SignalBeam with the
/// camera along the normal (sr).
double profileProjectedSolidAngle(EmissionProfile profile);

struct InstantiationOptions {
  std::uint64_t seed = 0;
  /// The paper's ablation: every light on, white (E, xy = 1/3, 1/3), one strength.
  bool ablation = false;
  double ablation_luminance_cd_m2 = 1000;  ///< the one strength of the ablation, cd/m^2
  std::array<StrengthInterval, kLastLightCategory + 1> strengths = defaultStrengths();

  static std::array<StrengthInterval, kLastLightCategory + 1> defaultStrengths();
};

/// What one light became.
struct LightState {
  bool on = false;
  bool emits = true;        ///< false: the category has no illuminant samples (never on)
  double activation = 0;    ///< the y its Bernoulli trial used
  Eigen::Vector2d xy{1.0 / 3.0, 1.0 / 3.0};  ///< CIE 1931, relative to white E
  double strength = 0;
  StrengthUnit unit = StrengthUnit::LuminanceCdPerM2;
  std::string colour_source;  ///< the illuminant sample's provenance, "day image", "ablation: white E"
};

/// One draw shared by a group's lights of one category (the root's lights draw their own
/// and are listed with group 0).
struct GroupDraw {
  int group = 0;
  int light = 0;  ///< the root light this draw belongs to; 0 for a group draw
  LightCategory category = LightCategory::WindowBuilding;
  double activation = 0;
  int sample = -1;  ///< index into the category's samples; -1 = not from the table
  Eigen::Vector2d xy{1.0 / 3.0, 1.0 / 3.0};
  double strength = 0;
};

struct LightInstantiation {
  std::vector<LightState> lights;  ///< per tree.lights
  std::vector<GroupDraw> draws;
};

/// Instantiates every light of the tree. `inferred_xy` (per tree.lights, may be empty)
/// gives the colour of inferred lights; without it they are white E.
LightInstantiation instantiateLights(const LightGroupTree& tree, const IlluminantTable& table,
                                     const InstantiationOptions& options,
                                     const std::vector<std::optional<Eigen::Vector2d>>& inferred_xy = {});

/// Colour of each inferred light from the day image (CV_32FC3 sRGB-encoded RGB at the
/// tree's resolution): mean linear sRGB of its pixels -> XYZ (D65) -> Bradford to white E
/// -> xy, so the post-process's E -> D65 adaptation gives back the day colour. nullopt for
/// other categories and for black pixels.
std::vector<std::optional<Eigen::Vector2d>> inferredChromaticities(const LightGroupTree& tree, const cv::Mat& day_image);

/// Normal luminance the renderer emits, cd/m^2: the strength itself for luminances; for a
/// flux, flux / (area * profileProjectedSolidAngle). 0 for lights that are off or have
/// no area.
double emittedLuminance(const LightState& state, LightCategory category, double area_m2);

}  // namespace solo
