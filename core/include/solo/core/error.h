#pragma once
// Errors raised for bad input. Every message names the file and the problem.

#include <filesystem>
#include <stdexcept>
#include <string>

namespace solo {

/// A file or value the user gave cannot be used. what() reads "<file>: <problem>".
class InputError : public std::runtime_error {
 public:
  InputError(const std::filesystem::path& file, const std::string& problem)
      : std::runtime_error(file.string() + ": " + problem), file_(file), problem_(problem) {}

  const std::filesystem::path& file() const { return file_; }
  const std::string& problem() const { return problem_; }

 private:
  std::filesystem::path file_;
  std::string problem_;
};

}  // namespace solo
