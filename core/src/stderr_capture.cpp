#include "solo/core/stderr_capture.h"

#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <sstream>

namespace solo {
namespace {

std::mutex& captureMutex() {
  static std::mutex m;
  return m;
}

}  // namespace

StderrCapture::StderrCapture(bool active) {
  if (!active) return;
  lock_ = std::unique_lock<std::mutex>(captureMutex());
  std::fflush(stderr);
  capture_ = ::memfd_create("solo-stderr", MFD_CLOEXEC);
  saved_ = capture_ < 0 ? -1 : ::dup(2);
  if (saved_ < 0 || ::dup2(capture_, 2) < 0) release();
}

StderrCapture::~StderrCapture() { finish(); }

std::vector<std::string> StderrCapture::finish() {
  if (saved_ < 0) {
    release();
    return {};
  }
  std::fflush(stderr);
  ::dup2(saved_, 2);
  std::string text;
  char buffer[4096];
  ssize_t n = 0;
  ::lseek(capture_, 0, SEEK_SET);
  while ((n = ::read(capture_, buffer, sizeof buffer)) > 0) text.append(buffer, static_cast<std::size_t>(n));
  release();
  std::vector<std::string> lines;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line))
    if (!line.empty()) lines.push_back(line);
  return lines;
}

void StderrCapture::release() {
  if (saved_ >= 0) ::close(saved_);
  if (capture_ >= 0) ::close(capture_);
  saved_ = capture_ = -1;
  if (lock_.owns_lock()) lock_.unlock();
}

std::string joinedLines(const std::vector<std::string>& lines) {
  std::vector<std::string> distinct;
  for (const std::string& line : lines)
    if (std::find(distinct.begin(), distinct.end(), line) == distinct.end()) distinct.push_back(line);
  std::string joined;
  for (const std::string& line : distinct) joined += (joined.empty() ? "" : "; ") + line;
  return joined;
}

}  // namespace solo
