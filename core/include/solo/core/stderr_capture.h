#pragma once
// Text that libraries print on stderr (libpng's "libpng error: ...", CGAL's "Error line 4 of
// file") kept off the terminal and folded into solo's own error instead.

#include <mutex>
#include <string>
#include <vector>

namespace solo {

/// While it lives (or until finish()), the process's stderr (file descriptor 2) goes to a memory
/// file; one capture at a time in the process (others wait). Inactive (active = false, or the
/// memory file cannot be made): does nothing and captures nothing.
class StderrCapture {
 public:
  explicit StderrCapture(bool active = true);
  ~StderrCapture();
  StderrCapture(const StderrCapture&) = delete;
  StderrCapture& operator=(const StderrCapture&) = delete;

  /// Puts stderr back and returns the lines written meanwhile (without their newlines).
  std::vector<std::string> finish();

 private:
  void release();

  std::unique_lock<std::mutex> lock_;
  int saved_ = -1, capture_ = -1;
};

/// The lines joined by "; ", repeated lines once.
std::string joinedLines(const std::vector<std::string>& lines);

}  // namespace solo
