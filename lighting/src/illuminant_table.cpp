#include "solo/lighting/illuminant_table.h"

#include "csv.h"

#include <solo/core/atomic_file.h>
#include <solo/core/error.h>

#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace solo {

std::vector<IlluminantSample> IlluminantTable::samplesFor(LightCategory category) const {
  std::vector<IlluminantSample> out;
  for (const IlluminantSample& s : samples)
    if (s.category == category) out.push_back(s);
  return out;
}

void validateChromaticity(const Eigen::Vector2d& xy, const std::filesystem::path& source, const std::string& where) {
  if (!std::isfinite(xy.x()) || !std::isfinite(xy.y()) || xy.x() < 0 || xy.y() <= 0 || xy.x() + xy.y() > 1)
    throw InputError(source, where + "chromaticity (" + std::to_string(xy.x()) + ", " + std::to_string(xy.y()) +
                                 ") is impossible (need x >= 0, y > 0, x + y <= 1)");
}

IlluminantTable readIlluminantTable(const std::filesystem::path& file) {
  std::vector<csv::Line> lines = csv::readLines(file);
  const std::vector<std::string> header = {"category", "x", "y", "source"};
  if (lines.empty() || lines.front().fields.size() != 4 || csv::trim(lines.front().fields[0]) != header[0] ||
      csv::trim(lines.front().fields[1]) != header[1] || csv::trim(lines.front().fields[2]) != header[2] ||
      csv::trim(lines.front().fields[3]) != header[3])
    throw InputError(file, "expected the header category,x,y,source");
  lines.erase(lines.begin());
  IlluminantTable table;
  for (const csv::Line& line : lines) {
    const std::string where = "line " + std::to_string(line.number) + ": ";
    if (line.fields.size() != 4)
      throw InputError(file, where + "expected 4 columns, got " + std::to_string(line.fields.size()));
    IlluminantSample s;
    try {
      s.category = lightCategoryFromName(csv::trim(line.fields[0]));
    } catch (const std::invalid_argument& e) {
      throw InputError(file, where + e.what());
    }
    s.xy = {csv::number(file, line, 1, "x"), csv::number(file, line, 2, "y")};
    validateChromaticity(s.xy, file, where);
    s.source = csv::trim(line.fields[3]);
    table.samples.push_back(std::move(s));
  }
  return table;
}

std::string illuminantTableCsv(const IlluminantTable& table) {
  std::string text = "category,x,y,source\n";
  char number[64];
  for (const IlluminantSample& s : table.samples) {
    std::snprintf(number, sizeof number, ",%.5f,%.5f,", s.xy.x(), s.xy.y());
    text += lightCategoryName(s.category) + std::string(number) + csv::quote(s.source) + "\n";
  }
  return text;
}

void writeIlluminantTable(const std::filesystem::path& file, const IlluminantTable& table) {
  writeTextAtomically(file, illuminantTableCsv(table));
}

}  // namespace solo
