#include "mesh_header_bounds.h"

#include "solo/core/error.h"
#include <solo/core/output_path.h>

#include <algorithm>
#include <cstdlib>
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

// The whitespace-separated words of a line of an OFF file, a '#' and what follows dropped.
std::vector<std::string> offWords(const std::string& line) {
  std::istringstream words(line.substr(0, line.find('#')));
  std::vector<std::string> out;
  std::string word;
  while (words >> word) out.push_back(word);
  return out;
}

// The numbers of a face line as CGAL's OFF scanner reads them: doubles by stream extraction
// up to the first that fails ("2-1" is 2 and -1), a '#' and what follows dropped.
std::vector<double> offNumbers(const std::string& line) {
  std::istringstream numbers(line.substr(0, line.find('#')));
  std::vector<double> out;
  double value = 0;
  while (numbers >> value) out.push_back(value);
  return out;
}

// An OFF file as far as CGAL's scanner reads it safely: the word OFF and three counts (its
// colour reading overflows its buffers, its keyword reading takes "OFF$0"); in ASCII, the face
// lines (found as the scanner finds them: after the counts, one vertex and then one face a
// non-blank line) with vertex counts and indices from 0 to 2^53, which it converts to size_t
// (undefined for a negative or too large value), and no more vertices than the line lists (it
// allocates the count first). A binary OFF is left to the reader.
void requirePlainOffWithIndices(const fs::path& file) {
  constexpr double kMaxIndex = 9007199254740992.0;  // 2^53
  std::ifstream in(file, std::ios::binary);
  std::string line, rest;  // rest: what follows the counts on their line, CGAL's first vertex line
  std::vector<std::string> header;
  while (header.size() < 4 && std::getline(in, line)) {
    const std::vector<std::string> words = offWords(line);
    for (std::size_t w = 0; w < words.size(); ++w) {
      if (header.size() < 4)
        header.push_back(words[w]);
      else
        rest += words[w] + " ";
    }
  }
  if (header.empty() || header[0] != "OFF")
    throw InputError(file, "cannot read as a mesh: an OFF file starts with the word OFF, this one with \"" +
                               (header.empty() ? std::string() : header[0]) +
                               "\" (variants with colours, normals, texture coordinates, 4D or nD points are not read)");
  if (header.size() > 1 && header[1] == "BINARY") return;
  const auto vertices = parseCount(header.size() > 1 ? header[1] : ""), faces = parseCount(header.size() > 2 ? header[2] : "");
  if (header.size() < 4 || !vertices || !faces || !parseCount(header[3]))
    throw InputError(file, "cannot read as a mesh: OFF counts of vertices, faces and edges are not three whole numbers");
  std::uint64_t vertex_lines = 0, face = 0;
  bool pending = !rest.empty();
  while (face < *faces && (pending || std::getline(in, line))) {
    if (pending) line = rest;
    pending = false;
    if (offWords(line).empty()) continue;
    if (vertex_lines < *vertices) {
      ++vertex_lines;
      continue;
    }
    const std::vector<double> numbers = offNumbers(line);
    const double corners = numbers.empty() ? 0 : numbers[0];
    if (corners > static_cast<double>(numbers.size()) - 1)  // CGAL sizes the face from it first
      throw InputError(file, "cannot read as a mesh: face " + std::to_string(face) + " declares more vertices than " +
                                 "its line lists (" + std::to_string(numbers.size() - 1) + ")");
    for (std::size_t n = 0; n < numbers.size() && (n == 0 || n <= corners); ++n)
      if (!(numbers[n] >= 0 && numbers[n] <= kMaxIndex)) {
        std::ostringstream problem;
        problem << "cannot read as a mesh: face " << face << " has " << numbers[n] << " as "
                << (n == 0 ? "its vertex count" : "a vertex index") << ", not a number from 0 to 2^53 (corrupt file)";
        throw InputError(file, problem.str());
      }
    ++face;
  }
}

