#include "solo/lighting/illuminant_recipe.h"

#include "csv.h"

#include <solo/core/error.h>

#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace solo {

namespace {

std::string formatCct(const CorrelatedColourTemperature& cct) {
  char text[96];
  std::snprintf(text, sizeof text, "CCT %.0f K, Duv %+.4f", cct.cct_K, cct.duv);
  return text;
}

}  // namespace

DerivedChromaticity chromaticityFromSpectrumFile(const std::filesystem::path& spectrum_file,
                                                 const ColorMatchingFunctions& cmf) {
  DerivedChromaticity d;
  d.xy = chromaticity(tristimulus(readSpectrumCsv(spectrum_file), cmf));
  d.cct = correlatedColourTemperature(d.xy, cmf);
  d.provenance = spectrum_file.filename().string() + ": SPD x CIE 1931 2-deg CMF, " + formatCct(d.cct);
  return d;
}

DerivedChromaticity chromaticityFromTemperature(double temperature_K, const ColorMatchingFunctions& cmf,
                                                const std::string& source) {
  if (!(temperature_K >= 500 && temperature_K <= 100000))
    throw InputError(source, "colour temperature " + std::to_string(temperature_K) + " K is outside 500..100000 K");
  DerivedChromaticity d;
  d.xy = planckianChromaticity(temperature_K, cmf);
  d.cct = {temperature_K, 0};
  char text[96];
  std::snprintf(text, sizeof text, "Planckian radiator at %.0f K (c2 = 1.4388e-2 m K) x CIE 1931 2-deg CMF", temperature_K);
  d.provenance = text;
  return d;
}

IlluminantTable buildIlluminantTable(const std::filesystem::path& recipe_file, const ColorMatchingFunctions& cmf,
                                     const std::vector<ChromaticityRegion>& regions) {
  std::vector<csv::Line> lines = csv::readLines(recipe_file);
  if (lines.empty() || lines.front().fields.size() != 5 || csv::trim(lines.front().fields[0]) != "category")
    throw InputError(recipe_file, "expected the header category,kind,parameter,region,description");
  lines.erase(lines.begin());
  const std::filesystem::path folder = recipe_file.parent_path();
  IlluminantTable table;
  for (const csv::Line& line : lines) {
    const std::string where = "line " + std::to_string(line.number) + ": ";
    if (line.fields.size() != 5) throw InputError(recipe_file, where + "expected 5 columns");
    IlluminantSample sample;
    try {
      sample.category = lightCategoryFromName(csv::trim(line.fields[0]));
    } catch (const std::invalid_argument& e) {
      throw InputError(recipe_file, where + e.what());
    }
    const std::string kind = csv::trim(line.fields[1]);
    const std::string parameter = csv::trim(line.fields[2]);
    const std::string region_key = csv::trim(line.fields[3]);
    const std::string description = csv::trim(line.fields[4]);
    DerivedChromaticity derived;
    if (kind == "spectrum") {
      derived = chromaticityFromSpectrumFile(folder / parameter, cmf);
    } else if (kind == "planck") {
      derived = chromaticityFromTemperature(csv::number(recipe_file, line, 2, "temperature"), cmf,
                                            recipe_file.string() + ":" + std::to_string(line.number));
    } else if (kind == "led") {
      double peak = 0, fwhm = 0;
      const auto slash = parameter.find('/');
      if (slash == std::string::npos || !csv::parseNumber(parameter.substr(0, slash), peak) ||
          !csv::parseNumber(parameter.substr(slash + 1), fwhm) || peak < 380 || peak > 780 || fwhm <= 0 || fwhm > 200)
        throw InputError(recipe_file, where + "an led parameter is \"peak_nm/fwhm_nm\" (380-780 nm, width 0-200 nm)");
      derived.xy = chromaticity(tristimulus(gaussianLedSpectrum(peak, fwhm), cmf));
      char text[128];
      std::snprintf(text, sizeof text, "Gaussian LED spectrum, peak %.0f nm, FWHM %.0f nm, x CIE 1931 2-deg CMF", peak, fwhm);
      derived.provenance = text;
    } else {
      throw InputError(recipe_file, where + "unknown kind \"" + kind + "\" (spectrum, planck or led)");
    }
    std::string provenance = description + " [" + derived.provenance;
    if (!region_key.empty()) {
      const ChromaticityRegion& region = findRegion(regions, region_key, recipe_file);
      if (!region.contains(derived.xy)) {
        char xy[64];
        std::snprintf(xy, sizeof xy, "(%.4f, %.4f)", derived.xy.x(), derived.xy.y());
        throw InputError(recipe_file, where + "xy " + xy + " lies outside the region " + region_key);
      }
      provenance += "; inside " + region_key;
    }
    sample.xy = derived.xy;
    sample.source = provenance + "]";
    table.samples.push_back(std::move(sample));
  }
  return table;
}

}  // namespace solo
