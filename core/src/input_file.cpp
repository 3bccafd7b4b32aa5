#include "solo/core/input_file.h"

#include "solo/core/error.h"

#include <system_error>

namespace fs = std::filesystem;

namespace solo {
namespace {

std::string kindOf(fs::file_type type) {
  switch (type) {
    case fs::file_type::directory:
      return "a folder";
    case fs::file_type::character:
      return "a character device";
    case fs::file_type::block:
      return "a block device";
    case fs::file_type::fifo:
      return "a FIFO (named pipe)";
    case fs::file_type::socket:
      return "a socket";
    default:
      return "not a regular file";
  }
}

[[noreturn]] void throwStatusError(const fs::path& file, const std::string& what, const std::error_code& ec) {
  if (ec == std::errc::too_many_symbolic_link_levels)
    throw InputError(file, "symbolic link loop (too many levels of links), expected a " + what + " file");
  if (ec == std::errc::no_such_file_or_directory || ec == std::errc::not_a_directory) {
    std::error_code link_ec;
    if (fs::is_symlink(fs::symlink_status(file, link_ec)))
      throw InputError(file,
                       "file not found (broken symbolic link to " + fs::read_symlink(file, link_ec).string() + ")");
    throw InputError(file, "file not found");
  }
  throw InputError(file, "cannot access: " + ec.message());
}

}  // namespace

std::uintmax_t requireRegularFile(const fs::path& file, const std::string& what) {
  std::error_code ec;
  const fs::file_status status = fs::status(file, ec);
  if (status.type() == fs::file_type::not_found)
    throwStatusError(file, what, std::make_error_code(std::errc::no_such_file_or_directory));
  if (ec) throwStatusError(file, what, ec);
  if (status.type() != fs::file_type::regular)
    throw InputError(file, "is " + kindOf(status.type()) + ", expected a " + what + " file");
  const std::uintmax_t size = fs::file_size(file, ec);
  if (ec) throw InputError(file, "cannot read its size: " + ec.message());
  return size;
}

std::uintmax_t requireNonEmptyRegularFile(const fs::path& file, const std::string& what) {
  const std::uintmax_t size = requireRegularFile(file, what);
  if (size == 0) throw InputError(file, "file is empty");
  return size;
}

}  // namespace solo