// A vertex coordinate (x, y, z) must be a float or double scalar: CGAL's reader assumes it and
// dereferences a null pointer otherwise.
void requireFloatCoordinate(const fs::path& file, bool list, const std::string& type, const std::string& name) {
  if (name != "x" && name != "y" && name != "z") return;
  if (!list && (type == "float" || type == "float32" || type == "double" || type == "float64")) return;
  throw InputError(file, "cannot read as a mesh: PLY vertex coordinate " + name + " is " + (list ? "a list" : type) +
                             ", not a float or double (corrupt header)");
}

// PLY: "element NAME COUNT" lines, each followed by its properties, up to "end_header". A
// binary scalar takes its type's size, a binary list at least its count; an ASCII value at
// least one digit and a separator. Throws for an element count that is not a number, a property
// before any element, a vertex coordinate that is not a float or double, and a header without
// "end_header" in its first 64 KiB: CGAL's reader dereferences missing elements and properties.
std::vector<ElementBound> plyBounds(const fs::path& file, const std::string& header) {
  std::istringstream lines(header);
  std::string line, word;
  if (!std::getline(lines, line) || !(std::istringstream(line) >> word) || word != "ply") return {};  // " ply" too, as CGAL
  bool binary = false, ended = false, vertex_element = false;
  std::vector<ElementBound> elements;
  // The second line is the format line whatever it holds, as CGAL reads it.
  if (std::getline(lines, line)) {
    std::istringstream words(line);
    std::string format;
    words >> word >> format;
    binary = format != "ascii";
  }
  while (std::getline(lines, line)) {
    std::istringstream words(line);
    word.clear();
    words >> word;
    if (word == "end_header") {
      ended = true;
      break;
    }
    if (word == "element") {
      ElementBound element;
      std::string count;
      words >> element.name >> count;
      const auto parsed = parseCount(count);
      if (!parsed)
        throw InputError(file, "cannot read as a mesh: PLY element " + element.name + " has the count \"" + count +
                                   "\", not a whole number (corrupt header)");
      element.count = *parsed;
      vertex_element = element.name == "vertex" || element.name == "vertices";
      elements.push_back(element);
    } else if (word == "property" && elements.empty()) {
      throw InputError(file, "cannot read as a mesh: PLY header has a property before any element (corrupt header)");
    } else if (word == "property") {
      std::string type, name;
      words >> type;
      const bool list = type == "list";
      if (list) words >> type;  // a list starts with its count
      elements.back().min_bytes += binary ? plyScalarBytes(type) : 2;
      std::string item_type = type;
      if (list) words >> item_type;
      words >> name;
      if (vertex_element) requireFloatCoordinate(file, list, item_type, name);
    }
  }
  if (!ended)
    throw InputError(file, "cannot read as a mesh: PLY header has no end_header in its first " +
                               std::to_string(kMaxHeaderBytes) + " bytes (truncated or corrupt header)");
  return elements;
}

}  // namespace

void requireMeshHeaderFitsFile(const fs::path& file, std::uintmax_t file_size_bytes) {
  const std::string ext = lowercaseExtension(file);
  if (ext != ".off" && ext != ".ply") return;
  const std::string header = headerText(file);
  const std::vector<ElementBound> elements = ext == ".off" ? offBounds(header) : plyBounds(file, header);
  std::uint64_t need_bytes = 0;
  for (const ElementBound& element : elements) {
    std::uint64_t element_bytes = 0;
    // An element without properties takes no bytes, yet CGAL's reader loops over its count.
    const std::uint64_t item_bytes = std::max<std::uint64_t>(element.min_bytes, 1);
    if (__builtin_mul_overflow(element.count, item_bytes, &element_bytes) ||
        __builtin_add_overflow(need_bytes, element_bytes, &need_bytes) || need_bytes > file_size_bytes)
      throw InputError(file, "cannot read as a mesh: header declares " + std::to_string(element.count) + " " +
                                 element.name + ", more than the file's " + std::to_string(file_size_bytes) +
                                 " bytes can hold (truncated or corrupt header)");
  }
  if (ext == ".off") requirePlainOffWithIndices(file);
}

}  // namespace solo
