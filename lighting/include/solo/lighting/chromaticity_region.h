#pragma once
// The chromaticity regions that lighting standards allow for signal lamps (SAE J578 vehicle
// lamps, ITE traffic signals, COLREGs navigation lights), read from
// data/illuminants/signal_light_chromaticity_regions.csv. A region is either a polygon in
// CIE 1931 xy or a set of linear inequalities "y <= a + b x" / "y >= a + b x".

#include <Eigen/Core>

#include <filesystem>
#include <string>
#include <vector>

namespace solo {

/// y (<= or >=) intercept + slope * x.
struct ChromaticityInequality {
  bool y_at_most = true;  ///< true: y <= rhs; false: y >= rhs
  double intercept = 0;
  double slope = 0;
  bool holds(const Eigen::Vector2d& xy) const;
};

struct ChromaticityRegion {
  std::string standard;  ///< "SAE J578 (2020)"
  std::string colour;    ///< "red (tail/stop)"
  std::string source;    ///< where the numbers were read
  std::vector<Eigen::Vector2d> polygon;             ///< non-empty for polygon regions
  std::vector<ChromaticityInequality> inequalities;  ///< non-empty for inequality regions
  /// "standard/colour", the key recipes use.
  std::string key() const { return standard + "/" + colour; }
  bool contains(const Eigen::Vector2d& xy) const;
};

/// Parses inequalities such as "y <= 0.308 ; y >= 0.998 - x ; 0.411 <= y <= 0.452 ;
/// y >= 0.506 - 0.519x". Throws std::invalid_argument describing the first bad term.
std::vector<ChromaticityInequality> parseChromaticityInequalities(const std::string& text);

/// Reads the regions table (standard, colour, kind, values_cie1931_xy, source_as_read).
/// Throws InputError naming the file and line for a malformed row.
std::vector<ChromaticityRegion> readChromaticityRegions(const std::filesystem::path& file);

/// The region with this key, or throws InputError(file, "no region ...").
const ChromaticityRegion& findRegion(const std::vector<ChromaticityRegion>& regions, const std::string& key,
                                     const std::filesystem::path& file);

}  // namespace solo
