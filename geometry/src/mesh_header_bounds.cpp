#include "mesh_header_bounds.h"

#include "solo/core/error.h"
#include <solo/core/output_path.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <type_traits>
#include <vector>

namespace fs = std::filesystem;

namespace solo {
namespace {

constexpr std::size_t kMaxHeaderBytes = 1 << 16;

// A PLY property as CGAL's reader reads it: a scalar of `item_type`, or a list of `item_type`
// preceded by its size of `count_type`.
struct PlyProperty {
  bool list = false;
  std::string count_type;
  std::string item_type;
};

struct ElementBound {
  std::string name;
  std::uint64_t count = 0;
  std::uint64_t min_bytes = 0;  ///< smallest size of one element in the file's encoding
  std::vector<PlyProperty> properties;  ///< PLY only: the properties CGAL's reader creates
};

enum class PlyFormat { Ascii, BinaryLittleEndian, BinaryBigEndian, Unknown };

struct PlyHeader {
  std::vector<ElementBound> elements;
  PlyFormat format = PlyFormat::Unknown;
  std::uint64_t body_offset_bytes = 0;  ///< where the first element's data starts
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
  return {{"vertices", *vertices, binary ? 12u : 6u, {}}, {"faces", *faces, binary ? 4u : 2u, {}}};
}

std::uint64_t plyScalarBytes(const std::string& type) {
  static const std::map<std::string, std::uint64_t> sizes = {
      {"char", 1},   {"int8", 1},    {"uchar", 1},  {"uint8", 1},  {"short", 2}, {"int16", 2},
      {"ushort", 2}, {"uint16", 2},  {"int", 4},    {"int32", 4},  {"uint", 4},  {"uint32", 4},
      {"float", 4},  {"float32", 4}, {"double", 8}, {"float64", 8}};
  const auto it = sizes.find(type);
  return it == sizes.end() ? 0 : it->second;
}

// A vertex coordinate (x, y, z) must be a float or double scalar: CGAL's reader assumes it and
// dereferences a null pointer otherwise.
void requireFloatCoordinate(const fs::path& file, bool list, const std::string& type, const std::string& name) {
  if (name != "x" && name != "y" && name != "z") return;
  if (!list && (type == "float" || type == "float32" || type == "double" || type == "float64")) return;
  throw InputError(file, "cannot read as a mesh: PLY vertex coordinate " + name + " is " + (list ? "a list" : type) +
                             ", not a float or double (corrupt header)");
}

bool isPlyListCountType(const std::string& type) {
  return plyScalarBytes(type) != 0 && type != "float" && type != "float32" && type != "double" && type != "float64";
}

PlyFormat plyFormat(const std::string& name) {
  if (name == "ascii") return PlyFormat::Ascii;
  if (name == "binary_little_endian") return PlyFormat::BinaryLittleEndian;
  if (name == "binary_big_endian") return PlyFormat::BinaryBigEndian;
  return PlyFormat::Unknown;
}

// A "property" line of a PLY header added to `element` as CGAL's reader adds it: a property
// of a type it does not know is skipped (it reads no bytes for it).
void addPlyProperty(const fs::path& file, std::istringstream& words, bool binary, bool vertex_element,
                    ElementBound& element) {
  PlyProperty property;
  std::string type, name;
  words >> type;
  property.list = type == "list";
  if (property.list) {
    words >> property.count_type >> property.item_type;
  } else {
    property.item_type = type;
  }
  words >> name;
  if (vertex_element) requireFloatCoordinate(file, property.list, property.item_type, name);
  const bool known = plyScalarBytes(property.item_type) != 0 && (!property.list || isPlyListCountType(property.count_type));
  if (!known) return;
  element.min_bytes += binary ? plyScalarBytes(property.list ? property.count_type : property.item_type) : 2;
  element.properties.push_back(property);
}

// PLY: "element NAME COUNT" lines, each followed by its properties, up to "end_header". A
// binary scalar takes its type's size, a binary list at least its count; an ASCII value at
// least one digit and a separator. Throws for an element count that is not a number, a property
// before any element, a vertex coordinate that is not a float or double, and a header without
// "end_header" in its first 64 KiB: CGAL's reader dereferences missing elements and properties.
PlyHeader plyHeader(const fs::path& file, const std::string& header) {
  std::istringstream lines(header);
  std::string line, word;
  PlyHeader ply;
  if (!std::getline(lines, line) || !(std::istringstream(line) >> word) || word != "ply") return ply;  // " ply" too, as CGAL
  bool binary = false, ended = false, vertex_element = false;
  // The second line is the format line whatever it holds, as CGAL reads it.
  if (std::getline(lines, line)) {
    std::istringstream words(line);
    std::string format;
    words >> word >> format;
    binary = format != "ascii";
    ply.format = plyFormat(format);
  }
  while (!ended && std::getline(lines, line)) {
    std::istringstream words(line);
    word.clear();
    words >> word;
    ended = word == "end_header";
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
      ply.elements.push_back(element);
    } else if (word == "property" && ply.elements.empty()) {
      throw InputError(file, "cannot read as a mesh: PLY header has a property before any element (corrupt header)");
    } else if (word == "property") {
      addPlyProperty(file, words, binary, vertex_element, ply.elements.back());
    }
  }
  if (!ended)
    throw InputError(file, "cannot read as a mesh: PLY header has no end_header in its first " +
                               std::to_string(kMaxHeaderBytes) + " bytes (truncated or corrupt header)");
  const std::streamoff body = lines.tellg();
  ply.body_offset_bytes = body < 0 ? header.size() : static_cast<std::uint64_t>(body);
  return ply;
}

// The bytes of a binary PLY body read in chunks, for a walk over millions of small values.
class ChunkedBytes {
 public:
  ChunkedBytes(const fs::path& file, std::uint64_t offset_bytes) : in_(file, std::ios::binary), consumed_(offset_bytes) {
    in_.seekg(static_cast<std::streamoff>(offset_bytes));
  }
  /// Copies the next `count` bytes to `out`; false at the end of the file.
  bool read(char* out, std::size_t count) {
    for (std::size_t done = 0; done < count;) {
      if (next_ == buffer_.size() && !refill()) return false;
      const std::size_t take = std::min(count - done, buffer_.size() - next_);
      std::memcpy(out + done, buffer_.data() + next_, take);
      next_ += take;
      done += take;
    }
    return true;
  }
  /// Skips `count` bytes; false at the end of the file.
  bool skip(std::uint64_t count) {
    while (count > 0) {
      if (next_ == buffer_.size() && !refill()) return false;
      const std::uint64_t take = std::min<std::uint64_t>(count, buffer_.size() - next_);
      next_ += static_cast<std::size_t>(take);
      count -= take;
    }
    return true;
  }
  std::uint64_t position() const { return consumed_ + next_; }

