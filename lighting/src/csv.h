#pragma once
// Internal: the small CSV dialect of solo's data tables. Fields are separated by commas;
// a field may be double-quoted (a doubled quote inside stands for one quote). Lines that
// are empty or start with '#' are comments.

#include <solo/core/error.h>
#include <solo/core/input_file.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace solo::csv {

struct Line {
  int number = 0;  ///< 1-based line number in the file
  std::vector<std::string> fields;
};

/// Splits one line into fields, undoing the quoting.
inline std::vector<std::string> splitLine(const std::string& line) {
  std::vector<std::string> fields(1);
  bool quoted = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted) {
      if (c == '"' && i + 1 < line.size() && line[i + 1] == '"') {
        fields.back() += '"';
        ++i;
      } else if (c == '"') {
        quoted = false;
      } else {
        fields.back() += c;
      }
    } else if (c == '"') {
      quoted = true;
    } else if (c == ',') {
      fields.emplace_back();
    } else if (c != '\r') {
      fields.back() += c;
    }
  }
  return fields;
}

/// Quotes a field when it holds a comma, a quote or leading/trailing blanks.
inline std::string quote(const std::string& field) {
  if (field.find_first_of(",\"") == std::string::npos && (field.empty() || (field.front() != ' ' && field.back() != ' ')))
    return field;
  std::string out = "\"";
  for (char c : field) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

/// Every non-comment line of a file. Throws InputError when the file cannot be opened.
inline std::vector<Line> readLines(const std::filesystem::path& file) {
  requireRegularFile(file, "table");
  std::ifstream in(file);
  if (!in) throw InputError(file, "cannot be opened");
  std::vector<Line> lines;
  std::string text;
  int number = 0;
  while (std::getline(in, text)) {
    ++number;
    const auto first = text.find_first_not_of(" \t\r");
    if (first == std::string::npos || text[first] == '#') continue;
    lines.push_back({number, splitLine(text)});
  }
  return lines;
}

/// A finite number, or nullopt-like false when the field is not one.
inline bool parseNumber(const std::string& field, double& value) {
  const auto first = field.find_first_not_of(" \t");
  if (first == std::string::npos) return false;
  const char* begin = field.c_str() + first;
  char* end = nullptr;
  value = std::strtod(begin, &end);
  if (end == begin) return false;
  while (*end == ' ' || *end == '\t') ++end;
  return *end == '\0' && std::isfinite(value);
}

/// parseNumber or an InputError naming the file, line and column.
inline double number(const std::filesystem::path& file, const Line& line, std::size_t column, const char* what) {
  double value = 0;
  if (column >= line.fields.size() || !parseNumber(line.fields[column], value))
    throw InputError(file, "line " + std::to_string(line.number) + ": " + what + " is not a finite number" +
                               (column < line.fields.size() ? " (\"" + line.fields[column] + "\")" : std::string()));
  return value;
}

/// Trimmed copy.
inline std::string trim(const std::string& s) {
  const auto first = s.find_first_not_of(" \t");
  if (first == std::string::npos) return {};
  return s.substr(first, s.find_last_not_of(" \t") - first + 1);
}

}  // namespace solo::csv
