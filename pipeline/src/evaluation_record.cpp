// The CSV form of an evaluation record and its append rule.

#include <solo/pipeline/evaluation_record.h>

#include <solo/core/error.h>

#include <fcntl.h>
#include <unistd.h>
#include <cerrno>
#include <charconv>
#include <cstring>
#include <fstream>

namespace fs = std::filesystem;

namespace solo {
namespace {

std::string csvCell(const EvaluationValue& v) {
  if (std::holds_alternative<std::monostate>(v)) return "";
  if (const bool* b = std::get_if<bool>(&v)) return *b ? "true" : "false";
  if (const std::int64_t* i = std::get_if<std::int64_t>(&v)) return std::to_string(*i);
  if (const double* d = std::get_if<double>(&v)) {
    char text[32];  // shortest text that reads back as the same double
    const auto result = std::to_chars(text, text + sizeof text, *d);
    return std::string(text, result.ptr);
  }
  const std::string& s = std::get<std::string>(v);
  if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
  std::string quoted = "\"";
  for (const char c : s) quoted += c == '"' ? std::string("\"\"") : std::string(1, c);
  return quoted + "\"";
}

/// The header (keys) or the row (cells) of the record's fields.
std::string csvLine(const EvaluationRecord& r, bool header) {
  std::string line;
  bool first = true;
  for (const std::vector<EvaluationField>* fields : {&r.inputs, &r.options, &r.metrics})
    for (const EvaluationField& f : *fields) {
      if (!first) line += ",";
      first = false;
      line += header ? f.key : csvCell(f.value);
    }
  return line + "\n";
}

}  // namespace

EvaluationValue optionalPathValue(const std::optional<fs::path>& path) {
  return path ? EvaluationValue(path->string()) : EvaluationValue(std::monostate{});
}

EvaluationValue optionalNumberValue(const std::optional<double>& value) {
  return value ? EvaluationValue(*value) : EvaluationValue(std::monostate{});
}

std::string evaluationCsvHeader(const EvaluationRecord& record) { return csvLine(record, true); }

std::string evaluationCsvRow(const EvaluationRecord& record) { return csvLine(record, false); }

void appendEvaluationCsvRow(const fs::path& file, const EvaluationRecord& record) {
  const std::string header = evaluationCsvHeader(record);
  std::string text = evaluationCsvRow(record);
  std::error_code ec;
  if (fs::exists(file, ec) && fs::file_size(file, ec) > 0) {
    std::ifstream in(file);
    std::string first_line;
    std::getline(in, first_line);
    if (first_line + "\n" != header)
      throw InputError(file, "its columns are not those of `solo " + record.command +
                                 "` (the first line differs); append to a new file");
  } else {
    text = header + text;
  }
  const int fd = ::open(file.c_str(), O_WRONLY | O_APPEND | O_CREAT | O_CLOEXEC, 0644);
  if (fd < 0) throw InputError(file, std::string("cannot open for appending: ") + std::strerror(errno));
  const ssize_t written = ::write(fd, text.data(), text.size());
  const int write_errno = errno;
  ::close(fd);
  if (written != static_cast<ssize_t>(text.size()))
    throw InputError(
        file, std::string("cannot append the row: ") + (written < 0 ? std::strerror(write_errno) : "short write"));
}

}  // namespace solo
