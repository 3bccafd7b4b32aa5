#include "solo/core/image_io.h"
#include "solo/core/scene_from_arrays.h"

#include "solo/core/atomic_file.h"
#include "solo/core/error.h"
#include "solo/core/image_limits.h"
#include "solo/core/output_path.h"
#include "solo/core/stderr_capture.h"
#include "solo/core/input_file.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <optional>
#include <sstream>
#include <vector>

namespace fs = std::filesystem;

namespace solo {
namespace {

bool isNpy(const fs::path& file) { return lowercaseExtension(file) == ".npy"; }

std::uintmax_t requireReadableFile(const fs::path& file) { return requireNonEmptyRegularFile(file, "map or image"); }

std::string pixelTypeName(int cv_depth) {
  switch (cv_depth) {
    case CV_8U: return "uint8";
    case CV_16U: return "uint16";
    case CV_32S: return "int32";
    case CV_32F: return "float";
    case CV_64F: return "double";
    default: return "unsupported";
  }
}

bool isIntegerType(const std::string& pixel_type) {
  return pixel_type == "uint8" || pixel_type == "uint16" || pixel_type == "int32" ||
         pixel_type == "uint32" || pixel_type == "int16" || pixel_type == "int8";
}

// ---------------------------------------------------------------------------------- NPY

struct NpyHeader {
  std::string descr;
  bool fortran_order = false;
  std::vector<std::uint64_t> shape;
  std::size_t data_offset = 0;
};

// The entries of a shape tuple's text ("480, 640, 3" or "480, 640,"): decimal integers only,
// at most 19 digits each so that none overflows 64 bits.
std::vector<std::uint64_t> parseNpyShape(const fs::path& file, const std::string& text) {
  std::vector<std::uint64_t> shape;
  std::stringstream dims(text);
  std::string item;
  while (std::getline(dims, item, ',')) {
    item.erase(std::remove(item.begin(), item.end(), ' '), item.end());
    if (item.empty()) continue;
    const bool digits = std::all_of(item.begin(), item.end(), [](unsigned char c) { return std::isdigit(c); });
    if (!digits) throw InputError(file, "malformed .npy shape: \"" + item + "\" is not a whole number");
    if (item.size() > 19) throw InputError(file, ".npy shape entry " + item + " is implausibly large");
    shape.push_back(std::stoull(item));
  }
  return shape;
}

// Bytes of `shape` x `bytes_per_value`, or nothing when the product overflows 64 bits.
std::optional<std::uint64_t> npyDataBytes(const std::vector<std::uint64_t>& shape, std::uint64_t bytes_per_value) {
  std::uint64_t total = bytes_per_value;
  for (std::uint64_t extent : shape)
    if (__builtin_mul_overflow(total, extent, &total)) return std::nullopt;
  return total;
}

NpyHeader parseNpyHeader(const fs::path& file, std::istream& in) {
  char magic[6];
  if (!in.read(magic, 6) || std::memcmp(magic, "\x93NUMPY", 6) != 0)
    throw InputError(file, "not a NumPy .npy file (bad magic bytes)");
  unsigned char version[2];
  if (!in.read(reinterpret_cast<char*>(version), 2)) throw InputError(file, "truncated .npy header");
  std::size_t header_len = 0;
  std::size_t prefix = 0;
  if (version[0] == 1) {
    unsigned char len[2];
    if (!in.read(reinterpret_cast<char*>(len), 2)) throw InputError(file, "truncated .npy header");
    header_len = len[0] | (len[1] << 8);
    prefix = 10;
  } else if (version[0] == 2 || version[0] == 3) {
    unsigned char len[4];
    if (!in.read(reinterpret_cast<char*>(len), 4)) throw InputError(file, "truncated .npy header");
    header_len = len[0] | (len[1] << 8) | (len[2] << 16) | (static_cast<std::size_t>(len[3]) << 24);
    prefix = 12;
  } else {
    throw InputError(file, "unsupported .npy format version " + std::to_string(version[0]));
  }
  if (header_len > (1u << 20)) throw InputError(file, ".npy header length is implausible");
  std::string header(header_len, '\0');
  if (!in.read(header.data(), static_cast<std::streamsize>(header_len)))
    throw InputError(file, "truncated .npy header");

  NpyHeader h;
  h.data_offset = prefix + header_len;
  auto valueAfter = [&](const std::string& key) -> std::size_t {
    std::size_t k = header.find("'" + key + "'");
    if (k == std::string::npos) throw InputError(file, ".npy header lacks '" + key + "'");
    std::size_t colon = header.find(':', k);
    if (colon == std::string::npos) throw InputError(file, "malformed .npy header");
    return header.find_first_not_of(' ', colon + 1);
  };
  std::size_t d = valueAfter("descr");
  if (d == std::string::npos || header[d] != '\'') throw InputError(file, "malformed .npy descr");
  std::size_t d_end = header.find('\'', d + 1);
  if (d_end == std::string::npos) throw InputError(file, "malformed .npy descr: no closing quote");
  h.descr = header.substr(d + 1, d_end - d - 1);
  std::size_t f = valueAfter("fortran_order");
  if (f == std::string::npos) throw InputError(file, "malformed .npy header: 'fortran_order' has no value");
  h.fortran_order = header.compare(f, 4, "True") == 0;
  std::size_t s = valueAfter("shape");
  if (s == std::string::npos || header[s] != '(') throw InputError(file, "malformed .npy shape");
  const std::size_t s_end = header.find(')', s);
  if (s_end == std::string::npos) throw InputError(file, "malformed .npy shape: no closing parenthesis");
  h.shape = parseNpyShape(file, header.substr(s + 1, s_end - s - 1));
  return h;
}

struct NpyType {
  int cv_depth;
  std::size_t bytes;
  bool int64;
};

NpyType npyType(const fs::path& file, const std::string& descr) {
  if (descr.size() < 3) throw InputError(file, "unsupported .npy dtype '" + descr + "'");
  char order = descr[0];
  std::string code = descr.substr(1);
  if (order == '>' && code != "u1" && code != "i1")
    throw InputError(file, "big-endian .npy data is not supported (dtype '" + descr + "')");
  if (code == "f4") return {CV_32F, 4, false};
  if (code == "f8") return {CV_64F, 8, false};
  if (code == "u1") return {CV_8U, 1, false};
  if (code == "u2") return {CV_16U, 2, false};
  if (code == "i4") return {CV_32S, 4, false};
  if (code == "i8") return {CV_32S, 8, true};
  throw InputError(file, "unsupported .npy dtype '" + descr +
                             "' (float32, float64, uint8, uint16, int32 or int64 expected)");
}

ImageFileInfo probeNpy(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError(file, "cannot open for reading");
  NpyHeader h = parseNpyHeader(file, in);
  NpyType t = npyType(file, h.descr);
  if (h.shape.size() < 2 || h.shape.size() > 3)
    throw InputError(file, ".npy array must have shape (H, W) or (H, W, C), found " +
                               std::to_string(h.shape.size()) + " dimensions");
  requireImageSizeWithinLimit(file, h.shape[1], h.shape[0]);
  ImageFileInfo info;
  info.height = static_cast<int>(h.shape[0]);
  info.width = static_cast<int>(h.shape[1]);
  info.channels = h.shape.size() == 3 ? static_cast<int>(std::min<std::uint64_t>(h.shape[2], 1u << 30)) : 1;
  info.pixel_type = t.int64 ? "int64" : pixelTypeName(t.cv_depth);
  info.format = "npy";
  return info;
}

// ------------------------------------------------------------------------ OpenImageIO

OIIO::TypeDesc oiioType(int cv_depth) {
  switch (cv_depth) {
    case CV_8U: return OIIO::TypeDesc::UINT8;
    case CV_16U: return OIIO::TypeDesc::UINT16;
    case CV_32S: return OIIO::TypeDesc::INT32;
    case CV_32F: return OIIO::TypeDesc::FLOAT;
    case CV_64F: return OIIO::TypeDesc::DOUBLE;
    default: return OIIO::TypeDesc::UNKNOWN;
  }
}

// The bytes before a PFM's pixel data (three lines: "PF" or "Pf", width and height, scale),
// or nothing when the file does not start like a PFM.
std::optional<std::uintmax_t> pfmHeaderBytes(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::string line;
  std::uintmax_t bytes = 0;
  for (int k = 0; k < 3; ++k) {
    if (!std::getline(in, line) || line.size() > 256) return std::nullopt;
    if (k == 0 && line != "PF" && line != "Pf") return std::nullopt;
    bytes += line.size() + 1;
  }
  return bytes;
}

// The header's size, from OpenImageIO's spec, checked before any pixel memory is taken: the
// pixel limit, a bounded channel count, and for PFM (uncompressed) the bytes the file must hold.
void requireDecodableSize(const fs::path& file, const OIIO::ImageSpec& spec, std::uintmax_t file_bytes) {
  constexpr int kMaxChannels = 16;
  if (spec.width <= 0 || spec.height <= 0 || spec.depth <= 0) throw InputError(file, "image has no pixels");
  if (spec.depth > 1) throw InputError(file, "volume images are not supported");
  if (spec.nchannels <= 0 || spec.nchannels > kMaxChannels)
    throw InputError(file, "image has " + std::to_string(spec.nchannels) + " channels, at most " +
                               std::to_string(kMaxChannels) + " are read");
  requireImageSizeWithinLimit(file, static_cast<std::uint64_t>(spec.width), static_cast<std::uint64_t>(spec.height));
  const std::optional<std::uintmax_t> header_bytes = pfmHeaderBytes(file);
  if (!header_bytes) return;
  const std::uintmax_t data_bytes = file_bytes > *header_bytes ? file_bytes - *header_bytes : 0;
  const std::uint64_t need_bytes = static_cast<std::uint64_t>(spec.width) * static_cast<std::uint64_t>(spec.height) *
                                   static_cast<std::uint64_t>(spec.nchannels) * sizeof(float);
  if (need_bytes > data_bytes)
    throw InputError(file, "PFM header declares " + std::to_string(spec.width) + "x" + std::to_string(spec.height) +
                               " pixels, " + std::to_string(need_bytes) + " bytes of data, but the file holds " +
                               std::to_string(data_bytes) + " after its header (truncated or corrupt)");
}

// True when the file starts with the PNG signature (whatever its extension).
bool hasPngSignature(const fs::path& file) {
  static const char kSignature[8] = {'\x89', 'P', 'N', 'G', '\r', '\n', '\x1a', '\n'};
  char head[8] = {};
  std::ifstream in(file, std::ios::binary);
  return in.read(head, sizeof head) && std::memcmp(head, kSignature, sizeof head) == 0;
}

// libpng's default handlers, which OpenImageIO's PNG reader keeps, print "libpng error: ..."
// and "libpng warning: ..." on stderr. While a PNG is opened or decoded, stderr is captured
// (StderrCapture); finish() returns libpng's lines (their prefix dropped) for solo's own error
// and writes any other line (another thread's) back to stderr. Inactive: does nothing.
class LibpngStderrCapture {
 public:
  explicit LibpngStderrCapture(bool active) : capture_(active) {}

