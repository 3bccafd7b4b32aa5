#pragma once
// Helpers shared by the tests: temporary folders, running the solo binary, shared data.

#include <solo/core/report.h>

#include <gtest/gtest.h>

#include <cstdint>

#include <filesystem>
#include <string>

namespace solo::test {

/// A fresh folder under the system temp dir, removed with everything in it on destruction.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(const std::string& name) const { return path_ / name; }

 private:
  std::filesystem::path path_;
};

void writeText(const std::filesystem::path& file, const std::string& text);
std::string readText(const std::filesystem::path& file);
/// Writes `bytes` bytes of `source` to `target` (to make truncated copies).
void writeTruncatedCopy(const std::filesystem::path& source, const std::filesystem::path& target, std::size_t bytes);

struct CommandResult {
  int exit_code = -1;
  std::string output;  ///< stdout and stderr together
};
/// Writes `folder`/square.off, the unit square in z = 0 as two triangles, and
/// `folder`/lifted.ply, the same square at z = 0.25 (a reference 0.25 away everywhere).
void writeSquareAndLiftedSquare(const std::filesystem::path& folder);

/// Runs the solo binary with the given arguments (a shell-quoted string).
CommandResult runSolo(const std::string& arguments);

/// ../shared/data/<relative>, or an empty path when the shared data is absent.
std::filesystem::path sharedData(const std::string& relative);

/// An integer metric of a stage report; a test failure and -1 when the report has none.
std::int64_t metricInt(const solo::StageReport& report, const std::string& name);
/// A numeric metric of a stage report (double or integer) as a double; NaN when the report has
/// none or it is not a number.
double metricNumber(const solo::StageReport& report, const std::string& name);

/// Files in a folder (names only), for "no partial output" checks.
std::vector<std::string> listFolder(const std::filesystem::path& folder);

}  // namespace solo::test

/// Skips the current test with a message naming the missing shared-data file.
#define SOLO_REQUIRE_SHARED_DATA(path_variable, relative)                                                 \
  const std::filesystem::path path_variable = ::solo::test::sharedData(relative);                          \
  if (path_variable.empty())                                                                               \
  GTEST_SKIP_("shared data " relative " is absent (../shared/data is only on developer machines and CI)")
