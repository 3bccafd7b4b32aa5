#include "off_reader.h"

#include "solo/core/error.h"

#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

namespace fs = std::filesystem;

namespace solo {
namespace {

constexpr double kMaxIndex = 9007199254740992.0;  // 2^53

std::string withoutComment(const std::string& line) { return line.substr(0, line.find('#')); }

// The lines of an OFF file, comments removed, blank ones skipped; each split into words.
class OffLines {
 public:
  explicit OffLines(const fs::path& file) : in_(file, std::ios::binary) {}
  /// The words of the next line that has any; false at the end of the file.
  bool next(std::vector<std::string>& words) {
    std::string line;
    while (std::getline(in_, line)) {
      words.clear();
      std::istringstream split(withoutComment(line));
      for (std::string word; split >> word;) words.push_back(word);
      if (!words.empty()) return true;
    }
    return false;
  }

 private:
  std::ifstream in_;
};

[[noreturn]] void refuse(const fs::path& file, const std::string& problem) {
  throw InputError(file, "cannot read as a mesh: " + problem);
}

// A count of the header: a whole number without sign.
std::uint64_t headerCount(const fs::path& file, const std::string& word) {
  const bool digits = !word.empty() && word.size() <= 19 && word.find_first_not_of("0123456789") == std::string::npos;
  if (!digits) refuse(file, "OFF counts of vertices, faces and edges are not three whole numbers (\"" + word + "\")");
  return std::stoull(word);
}

// A coordinate: a whole word read as a number (inf and nan included, for readMesh to name).
double coordinate(const fs::path& file, const std::string& word, std::size_t vertex) {
  char* end = nullptr;
  errno = 0;
  const double value = std::strtod(word.c_str(), &end);
  if (end == word.c_str() || *end != '\0')
    refuse(file, "vertex " + std::to_string(vertex) + " has \"" + word + "\" as a coordinate, not a number");
  return value;
}

// The numbers of a face line as a stream reads them, up to the first word that is not one
// ("2-1" is 2 and -1, as every OFF reader built on streams reads it).
std::vector<double> faceNumbers(const std::vector<std::string>& words) {
  std::string line;
  for (const std::string& word : words) line += word + " ";
  std::istringstream numbers(line);
  std::vector<double> out;
  for (double value = 0; numbers >> value;) out.push_back(value);
  return out;
}

// A face's vertex count or index: a whole number from 0 to 2^53.
std::size_t faceNumber(const fs::path& file, double value, std::size_t face, bool count) {
  if (value >= 0 && value <= kMaxIndex && value == std::floor(value)) return static_cast<std::size_t>(value);
  std::ostringstream problem;
  problem << "face " << face << " has " << value << " as " << (count ? "its vertex count" : "a vertex index")
          << ", not a whole number from 0 to 2^53 (corrupt file)";
  refuse(file, problem.str());
}

std::vector<std::size_t> faceFromLine(const fs::path& file, const std::vector<std::string>& words, std::size_t face) {
  const std::vector<double> numbers = faceNumbers(words);
  if (numbers.empty()) refuse(file, "face " + std::to_string(face) + " starts with \"" + words[0] + "\", not a number");
  const std::size_t corners = faceNumber(file, numbers[0], face, true);
  if (corners > numbers.size() - 1)
    refuse(file, "face " + std::to_string(face) + " declares more vertices than its line lists (" +
                     std::to_string(numbers.size() - 1) + ")");
  std::vector<std::size_t> polygon(corners);
  for (std::size_t k = 0; k < corners; ++k) polygon[k] = faceNumber(file, numbers[k + 1], face, false);
  return polygon;
}

}  // namespace

void readPlainOff(const fs::path& file, std::vector<std::array<double, 3>>& points,
                  std::vector<std::vector<std::size_t>>& polygons) {
  OffLines lines(file);
  std::vector<std::string> words;
  if (!lines.next(words) || words[0] != "OFF")
    refuse(file, "an OFF file starts with the word OFF, this one with \"" + (words.empty() ? std::string() : words[0]) +
                     "\" (binary OFF and variants with colours, normals, texture coordinates, 4D or nD points are "
                     "not read)");
  // The rest is a stream of words up to the last vertex: counts first, then coordinates.
  std::vector<std::string> stream(words.begin() + 1, words.end());
  std::size_t next = 0;
  const auto word = [&](const char* what) -> const std::string& {
    while (next == stream.size()) {
      if (!lines.next(words)) refuse(file, std::string("malformed or truncated: the file ends before ") + what);
      stream = words;
      next = 0;
    }
    return stream[next++];
  };
  if (word("the counts") == "BINARY") refuse(file, "binary OFF is not read (convert it to PLY)");
  --next;
  const std::uint64_t vertex_count = headerCount(file, word("the counts"));
  const std::uint64_t face_count = headerCount(file, word("the counts"));
  headerCount(file, word("the counts"));
  points.clear();
  polygons.clear();
  points.reserve(vertex_count);  // bounded by the file's size (requireMeshHeaderFitsFile)
  for (std::uint64_t v = 0; v < vertex_count; ++v) {
    std::array<double, 3> point{};
    for (double& c : point) c = coordinate(file, word("its vertices"), v);
    points.push_back(point);
  }
  polygons.reserve(face_count);
  for (std::uint64_t f = 0; f < face_count; ++f) {
    if (!lines.next(words)) refuse(file, "malformed or truncated: the file ends before its faces");
    polygons.push_back(faceFromLine(file, words, f));
  }
}

}  // namespace solo
