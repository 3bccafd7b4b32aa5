#pragma once
// What every libFuzzer target shares: the input written to a file (solo's readers take paths,
// and the extension picks the format), and the rule that a reader may only refuse its input
// with InputError. Any other exception escapes the target and libFuzzer reports it as a crash,
// as it does for sanitizer findings, hangs and out-of-memory.

#include <solo/core/error.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <unistd.h>

namespace solo::fuzz {

/// The folder of this process's input files: /dev/shm when there is one (no disk writes).
inline std::filesystem::path inputFolder() {
  static const std::filesystem::path folder = [] {
    const std::filesystem::path base =
        std::filesystem::is_directory("/dev/shm") ? std::filesystem::path("/dev/shm") : std::filesystem::temp_directory_path();
    const std::filesystem::path made = base / ("solo-fuzz-" + std::to_string(::getpid()));
    std::filesystem::create_directories(made);
    return made;
  }();
  return folder;
}

/// Writes the input to <folder>/input<extension> and returns that path.
inline std::filesystem::path writeInput(const std::uint8_t* data, std::size_t size, const std::string& extension) {
  const std::filesystem::path file = inputFolder() / ("input" + extension);
  std::FILE* out = std::fopen(file.c_str(), "wb");
  if (!out) std::abort();
  if (size > 0 && std::fwrite(data, 1, size, out) != size) std::abort();
  if (std::fclose(out) != 0) std::abort();
  return file;
}

/// Runs read(file) on the input as a file with `extension`; an InputError is a refusal, not a finding.
template <typename Read>
int readInput(const std::uint8_t* data, std::size_t size, const std::string& extension, Read read) {
  const std::filesystem::path file = writeInput(data, size, extension);
  try {
    read(file);
  } catch (const InputError&) {
  }
  return 0;
}

/// Images in the fuzz runs stay small: 2^16 pixels at most (the limit solo checks before
/// decoding), so the fuzzer spends its time on headers and chunks rather than on big pixel arrays.
inline void limitImageSize() { ::setenv("SOLO_MAX_IMAGE_PIXELS", "65536", 1); }

}  // namespace solo::fuzz