 private:
  bool refill() {
    consumed_ += buffer_.size();
    buffer_.resize(1 << 20);
    in_.read(buffer_.data(), static_cast<std::streamsize>(buffer_.size()));
    buffer_.resize(static_cast<std::size_t>(in_.gcount()));
    next_ = 0;
    return !buffer_.empty();
  }
  std::ifstream in_;
  std::vector<char> buffer_;
  std::size_t next_ = 0;
  std::uint64_t consumed_;  ///< the file offset of buffer_[0]
};

// A binary list size: the count type read in the file's byte order (CGAL casts a negative one
// to a huge size_t).
std::int64_t binaryListSize(const char* bytes, const std::string& type, bool big_endian) {
  const std::size_t size = std::min<std::size_t>(plyScalarBytes(type), 4);  // list sizes are integers
  std::uint32_t raw = 0;
  for (std::size_t b = 0; b < size; ++b)
    raw |= std::uint32_t{static_cast<unsigned char>(bytes[big_endian ? size - 1 - b : b])} << (8 * b);
  const bool is_signed = type == "char" || type == "int8" || type == "short" || type == "int16" || type == "int" ||
                         type == "int32";
  if (!is_signed) return raw;
  return size == 1 ? std::int64_t{static_cast<std::int8_t>(raw)}
         : size == 2 ? std::int64_t{static_cast<std::int16_t>(raw)}
                     : std::int64_t{static_cast<std::int32_t>(raw)};
}

// Throws when a list of `size` values of `item_bytes` each (at least) cannot fit in the
// `remaining_bytes` after its size, or its size is negative.
void requireListFits(const fs::path& file, const ElementBound& element, std::uint64_t item, std::int64_t size,
                     std::uint64_t item_bytes, std::uint64_t remaining_bytes) {
  const std::string where = "cannot read as a mesh: PLY " + element.name + " " + std::to_string(item) + " has a list of ";
  if (size < 0) throw InputError(file, where + "negative size " + std::to_string(size) + " (corrupt file)");
  if (static_cast<std::uint64_t>(size) > remaining_bytes / item_bytes)
    throw InputError(file, where + std::to_string(size) + " values, more than the " + std::to_string(remaining_bytes) +
                               " bytes after it can hold (corrupt file)");
}

// Throws for a list whose size the file ends before or inside: CGAL's reader sizes a vector from
// the bytes it did not read (uninitialised memory, up to 2^32 items).
[[noreturn]] void throwListSizeCutOff(const fs::path& file, const ElementBound& element, std::uint64_t item) {
  throw InputError(file, "cannot read as a mesh: PLY " + element.name + " " + std::to_string(item) +
                             " has a list whose size the end of the file cuts off (truncated file)");
}

// A binary PLY body walked as CGAL's reader walks it, each list size checked against the bytes
// left before the reader sizes a vector from it. Stops quietly where the file ends before a
// scalar (the reader reports the truncation); throws where it ends before or inside a list size.
void requireBinaryPlyListsFitFile(const fs::path& file, const PlyHeader& ply, std::uint64_t file_size_bytes) {
  const bool big_endian = ply.format == PlyFormat::BinaryBigEndian;
  ChunkedBytes body(file, ply.body_offset_bytes);
  char bytes[8];
  for (const ElementBound& element : ply.elements)
    for (std::uint64_t item = 0; item < element.count; ++item)
      for (const PlyProperty& property : element.properties) {
        const std::uint64_t item_bytes = plyScalarBytes(property.item_type);
        if (!property.list) {
          if (!body.skip(item_bytes)) return;
          continue;
        }
        if (!body.read(bytes, static_cast<std::size_t>(plyScalarBytes(property.count_type))))
          throwListSizeCutOff(file, element, item);
        const std::int64_t size = binaryListSize(bytes, property.count_type, big_endian);
        const std::uint64_t remaining = file_size_bytes - std::min(file_size_bytes, body.position());
        requireListFits(file, element, item, size, item_bytes, remaining);
        if (!body.skip(static_cast<std::uint64_t>(size) * item_bytes)) return;
      }
}

// One ASCII value extracted as CGAL's reader extracts it (chars through a short, the others as
// themselves); false when the extraction fails.
template <typename Value>
bool extractAscii(std::istream& in, Value& value) {
  if constexpr (sizeof(Value) == 1) {
    std::conditional_t<std::is_signed_v<Value>, short, unsigned short> wide = 0;
    if (!(in >> wide)) return false;
    value = static_cast<Value>(wide);
    return true;
  } else {
    return static_cast<bool>(in >> value);
  }
}

// An ASCII list size as CGAL reads it: extracted as the count type (a failed extraction of an
// int leaves the type's limit, which the reader still uses; of a char, 0).
template <typename Count>
std::optional<std::int64_t> asciiListSize(std::istream& in) {
  Count count{};
  const bool read = extractAscii(in, count);
  if (!read && sizeof(Count) == 1) return std::nullopt;
  return static_cast<std::int64_t>(count);
}

std::optional<std::int64_t> asciiListSize(std::istream& in, const std::string& type) {
  if (type == "uchar" || type == "uint8") return asciiListSize<std::uint8_t>(in);
  if (type == "char" || type == "int8") return asciiListSize<std::int8_t>(in);
  if (type == "ushort" || type == "uint16") return asciiListSize<std::uint16_t>(in);
  if (type == "short" || type == "int16") return asciiListSize<std::int16_t>(in);
  if (type == "uint" || type == "uint32") return asciiListSize<std::uint32_t>(in);
  return asciiListSize<std::int32_t>(in);
}

// Skips one ASCII value of `type` as CGAL's reader extracts it; false when it fails.
bool skipAsciiValue(std::istream& in, const std::string& type) {
  if (type == "float" || type == "float32" || type == "double" || type == "float64") {
    double value = 0;
    return static_cast<bool>(in >> value);
  }
  if (type == "uchar" || type == "uint8" || type == "ushort" || type == "uint16") {
    unsigned short value = 0;
    return extractAscii(in, value);
  }
  long long value = 0;  // wide enough for every integer type: the walk needs the token, not its range
  return static_cast<bool>(in >> value);
}

// An ASCII PLY body walked value by value as CGAL's reader extracts them, each list size checked
// against the bytes left (a value takes at least one digit and a separator) before the reader
// sizes a vector from it. Stops quietly where an extraction fails (the reader reports it), except
// where the file ends before a list size: there the reader's extraction of an integer leaves its
// uninitialised variable as the size.
void requireAsciiPlyListsFitFile(const fs::path& file, const PlyHeader& ply, std::uint64_t file_size_bytes) {
  std::ifstream in(file, std::ios::binary);
  in.seekg(static_cast<std::streamoff>(ply.body_offset_bytes));
  for (const ElementBound& element : ply.elements)
    for (std::uint64_t item = 0; item < element.count; ++item)
      for (const PlyProperty& property : element.properties) {
        if (!property.list) {
          if (!skipAsciiValue(in, property.item_type)) return;
          continue;
        }
        if ((in >> std::ws).peek() == std::char_traits<char>::eof()) throwListSizeCutOff(file, element, item);
        const std::optional<std::int64_t> size = asciiListSize(in, property.count_type);
        if (!size) return;
        const std::uint64_t at = in.good() ? static_cast<std::uint64_t>(in.tellg()) : file_size_bytes;
        // The last value needs no separator after it.
        requireListFits(file, element, item, *size, 2, file_size_bytes - std::min(file_size_bytes, at) + 1);
        if (!in) return;
        for (std::int64_t k = 0; k < *size; ++k)
          if (!skipAsciiValue(in, property.item_type)) return;
      }
}

void requirePlyListsFitFile(const fs::path& file, const PlyHeader& ply, std::uint64_t file_size_bytes) {
  if (ply.format == PlyFormat::Ascii) requireAsciiPlyListsFitFile(file, ply, file_size_bytes);
  if (ply.format == PlyFormat::BinaryLittleEndian || ply.format == PlyFormat::BinaryBigEndian)
    requireBinaryPlyListsFitFile(file, ply, file_size_bytes);
}

}  // namespace

void requireMeshHeaderFitsFile(const fs::path& file, std::uintmax_t file_size_bytes) {
  const std::string ext = lowercaseExtension(file);
  if (ext != ".off" && ext != ".ply") return;
  const std::string header = headerText(file);
  const PlyHeader ply = ext == ".ply" ? plyHeader(file, header) : PlyHeader{};
  const std::vector<ElementBound> elements = ext == ".off" ? offBounds(header) : ply.elements;
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
  if (ext == ".ply") requirePlyListsFitFile(file, ply, file_size_bytes);
}

}  // namespace solo
