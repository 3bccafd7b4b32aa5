#pragma once
// One evaluation's result as named fields (docs/evaluation.md): its inputs, its options and its
// metrics, each with a key (the JSON key and CSV column), a table label and a unit. Every
// record of one kind has the same fields in the same order, so rows of a sweep line up under
// one CSV header; a value that does not apply is none (an empty CSV cell).

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <variant>
#include <vector>

namespace solo {

/// monostate = no value (an option not given, a metric that does not apply).
using EvaluationValue = std::variant<std::monostate, bool, std::int64_t, double, std::string>;

struct EvaluationField {
  std::string key;    ///< JSON key and CSV column
  std::string label;  ///< table label
  EvaluationValue value;
  std::string unit;  ///< table unit ("m", "deg", ...), empty for none
};

struct EvaluationRecord {
  std::string command;  ///< "eval depth", ...: the `solo` command that prints the record
  std::vector<EvaluationField> inputs, options, metrics;
  double seconds = 0;  ///< wall time of reading the inputs and measuring
};

/// A path, or none.
EvaluationValue optionalPathValue(const std::optional<std::filesystem::path>& path);
/// A number, or none.
EvaluationValue optionalNumberValue(const std::optional<double>& value);

/// The CSV header line of the record's fields (inputs, options, metrics), newline included.
std::string evaluationCsvHeader(const EvaluationRecord& record);
/// The record's CSV row: numbers in the shortest text that reads back as the same double,
/// booleans true/false, none empty, text quoted when it holds a comma, quote or line break.
std::string evaluationCsvRow(const EvaluationRecord& record);

/// Appends the record's row to `file`, with the header first when the file is new or empty.
/// An existing file must have this record's header (InputError otherwise). Row (and header) go
/// out in one write(2) on an O_APPEND descriptor, so rows of parallel runs never interleave.
void appendEvaluationCsvRow(const std::filesystem::path& file, const EvaluationRecord& record);

}  // namespace solo
