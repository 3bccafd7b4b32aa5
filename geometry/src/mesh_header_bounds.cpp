#include "mesh_header_bounds.h"

#include "solo/core/error.h"
#include <solo/core/output_path.h>

#include <algorithm>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;

namespace solo {
namespace {

constexpr std::size_t kMaxHeaderBytes = 1 << 16;

struct ElementBound {
  std::string name;
  std::uint64_t count = 0;
  std::uint64_t min_bytes = 0;  ///< smallest size of one element in the file's encoding
};

// A decimal count without sign, spaces or overflow; nothing when `token` is not one.
std::optional<std::uint64_t> parseCount(const std::string& token) {
  if (token.empty() || token.size() > 19 || !std::all_of(token.begin(), token.end(), ::isdigit)) return std::nullopt;
  return std::stoull(token);
}

// The first bytes of the file, enough for any header solo reads.
std::string headerText(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::string text(kMaxHeaderBytes, '\0');
  in.read(text.data(), static_cast<std::streamsize>(text.size()));
  text.resize(static_cast<std::size_t>(in.gcount()));
  return text;
}

// OFF: keyword ([ST][C][N][4][n]OFF, optionally BINARY), then vertex, face and edge counts;
// '#' starts a comment. ASCII vertices take at least "0 0 0\n", faces at least "0\n"; binary
// vertices 3 floats, faces one int.
std::vector<ElementBound> offBounds(const std::string& header) {
  std::istringstream lines(header);
  std::vector<std::string> tokens;
  std::string line;
  while (tokens.size() < 6 && std::getline(lines, line)) {
    std::istringstream words(line.substr(0, line.find('#')));
    std::string word;
    while (words >> word) tokens.push_back(word);
  }
  if (tokens.empty() || tokens[0].size() < 3 || tokens[0].compare(tokens[0].size() - 3, 3, "OFF") != 0) return {};
  std::size_t next = 1;
  const bool binary = tokens.size() > next && tokens[next] == "BINARY";
  if (binary) ++next;
  if (tokens[0].find("nOFF") != std::string::npos) ++next;  // the dimension comes first
  if (tokens.size() < next + 2) return {};
  const auto vertices = parseCount(tokens[next]), faces = parseCount(tokens[next + 1]);
  if (!vertices || !faces) return {};
  return {{"vertices", *vertices, binary ? 12u : 6u}, {"faces", *faces, binary ? 4u : 2u}};
}

std::uint64_t plyScalarBytes(const std::string& type) {
  static const std::map<std::string, std::uint64_t> sizes = {
      {"char", 1},   {"int8", 1},    {"uchar", 1},  {"uint8", 1},  {"short", 2}, {"int16", 2},
      {"ushort", 2}, {"uint16", 2},  {"int", 4},    {"int32", 4},  {"uint", 4},  {"uint32", 4},
      {"float", 4},  {"float32", 4}, {"double", 8}, {"float64", 8}};
  const auto it = sizes.find(type);
  return it == sizes.end() ? 0 : it->second;
}

// PLY: "element NAME COUNT" lines, each followed by its properties, up to "end_header". A
// binary scalar takes its type's size, a binary list at least its count; an ASCII value at
// least one digit and a separator.
std::vector<ElementBound> plyBounds(const std::string& header) {
  std::istringstream lines(header);
  std::string line, word;
  if (!std::getline(lines, line) || line.rfind("ply", 0) != 0) return {};
  bool binary = false, ended = false;
  std::vector<ElementBound> elements;
  while (std::getline(lines, line)) {
    std::istringstream words(line);
    words >> word;
    if (word == "end_header") {
      ended = true;
      break;
    }
    if (word == "format") {
      words >> word;
      binary = word != "ascii";
    } else if (word == "element") {
      ElementBound element;
      std::string count;
      words >> element.name >> count;
      const auto parsed = parseCount(count);
      if (!parsed) return {};
      element.count = *parsed;
      elements.push_back(element);
    } else if (word == "property" && !elements.empty()) {
      std::string type;
      words >> type;
      if (type == "list") words >> type;  // a list starts with its count
      elements.back().min_bytes += binary ? plyScalarBytes(type) : 2;
    }
  }
  return ended ? elements : std::vector<ElementBound>{};
}

}  // namespace

void requireMeshHeaderFitsFile(const fs::path& file, std::uintmax_t file_size_bytes) {
  const std::string ext = lowercaseExtension(file);
  if (ext != ".off" && ext != ".ply") return;
  const std::string header = headerText(file);
  const std::vector<ElementBound> elements = ext == ".off" ? offBounds(header) : plyBounds(header);
  std::uint64_t need_bytes = 0;
  for (const ElementBound& element : elements) {
    std::uint64_t element_bytes = 0;
    if (__builtin_mul_overflow(element.count, element.min_bytes, &element_bytes) ||
        __builtin_add_overflow(need_bytes, element_bytes, &need_bytes) || need_bytes > file_size_bytes)
      throw InputError(file, "cannot read as a mesh: header declares " + std::to_string(element.count) + " " +
                                 element.name + ", more than the file's " + std::to_string(file_size_bytes) +
                                 " bytes can hold (truncated or corrupt header)");
  }
}

}  // namespace solo