  std::vector<std::string> finish() {
    std::vector<std::string> libpng_lines;
    for (const std::string& line : capture_.finish()) {
      if (line.rfind("libpng", 0) != 0) {
        std::fprintf(stderr, "%s\n", line.c_str());
        continue;
      }
      const std::size_t colon = line.find(": ");
      libpng_lines.push_back(colon == std::string::npos ? line : line.substr(colon + 2));
    }
    return libpng_lines;
  }

 private:
  StderrCapture capture_;
};

// Why a read failed, on one line: libpng's own words when it said something, else
// OpenImageIO's error lines joined by "; ".
std::string readFailureReason(const std::string& oiio_error, const std::vector<std::string>& libpng_lines) {
  std::vector<std::string> oiio_lines;
  std::istringstream in(oiio_error);
  std::string line;
  while (std::getline(in, line))
    if (!line.empty()) oiio_lines.push_back(line);
  const std::string reason = joinedLines(libpng_lines.empty() ? oiio_lines : libpng_lines);
  return reason.empty() ? reason : " (" + reason + ")";
}

// An OpenEXR file's headers walked before OpenEXR reads them: every attribute (name, type,
// 4-byte size, value) must fit in the file, or OpenEXR allocates and reads what its size claims
// (a 135-byte file took 15 s and 1.7 GB). Multi-part files have several headers, each ended by
// an empty name, and an empty name after the last. Headers are walked in the first 16 MiB;
// other files pass.
void requireExrHeadersFitFile(const fs::path& file, std::uintmax_t file_bytes) {
  static const unsigned char kMagic[4] = {0x76, 0x2f, 0x31, 0x01};
  constexpr std::uintmax_t kWalkedBytes = 16u << 20;
  std::ifstream in(file, std::ios::binary);
  std::vector<unsigned char> bytes(static_cast<std::size_t>(std::min(file_bytes, kWalkedBytes)));
  in.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  bytes.resize(static_cast<std::size_t>(in.gcount()));
  if (bytes.size() < 8 || std::memcmp(bytes.data(), kMagic, 4) != 0) return;
  const bool whole_file = bytes.size() == file_bytes;
  const bool multipart = (bytes[5] & 0x10) != 0;  // version flag 0x1000
  std::size_t pos = 8;
  // The null-terminated word at pos (names and types have at most 255 characters); false at the
  // end of the walked bytes of a larger file.
  const auto word = [&](const char* what, std::string& text) {
    const auto begin = bytes.begin() + static_cast<std::ptrdiff_t>(pos);
    const auto end = std::find(begin, bytes.end(), 0);
    if (end == bytes.end() && !whole_file && bytes.end() - begin <= 255) return false;
    if (end == bytes.end() || end - begin > 255)
      throw InputError(file, std::string("OpenEXR header: ") + what + " without its end (truncated or corrupt)");
    text.assign(begin, end);
    pos = static_cast<std::size_t>(end - bytes.begin()) + 1;
    return true;
  };
  std::string name, type;
  while (word("attribute name", name)) {
    if (name.empty()) {
      if (!multipart || (pos < bytes.size() && bytes[pos] == 0)) return;
      continue;  // the next part's header
    }
    if (!word("attribute type", type) || (pos + 4 > bytes.size() && !whole_file)) return;
    if (pos + 4 > bytes.size()) throw InputError(file, "OpenEXR header: attribute " + name + " has no size (truncated)");
    std::uint32_t size = 0;
    for (int b = 3; b >= 0; --b) size = (size << 8) | bytes[pos + static_cast<std::size_t>(b)];
    pos += 4;
    if (size > file_bytes - pos)
      throw InputError(file, "OpenEXR header: attribute " + name + " declares " + std::to_string(size) +
                                 " bytes, more than the " + std::to_string(file_bytes - pos) +
                                 " left in the file (truncated or corrupt)");
    pos += size;
    if (pos >= bytes.size() && !whole_file) return;
  }
}

std::unique_ptr<OIIO::ImageInput> openOiio(const fs::path& file) {
  const std::uintmax_t file_bytes = requireReadableFile(file);
  requireExrHeadersFitFile(file, file_bytes);
  LibpngStderrCapture capture(hasPngSignature(file));
  auto in = OIIO::ImageInput::open(file.string());
  const std::vector<std::string> libpng_lines = capture.finish();
  if (!in) throw InputError(file, "cannot read as an image" + readFailureReason(OIIO::geterror(), libpng_lines));
  requireDecodableSize(file, in->spec(), file_bytes);
  return in;
}

ImageFileInfo infoFromSpec(const OIIO::ImageInput& in) {
  const OIIO::ImageSpec& spec = in.spec();
  ImageFileInfo info;
  info.width = spec.width;
  info.height = spec.height;
  info.channels = spec.nchannels;
  info.pixel_type = spec.format.c_str();
  info.format = in.format_name();
  return info;
}

// Reads channels [ch_begin, ch_end) in a cv type that keeps the stored values exactly.
cv::Mat readOiioChannels(const fs::path& file, OIIO::ImageInput& in, int ch_begin, int ch_end) {
  const OIIO::ImageSpec& spec = in.spec();
  const int channels = ch_end - ch_begin;
  int cv_depth = CV_32F;
  OIIO::TypeDesc want = OIIO::TypeDesc::FLOAT;
  switch (spec.format.basetype) {
    case OIIO::TypeDesc::UINT8: cv_depth = CV_8U; want = OIIO::TypeDesc::UINT8; break;
    case OIIO::TypeDesc::UINT16: cv_depth = CV_16U; want = OIIO::TypeDesc::UINT16; break;
    case OIIO::TypeDesc::INT8:
    case OIIO::TypeDesc::INT16:
    case OIIO::TypeDesc::INT32:
    case OIIO::TypeDesc::UINT32: cv_depth = CV_32S; want = OIIO::TypeDesc::INT32; break;
    case OIIO::TypeDesc::DOUBLE: cv_depth = CV_64F; want = OIIO::TypeDesc::DOUBLE; break;
    default: break;  // half and float read as float
  }
  cv::Mat out(spec.height, spec.width, CV_MAKETYPE(cv_depth, channels));
  LibpngStderrCapture capture(std::string(in.format_name()) == "png");
  const bool read = in.read_image(0, 0, ch_begin, ch_end, want, out.data);
  const std::vector<std::string> libpng_lines = capture.finish();
  if (!read)
    throw InputError(file, "cannot decode pixels, the file is truncated or corrupt" +
                               readFailureReason(in.geterror(), libpng_lines));
  return out;
}

cv::Mat readNative(const fs::path& file, ImageFileInfo& info) {
  if (isNpy(file)) {
    requireReadableFile(file);
    info = probeNpy(file);
    return readNpy(file);
  }
  auto in = openOiio(file);
  info = infoFromSpec(*in);
  return readOiioChannels(file, *in, 0, in->spec().nchannels);
}

/// The file's single-channel pixels as stored, or an InputError "<what> must have one channel".
cv::Mat readSingleChannel(const fs::path& file, ImageFileInfo& info, const char* what) {
  cv::Mat native = readNative(file, info);
  if (native.channels() != 1)
    throw InputError(file, std::string(what) + " must have one channel, found " + std::to_string(native.channels()));
  return native;
}

double maxCode(int cv_depth) { return cv_depth == CV_8U ? 255.0 : cv_depth == CV_16U ? 65535.0 : 1.0; }

// An OpenImageIO output proxy over a FILE* that remembers the first failed write: OpenImageIO's
// PNG writer ignores short writes (a full disk left a 0-byte PNG behind an exit code of 0), and
// libjpeg ends the process on one. So every write reports its bytes as taken, the first failure
// is kept, later writes are skipped, and finish() reports it. Not an IOFile: writers hand an
// IOFile's FILE* straight to their library, past these checks.
class CheckedOiioOutput : public OIIO::Filesystem::IOProxy {
 public:
  explicit CheckedOiioOutput(std::FILE* handle) : OIIO::Filesystem::IOProxy("", Write), handle_(handle) {}
  const char* proxytype() const override { return "solo-checked-file"; }
  size_t write(const void* buf, size_t size) override {
    const size_t written = pwrite(buf, size, m_pos);
    m_pos += static_cast<int64_t>(written);
    return written;
  }
  size_t pwrite(const void* buf, size_t size, int64_t offset) override {
    if (failure_ == 0) {
      errno = 0;
      if (::fseeko(handle_, offset, SEEK_SET) != 0 || std::fwrite(buf, 1, size, handle_) != size)
        failure_ = errno != 0 ? errno : EIO;
    }
    end_ = std::max(end_, static_cast<size_t>(offset) + size);
    return size;
  }
  size_t size() const override { return end_; }
  void flush() const override { std::fflush(handle_); }
  /// Flushes the buffered bytes; throws naming `target` when this or any earlier write failed.
  void finish(const fs::path& target) {
    if (failure_ == 0 && std::fflush(handle_) != 0) failure_ = errno;
    if (failure_ == 0 && std::ferror(handle_)) failure_ = EIO;
    if (failure_ != 0) throw InputError(target, std::string("write failed: ") + std::strerror(failure_));
  }

