#pragma once
// Inputs are read only from regular files: a device, FIFO, socket or folder given where a file
// is expected would block, never end, or fail deep inside a library with a raw message.

#include <cstdint>
#include <filesystem>
#include <string>

namespace solo {

/// Checks that `file` (symbolic links followed) is an existing regular file and returns its
/// size in bytes. `what` names the expected content in messages ("scene manifest", "depth map").
/// Throws InputError naming the file when it is missing, a broken symbolic link or a link loop,
/// inaccessible, or a folder, character or block device, FIFO or socket.
std::uintmax_t requireRegularFile(const std::filesystem::path& file, const std::string& what);

/// requireRegularFile, and also refuses an empty file ("file is empty"). Returns the size in bytes.
std::uintmax_t requireNonEmptyRegularFile(const std::filesystem::path& file, const std::string& what);

}  // namespace solo
