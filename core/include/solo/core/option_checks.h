#pragma once
// Checks of a numeric option against its documented range, before any work. Each throws
// InputError naming the option (its command-line flag) with the range and the value given.

#include <solo/core/error.h>

#include <cstdio>
#include <string>

namespace solo {

/// Throws InputError(option, ...) unless low <= value <= high (NaN fails).
inline void requireOptionInRange(double value, double low, double high, const std::string& option) {
  if (value >= low && value <= high) return;
  char problem[128];
  std::snprintf(problem, sizeof problem, "must be within [%g, %g], got %g", low, high, value);
  throw InputError(option, problem);
}

/// Throws InputError(option, ...) unless low < value <= high (NaN fails).
inline void requireOptionAboveAndAtMost(double value, double low, double high, const std::string& option) {
  if (value > low && value <= high) return;
  char problem[128];
  std::snprintf(problem, sizeof problem, "must be above %g and at most %g, got %g", low, high, value);
  throw InputError(option, problem);
}

}  // namespace solo
