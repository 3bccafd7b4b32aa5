#pragma once
// Regenerates the night-illuminant table from a recipe, so the bundled table is reproducible:
// every row of the recipe names a category and how its chromaticity follows from physics
// (a lamp spectrum integrated against the CIE 1931 colour matching functions, a Planckian
// colour temperature, or a narrow-band LED modelled as a Gaussian spectrum) and, for signal
// lamps, the standard's chromaticity region the result must lie in.
//
// Recipe CSV header: category,kind,parameter,region,description
//   kind "spectrum": parameter = spectrum CSV, relative to the recipe's folder
//   kind "planck":   parameter = colour temperature in kelvin
//   kind "led":      parameter = "peak_nm/fwhm_nm"
//   region: "" or a key "standard/colour" of the regions table

#include "solo/lighting/chromaticity_region.h"
#include "solo/lighting/colorimetry.h"
#include "solo/lighting/illuminant_table.h"

#include <filesystem>
#include <string>
#include <vector>

namespace solo {

/// The chromaticity of one recipe row's light and a provenance text for the table.
struct DerivedChromaticity {
  Eigen::Vector2d xy;
  CorrelatedColourTemperature cct;
  std::string provenance;
};

/// Chromaticity of a spectrum file, with its provenance ("<file name>: xy from its SPD x CIE 1931 2-deg CMF, CCT ...").
DerivedChromaticity chromaticityFromSpectrumFile(const std::filesystem::path& spectrum_file,
                                                 const ColorMatchingFunctions& cmf);
/// Chromaticity of a black body at `temperature_K` (must be 500..100000 K, else InputError on `source`).
DerivedChromaticity chromaticityFromTemperature(double temperature_K, const ColorMatchingFunctions& cmf,
                                                const std::string& source = "--cct");

/// Builds the table row by row. Throws InputError naming the recipe and line for a bad
/// row, a spectrum that cannot be read, an unknown region, or a sample outside its region.
IlluminantTable buildIlluminantTable(const std::filesystem::path& recipe_file, const ColorMatchingFunctions& cmf,
                                     const std::vector<ChromaticityRegion>& regions);

}  // namespace solo
