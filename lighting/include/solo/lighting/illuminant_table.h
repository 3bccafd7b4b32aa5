#pragma once
// The night-illuminant table: CIE 1931 xy chromaticity samples per light category, each
// with its provenance. CSV with the header "category,x,y,source"; the bundled table is
// data/illuminants/night_illuminants.csv (docs/lighting.md).

#include "solo/lighting/light_category.h"

#include <Eigen/Core>

#include <filesystem>
#include <string>
#include <vector>

namespace solo {

struct IlluminantSample {
  LightCategory category = LightCategory::WindowBuilding;
  Eigen::Vector2d xy{1.0 / 3.0, 1.0 / 3.0};  ///< CIE 1931 2-degree chromaticity
  std::string source;                        ///< provenance: spectrum, CCT, standard, photo
};

struct IlluminantTable {
  std::vector<IlluminantSample> samples;
  /// The samples of one category, in table order.
  std::vector<IlluminantSample> samplesFor(LightCategory category) const;
};

/// Reads a table. Throws InputError naming the file and line for a wrong header, an
/// unknown category, a non-numeric value or an impossible chromaticity (x < 0, y <= 0,
/// x + y > 1).
IlluminantTable readIlluminantTable(const std::filesystem::path& file);

/// The table as CSV text (5 decimals), rows in the given order.
std::string illuminantTableCsv(const IlluminantTable& table);
/// Writes it atomically.
void writeIlluminantTable(const std::filesystem::path& file, const IlluminantTable& table);

/// Throws InputError(source, ...) unless xy is a possible chromaticity (see above).
void validateChromaticity(const Eigen::Vector2d& xy, const std::filesystem::path& source, const std::string& where);

}  // namespace solo
