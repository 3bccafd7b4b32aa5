#include "solo/lighting/chromaticity_region.h"

#include "csv.h"

#include <solo/core/error.h>
#include <solo/lighting/colorimetry.h>

#include <sstream>
#include <stdexcept>

namespace solo {

namespace {

/// Removes blanks.
std::string compact(const std::string& s) {
  std::string out;
  for (char c : s)
    if (c != ' ' && c != '\t') out += c;
  return out;
}

/// "a", "a+bx", "a-bx", "a-x", "a+x" -> (a, b).
void parseLinear(const std::string& text, double& intercept, double& slope) {
  std::size_t split = std::string::npos;
  for (std::size_t i = 1; i < text.size(); ++i)
    if ((text[i] == '+' || text[i] == '-') && text[i - 1] != 'e' && text[i - 1] != 'E') split = i;
  if (!csv::parseNumber(split == std::string::npos ? text : text.substr(0, split), intercept))
    throw std::invalid_argument("cannot read \"" + text + "\" as a + b x");
  slope = 0;
  if (split == std::string::npos) return;
  std::string term = text.substr(split);
  if (term.empty() || term.back() != 'x') throw std::invalid_argument("cannot read \"" + text + "\" as a + b x");
  term.pop_back();
  if (term == "+" || term == "-") {
    slope = term == "+" ? 1 : -1;
  } else if (!csv::parseNumber(term, slope)) {
    throw std::invalid_argument("cannot read the slope in \"" + text + "\"");
  }
}

}  // namespace

bool ChromaticityInequality::holds(const Eigen::Vector2d& xy) const {
  const double rhs = intercept + slope * xy.x();
  return y_at_most ? xy.y() <= rhs + 1e-12 : xy.y() >= rhs - 1e-12;
}

bool ChromaticityRegion::contains(const Eigen::Vector2d& xy) const {
  if (!polygon.empty()) return insidePolygon(xy, polygon);
  for (const ChromaticityInequality& q : inequalities)
    if (!q.holds(xy)) return false;
  return !inequalities.empty();
}

std::vector<ChromaticityInequality> parseChromaticityInequalities(const std::string& text) {
  std::vector<ChromaticityInequality> out;
  std::stringstream stream(text);
  std::string term;
  while (std::getline(stream, term, ';')) {
    term = compact(term);
    if (term.empty()) continue;
    // "L<=y<=U": two inequalities.
    const auto first = term.find("<=y<=");
    if (first != std::string::npos) {
      ChromaticityInequality lower{false, 0, 0}, upper{true, 0, 0};
      if (!csv::parseNumber(term.substr(0, first), lower.intercept) ||
          !csv::parseNumber(term.substr(first + 5), upper.intercept))
        throw std::invalid_argument("cannot read \"" + term + "\"");
      out.push_back(lower);
      out.push_back(upper);
      continue;
    }
    ChromaticityInequality q;
    if (term.rfind("y<=", 0) == 0) {
      q.y_at_most = true;
    } else if (term.rfind("y>=", 0) == 0) {
      q.y_at_most = false;
    } else {
      throw std::invalid_argument("expected \"y <= ...\", \"y >= ...\" or \"a <= y <= b\", got \"" + term + "\"");
    }
    parseLinear(term.substr(3), q.intercept, q.slope);
    out.push_back(q);
  }
  if (out.empty()) throw std::invalid_argument("no inequality");
  return out;
}

std::vector<ChromaticityRegion> readChromaticityRegions(const std::filesystem::path& file) {
  std::vector<csv::Line> lines = csv::readLines(file);
  if (lines.empty() || lines.front().fields.empty() || csv::trim(lines.front().fields[0]) != "standard")
    throw InputError(file, "expected the header standard,colour,kind,values_cie1931_xy,source_as_read");
  lines.erase(lines.begin());
  std::vector<ChromaticityRegion> regions;
  for (const csv::Line& line : lines) {
    const std::string where = "line " + std::to_string(line.number) + ": ";
    if (line.fields.size() != 5) throw InputError(file, where + "expected 5 columns");
    ChromaticityRegion r;
    r.standard = csv::trim(line.fields[0]);
    r.colour = csv::trim(line.fields[1]);
    r.source = csv::trim(line.fields[4]);
    const std::string kind = csv::trim(line.fields[2]);
    const std::string values = line.fields[3];
    if (kind == "polygon vertices") {
      std::string text = values;
      for (char& c : text)
        if (c == '(' || c == ')' || c == ',') c = ' ';
      std::stringstream stream(text);
      double x = 0, y = 0;
      while (stream >> x >> y) r.polygon.emplace_back(x, y);
      if (r.polygon.size() < 3 || !stream.eof()) throw InputError(file, where + "expected at least 3 (x,y) vertices");
    } else if (kind == "boundary inequalities") {
      try {
        r.inequalities = parseChromaticityInequalities(values);
      } catch (const std::invalid_argument& e) {
        throw InputError(file, where + e.what());
      }
    } else {
      throw InputError(file, where + "unknown region kind \"" + kind + "\"");
    }
    regions.push_back(std::move(r));
  }
  return regions;
}

const ChromaticityRegion& findRegion(const std::vector<ChromaticityRegion>& regions, const std::string& key,
                                     const std::filesystem::path& file) {
  for (const ChromaticityRegion& r : regions)
    if (r.key() == key) return r;
  throw InputError(file, "no chromaticity region \"" + key + "\"");
}

}  // namespace solo