 private:
  std::FILE* handle_;
  size_t end_ = 0;
  int failure_ = 0;
};

// A FILE* open for writing, closed on every path; close() reports the error of the final close.
class OutputFileHandle {
 public:
  explicit OutputFileHandle(const fs::path& file) : handle_(std::fopen(file.c_str(), "wb")) {
    if (!handle_) throw InputError(file, std::string("cannot open for writing: ") + std::strerror(errno));
  }
  ~OutputFileHandle() {
    if (handle_) std::fclose(handle_);
  }
  OutputFileHandle(const OutputFileHandle&) = delete;
  OutputFileHandle& operator=(const OutputFileHandle&) = delete;
  std::FILE* get() const { return handle_; }
  /// Closes the file; throws naming `target` when the close fails.
  void close(const fs::path& target) {
    const int result = std::fclose(handle_);
    handle_ = nullptr;
    if (result != 0) throw InputError(target, std::string("write failed on close: ") + std::strerror(errno));
  }

 private:
  std::FILE* handle_;
};

std::string oiioError(const OIIO::ImageOutput& out) {
  std::string why = out.geterror();
  return why.empty() ? std::string("unknown error") : why;
}

// Writes `image` to `file` through OpenImageIO, checking every write and the final flush and
// close: PNG and JPEG through a checked proxy (their writers do not check), the other formats
// by OpenImageIO's own checks (its TIFF and OpenEXR writers report failed writes).
void writeOiio(const fs::path& file, const cv::Mat& image) {
  cv::Mat contiguous = image.isContinuous() ? image : image.clone();
  OIIO::TypeDesc type = oiioType(image.depth());
  if (type == OIIO::TypeDesc::UNKNOWN)
    throw InputError(file, "cannot write pixel type " + pixelTypeName(image.depth()));
  // Declared before the writer, destroyed after it: a writer closed by its destructor (on an
  // exception) still writes through a live proxy and file.
  std::optional<OutputFileHandle> handle;
  std::unique_ptr<CheckedOiioOutput> proxy;
  const std::string ext = lowercaseExtension(file);
  if (ext == ".png" || ext == ".jpg" || ext == ".jpeg") {
    handle.emplace(file);
    proxy = std::make_unique<CheckedOiioOutput>(handle->get());
  }
  auto out = OIIO::ImageOutput::create(file.string());
  if (!out) throw InputError(file, "no image writer for this extension (" + OIIO::geterror() + ")");
  OIIO::ImageSpec spec(image.cols, image.rows, image.channels(), type);
  // OpenImageIO stamps the write time unless DateTime is set: an empty one keeps outputs
  // byte-identical across runs, which seeded generation promises.
  spec.attribute("DateTime", "");
  if (proxy && !(out->supports("ioproxy") && out->set_ioproxy(proxy.get())))
    throw InputError(file, "cannot open for writing: this OpenImageIO takes no output proxy for " + ext);
  if (!out->open(file.string(), spec)) throw InputError(file, "cannot open for writing: " + oiioError(*out));
  if (!out->write_image(type, contiguous.data)) throw InputError(file, "write failed: " + oiioError(*out));
  if (!out->close()) throw InputError(file, "write failed on close: " + oiioError(*out));
  if (proxy) {
    proxy->finish(file);
    handle->close(file);
  }
  // A writer that reported success but left nothing behind failed all the same.
  std::error_code ec;
  if (fs::file_size(file, ec) == 0 || ec) throw InputError(file, "write failed: nothing was written");
}

// PFM (Portable Float Map): OpenImageIO reads it but has no writer. Little endian,
// rows stored bottom to top, 1 ("Pf") or 3 ("PF") float channels.
void writePfmTo(const fs::path& file, const cv::Mat& image) {
  if (image.depth() != CV_32F || (image.channels() != 1 && image.channels() != 3))
    throw InputError(file, "PFM stores 1 or 3 float channels, got " + std::to_string(image.channels()) + " " +
                               pixelTypeName(image.depth()));
  std::ofstream out(file, std::ios::binary);
  if (!out) throw InputError(file, "cannot open for writing");
  out << (image.channels() == 3 ? "PF" : "Pf") << "\n" << image.cols << " " << image.rows << "\n-1.0\n";
  const std::size_t row_bytes = static_cast<std::size_t>(image.cols) * image.elemSize();
  for (int y = image.rows - 1; y >= 0; --y)
    out.write(reinterpret_cast<const char*>(image.ptr(y)), static_cast<std::streamsize>(row_bytes));
  out.close();  // the last buffered bytes are written here: checked too
  if (!out) throw InputError(file, "write failed");
}

}  // namespace

// ----------------------------------------------------------------------------- public

std::string sizeText(int width, int height) { return std::to_string(width) + "x" + std::to_string(height); }

std::string sizeText(const cv::Mat& image) { return sizeText(image.cols, image.rows); }

ImageFileInfo probeImage(const fs::path& file) {
  if (isNpy(file)) {
    requireReadableFile(file);
    return probeNpy(file);
  }
  auto in = openOiio(file);
  return infoFromSpec(*in);
}

cv::Mat readNpy(const fs::path& file) {
  requireReadableFile(file);
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError(file, "cannot open for reading");
  NpyHeader h = parseNpyHeader(file, in);
  NpyType t = npyType(file, h.descr);
  if (h.fortran_order) throw InputError(file, "Fortran-ordered .npy arrays are not supported (save with C order)");
  if (h.shape.size() < 2 || h.shape.size() > 3)
    throw InputError(file, ".npy array must have shape (H, W) or (H, W, C)");
  const std::uint64_t rows = h.shape[0], cols = h.shape[1], channels = h.shape.size() == 3 ? h.shape[2] : 1;
  if (rows == 0 || cols == 0 || channels == 0 || channels > 4)
    throw InputError(file, ".npy shape is empty or has more than 4 channels");
  requireImageSizeWithinLimit(file, cols, rows);
  const std::optional<std::uint64_t> need_bytes = npyDataBytes(h.shape, t.bytes);
  const std::uintmax_t file_bytes = fs::file_size(file);
  const std::uintmax_t have = file_bytes > h.data_offset ? file_bytes - h.data_offset : 0;
  if (!need_bytes || have < *need_bytes)
    throw InputError(file, "truncated .npy data: the shape needs " +
                               (need_bytes ? std::to_string(*need_bytes) : std::string("more than 2^64")) +
                               " bytes, the file holds " + std::to_string(have));
  const std::size_t count = static_cast<std::size_t>(rows * cols * channels);
  const std::size_t need = static_cast<std::size_t>(*need_bytes);
  cv::Mat out(static_cast<int>(rows), static_cast<int>(cols), CV_MAKETYPE(t.cv_depth, static_cast<int>(channels)));
  if (!t.int64) {
    in.read(reinterpret_cast<char*>(out.data), static_cast<std::streamsize>(need));
  } else {
    std::vector<std::int64_t> wide(count);
    in.read(reinterpret_cast<char*>(wide.data()), static_cast<std::streamsize>(need));
    auto* dst = reinterpret_cast<std::int32_t*>(out.data);
    for (std::size_t i = 0; i < count; ++i) {
      if (wide[i] < INT32_MIN || wide[i] > INT32_MAX)
        throw InputError(file, "int64 value " + std::to_string(wide[i]) + " does not fit a label map");
      dst[i] = static_cast<std::int32_t>(wide[i]);
    }
  }
  if (!in) throw InputError(file, "read failed");
  return out;
}

void writeNpyTo(const fs::path& file, const cv::Mat& array) {
  std::string descr;
  switch (array.depth()) {
    case CV_32F: descr = "<f4"; break;
    case CV_64F: descr = "<f8"; break;
    case CV_8U: descr = "|u1"; break;
    case CV_16U: descr = "<u2"; break;
    case CV_32S: descr = "<i4"; break;
    default: throw InputError(file, "cannot write pixel type " + pixelTypeName(array.depth()) + " as .npy");
  }
  std::string shape = "(" + std::to_string(array.rows) + ", " + std::to_string(array.cols) +
                      (array.channels() > 1 ? ", " + std::to_string(array.channels()) + ")" : ")");
  std::string header = "{'descr': '" + descr + "', 'fortran_order': False, 'shape': " + shape + ", }";
  // Pad so that the data starts on a 64-byte boundary, header ends with '\n'.
  const std::size_t unpadded = 10 + header.size() + 1;
  header.append((64 - unpadded % 64) % 64, ' ');
  header.push_back('\n');
  std::ofstream out(file, std::ios::binary);
  if (!out) throw InputError(file, "cannot open for writing");
  const unsigned char prefix[10] = {0x93, 'N', 'U', 'M', 'P', 'Y', 1, 0,
                                    static_cast<unsigned char>(header.size() & 0xff),
                                    static_cast<unsigned char>(header.size() >> 8)};
  out.write(reinterpret_cast<const char*>(prefix), 10);
  out.write(header.data(), static_cast<std::streamsize>(header.size()));
  cv::Mat contiguous = array.isContinuous() ? array : array.clone();
  out.write(reinterpret_cast<const char*>(contiguous.data),
            static_cast<std::streamsize>(contiguous.total() * contiguous.elemSize()));
  out.close();  // the last buffered bytes are written here: checked too
  if (!out) throw InputError(file, "write failed");
}

cv::Mat readImageRaw(const fs::path& file, ImageFileInfo* info) {
  ImageFileInfo local;
  cv::Mat native = readNative(file, local);
  if (info) *info = local;
  cv::Mat out;
  native.convertTo(out, CV_MAKETYPE(CV_32F, native.channels()));
  return out;
}

cv::Mat readDepth(const fs::path& file, double scale_m_per_unit, DepthReadStats* stats, ImageFileInfo* info) {
  ImageFileInfo local;
  cv::Mat native;
  if (isNpy(file)) {
    native = readNative(file, local);
  } else {
    auto in = openOiio(file);
    local = infoFromSpec(*in);
    int channel = 0;
    if (local.channels > 1) {
      const auto& names = in->spec().channelnames;
      channel = -1;
      for (int c = 0; c < static_cast<int>(names.size()); ++c) {
        std::string n = names[c];
        std::transform(n.begin(), n.end(), n.begin(), [](unsigned char ch) { return std::tolower(ch); });
        if (n == "z" || n == "depth") channel = c;
      }
      if (channel < 0)
        throw InputError(file, "depth must have one channel, found " + std::to_string(local.channels) +
                                   " and none named Z or depth");
    }
    native = readOiioChannels(file, *in, channel, channel + 1);
  }
  if (native.channels() != 1)
    throw InputError(file, "depth must have one channel, found " + std::to_string(native.channels()));
  if (local.pixel_type == "uint8")
    throw InputError(file, "8-bit depth has only 256 levels; store depth as 16-bit PNG or float");
  const bool integer = isIntegerType(local.pixel_type) || local.pixel_type == "int64";
  if (integer && !(scale_m_per_unit > 0))
    throw InputError(file, local.pixel_type +
                               " depth needs a scale in metres per unit (\"depth\": {\"file\": ..., \"scale\": "
                               "0.00390625} for KITTI 1/256, 0.001 for millimetres)");
  if (!std::isfinite(scale_m_per_unit)) throw InputError(file, "depth scale is not finite");
  const double scale = scale_m_per_unit > 0 ? scale_m_per_unit : 1.0;

  cv::Mat values;
  native.convertTo(values, CV_64F);
  cv::Mat depth(values.rows, values.cols, CV_32F);
  DepthReadStats s;
  double lo = INFINITY, hi = -INFINITY;
  for (int y = 0; y < values.rows; ++y) {
    const double* src = values.ptr<double>(y);
    float* dst = depth.ptr<float>(y);
    for (int x = 0; x < values.cols; ++x) {
      const double v = src[x];
      float d = 0.f;
      if (std::isnan(v)) ++s.nan;
      else if (std::isinf(v)) ++s.inf;
      else if (v < 0) ++s.negative;
      else if (v == 0) ++s.zero;
      else {
        const double m = v * scale;
        if (!std::isfinite(static_cast<float>(m)) || static_cast<float>(m) <= 0.f) {
          ++s.inf;  // overflows or underflows float: unusable
        } else {
          ++s.valid;
          d = static_cast<float>(m);
          lo = std::min(lo, m);
          hi = std::max(hi, m);
        }
      }
      dst[x] = d;
    }
  }
  s.min_m = s.valid ? lo : 0;
  s.max_m = s.valid ? hi : 0;
  if (stats) *stats = s;
  if (info) *info = local;
  return depth;
}

cv::Mat decodeNormals(const cv::Mat& native_in, const fs::path& source, NormalReadStats& s) {
  cv::Mat native = native_in;
  if (native.channels() != 3 && native.channels() != 4)
    throw InputError(source, "normals need 3 channels (x, y, z), found " + std::to_string(native.channels()));
  if (native.channels() == 4) {
    std::vector<cv::Mat> planes;
    cv::split(native, planes);
    planes.resize(3);
    cv::merge(planes, native);
  }
  const bool encoded = native.depth() == CV_8U || native.depth() == CV_16U;
  if (!encoded && native.depth() != CV_32F && native.depth() != CV_64F)
    throw InputError(source, "normals must be 8/16-bit or float");
  const double code_max = maxCode(native.depth());
  // Length tolerance: quantisation of the format, or float rounding for float files.
  const double tolerance = encoded ? 2.0 * std::sqrt(3.0) / code_max : 1e-3;

  cv::Mat values;
  native.convertTo(values, CV_64FC3);
  cv::Mat normals(values.rows, values.cols, CV_32FC3);
  for (int y = 0; y < values.rows; ++y) {
    const cv::Vec3d* src = values.ptr<cv::Vec3d>(y);
    cv::Vec3f* dst = normals.ptr<cv::Vec3f>(y);
    for (int x = 0; x < values.cols; ++x) {
      cv::Vec3d v = src[x];
      dst[x] = cv::Vec3f(0, 0, 0);
      if (encoded) {
        if (v[0] == 0 && v[1] == 0 && v[2] == 0) {
          ++s.invalid;
          continue;
        }
        v = v * (2.0 / code_max) - cv::Vec3d(1, 1, 1);
      }
      if (!std::isfinite(v[0]) || !std::isfinite(v[1]) || !std::isfinite(v[2])) {
        ++s.invalid;
        continue;
      }
      const double length = cv::norm(v);
      if (length < 1e-6) {
        ++s.invalid;
        continue;
      }
      if (std::abs(length - 1.0) > tolerance) ++s.renormalised;
      v /= length;
      ++s.valid;
      dst[x] = cv::Vec3f(static_cast<float>(v[0]), static_cast<float>(v[1]), static_cast<float>(v[2]));
    }
  }
  return normals;
}

cv::Mat readNormals(const fs::path& file, NormalReadStats* stats, ImageFileInfo* info) {
  ImageFileInfo local;
  const cv::Mat native = readNative(file, local);
  const bool known_depth = native.depth() == CV_8U || native.depth() == CV_16U || native.depth() == CV_32F ||
                           native.depth() == CV_64F;
  if ((native.channels() == 3 || native.channels() == 4) && !known_depth)
    throw InputError(file, "normals must be 8/16-bit or float, found " + local.pixel_type);
  NormalReadStats s;
  cv::Mat normals = decodeNormals(native, file, s);
  if (stats) *stats = s;
  if (info) *info = local;
  return normals;
}

cv::Mat readLabels(const fs::path& file, ImageFileInfo* info) {
  ImageFileInfo local;
  const cv::Mat native = readSingleChannel(file, local, "label map");
  if (native.depth() != CV_8U && native.depth() != CV_16U && native.depth() != CV_32S)
    throw InputError(file, "label map must hold integers (8/16-bit PNG), found " + local.pixel_type);
  cv::Mat labels;
  native.convertTo(labels, CV_32S);
  if (info) *info = local;
  return labels;
}

cv::Mat readColorImage(const fs::path& file, ImageFileInfo* info) {
  ImageFileInfo local;
  cv::Mat native = readNative(file, local);
  const int channels = native.channels();
  if (channels != 1 && channels != 3 && channels != 4)
    throw InputError(file, "colour image needs 1, 3 or 4 channels, found " + std::to_string(channels));
  if (native.depth() == CV_32S) throw InputError(file, "colour image must be 8/16-bit or float, found " + local.pixel_type);
  cv::Mat rgb;
  if (channels == 1) {
    cv::merge(std::vector<cv::Mat>{native, native, native}, rgb);
  } else if (channels == 4) {
    std::vector<cv::Mat> planes;
    cv::split(native, planes);
    planes.resize(3);
    cv::merge(planes, rgb);
  } else {
    rgb = native;
  }
  cv::Mat out;
  rgb.convertTo(out, CV_32FC3, 1.0 / maxCode(native.depth()));
  if (info) *info = local;
  return out;
}

cv::Mat readScalarMap(const fs::path& file, ImageFileInfo* info) {
  ImageFileInfo local;
  const cv::Mat native = readSingleChannel(file, local, "scalar map");
  if (native.depth() == CV_32S) throw InputError(file, "scalar map must be 8/16-bit or float, found " + local.pixel_type);
  cv::Mat out;
  native.convertTo(out, CV_32F, 1.0 / maxCode(native.depth()));
  if (info) *info = local;
  return out;
}

void writeImage(const fs::path& file, const cv::Mat& image) {
  if (image.empty()) throw InputError(file, "refusing to write an empty image");
  const int channels = image.channels();
  if (channels != 1 && channels != 3 && channels != 4)
    throw InputError(file, "cannot write " + std::to_string(channels) + " channels");
  writeAtomically(file, [&](const fs::path& tmp) {
    if (isNpy(file)) writeNpyTo(tmp, image);
    else if (lowercaseExtension(file) == ".pfm") writePfmTo(tmp, image);
    else writeOiio(tmp, image);
  });
}

void writeDepth(const fs::path& file, const cv::Mat& depth_m, double scale_m_per_unit) {
  if (depth_m.type() != CV_32F) throw InputError(file, "depth to write must be CV_32F metres");
  if (lowercaseExtension(file) != ".png") {
    cv::Mat clean = depth_m.clone();
    clean.forEach<float>([](float& d, const int*) { if (!(std::isfinite(d) && d > 0)) d = 0.f; });
    writeImage(file, clean);
    return;
  }
  if (!(scale_m_per_unit > 0)) throw InputError(file, "16-bit depth PNG needs a positive scale");
  cv::Mat codes(depth_m.rows, depth_m.cols, CV_16U);
  for (int y = 0; y < depth_m.rows; ++y) {
    const float* src = depth_m.ptr<float>(y);
    std::uint16_t* dst = codes.ptr<std::uint16_t>(y);
    for (int x = 0; x < depth_m.cols; ++x) {
      const double d = src[x];
      if (!(std::isfinite(d) && d > 0)) { dst[x] = 0; continue; }
      // A valid depth never becomes 0 (= invalid); beyond the range it saturates.
      dst[x] = static_cast<std::uint16_t>(std::clamp(std::lround(d / scale_m_per_unit), 1L, 65535L));
    }
  }
  writeImage(file, codes);
}

void writeNormals(const fs::path& file, const cv::Mat& normals) {
  if (normals.type() != CV_32FC3) throw InputError(file, "normals to write must be CV_32FC3");
  if (lowercaseExtension(file) != ".png") {
    writeImage(file, normals);
    return;
  }
  cv::Mat codes(normals.rows, normals.cols, CV_16UC3);
  for (int y = 0; y < normals.rows; ++y) {
    const cv::Vec3f* src = normals.ptr<cv::Vec3f>(y);
    cv::Vec<std::uint16_t, 3>* dst = codes.ptr<cv::Vec<std::uint16_t, 3>>(y);
    for (int x = 0; x < normals.cols; ++x) {
      const cv::Vec3f n = src[x];
      if (!(std::isfinite(n[0]) && std::isfinite(n[1]) && std::isfinite(n[2])) || cv::norm(n) < 1e-6) {
        dst[x] = {0, 0, 0};
        continue;
      }
      for (int c = 0; c < 3; ++c) {
        // Code 0 on all three channels is reserved for "invalid": clamp to at least 1.
        const long code = std::lround((std::clamp(n[c], -1.f, 1.f) + 1.0) * 0.5 * 65535.0);
        dst[x][c] = static_cast<std::uint16_t>(std::clamp(code, 1L, 65535L));
      }
    }
  }
  writeImage(file, codes);
}

}  // namespace solo
