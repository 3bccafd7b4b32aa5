#include "commands.h"

#include <solo/core/error.h>
#include <solo/lighting/chromaticity_region.h>
#include <solo/lighting/colorimetry.h>
#include <solo/lighting/illuminant_recipe.h>
#include <solo/lighting/illuminant_table.h>
#include <solo/lighting/raw_gray_card.h>

#include <cstdio>
#include <iostream>
#include <stdexcept>

namespace fs = std::filesystem;

namespace solo::tools {

namespace {

ColorMatchingFunctions bundledColorMatchingFunctions() {
  return readColorMatchingFunctions(dataDirectory() / "colorimetry" / "cie1931_2deg_cmf_1nm.csv");
}

cv::Rect parseRegion(const std::string& text) {
  int x = 0, y = 0, w = 0, h = 0;
  char tail = 0;
  if (std::sscanf(text.c_str(), "%d,%d,%d,%d%c", &x, &y, &w, &h, &tail) != 4 || w <= 0 || h <= 0 || x < 0 || y < 0)
    throw InputError("--roi", "expected X,Y,WIDTH,HEIGHT in pixels (positive size), got \"" + text + "\"");
  return {x, y, w, h};
}

}  // namespace

int runIlluminantAdd(const IlluminantAddOptions& o) {
  const int given = (o.spectrum ? 1 : 0) + (o.cct_K ? 1 : 0) + (o.raw ? 1 : 0);
  if (given != 1) throw InputError("solo illuminant add", "give exactly one of --spectrum, --cct, --raw");
  IlluminantSample sample;
  try {
    sample.category = lightCategoryFromName(o.category);
  } catch (const std::invalid_argument& e) {
    throw InputError("--category", e.what());
  }
  const ColorMatchingFunctions cmf = bundledColorMatchingFunctions();
  std::string provenance;
  if (o.spectrum) {
    const DerivedChromaticity d = chromaticityFromSpectrumFile(*o.spectrum, cmf);
    sample.xy = d.xy;
    provenance = d.provenance;
  } else if (o.cct_K) {
    const DerivedChromaticity d = chromaticityFromTemperature(*o.cct_K, cmf);
    sample.xy = d.xy;
    provenance = d.provenance;
  } else {
    if (!o.roi) throw InputError("--raw", "a gray-card photo needs --roi X,Y,WIDTH,HEIGHT");
    const GrayCardMeasurement m = measureGrayCard(*o.raw, parseRegion(*o.roi));
    sample.xy = m.xy;
    provenance = o.raw->filename().string() + ": gray card, " + std::to_string(m.pixels) + " px at " + *o.roi + ", " +
                 m.camera + ", camera RGB -> XYZ with the file's colour matrix";
    if (m.clipped > 0)
      std::cerr << "solo: warning: " << m.clipped << " of " << m.pixels
                << " pixels in the region are saturated: the chromaticity is biased\n";
  }
  validateChromaticity(sample.xy, o.table, "new sample: ");
  sample.source = o.source.empty() ? provenance : o.source + " [" + provenance + "]";
  IlluminantTable table;
  if (fs::exists(o.table)) table = readIlluminantTable(o.table);
  table.samples.push_back(sample);
  writeIlluminantTable(o.table, table);
  const CorrelatedColourTemperature cct = correlatedColourTemperature(sample.xy, cmf);
  std::printf("%s: x %.5f y %.5f (CCT %.0f K, Duv %+.4f) added to %s (%zu samples for this category)\n",
              lightCategoryName(sample.category), sample.xy.x(), sample.xy.y(), cct.cct_K, cct.duv,
              o.table.string().c_str(), table.samplesFor(sample.category).size());
  return 0;
}

int runIlluminantRegenerate(const IlluminantRegenerateOptions& o) {
  const fs::path recipe = o.recipe ? *o.recipe : dataDirectory() / "illuminants" / "recipe.csv";
  const fs::path regions_file = o.regions ? *o.regions : recipe.parent_path() / "signal_light_chromaticity_regions.csv";
  const IlluminantTable table =
      buildIlluminantTable(recipe, bundledColorMatchingFunctions(), readChromaticityRegions(regions_file));
  writeIlluminantTable(o.output, table);
  std::printf("%zu samples from %s written to %s\n", table.samples.size(), recipe.string().c_str(),
              o.output.string().c_str());
  for (int c = kFirstLightCategory; c <= kLastLightCategory; ++c) {
    const std::size_t n = table.samplesFor(static_cast<LightCategory>(c)).size();
    std::printf("  %-22s %zu\n", lightCategoryName(static_cast<LightCategory>(c)), n);
  }
  return 0;
}

}  // namespace solo::tools
