#pragma once
// Element counts in mesh headers checked against the file size before a reader sizes its
// arrays from them: an OFF header claiming 10^9 faces in a few bytes must not take gigabytes.

#include <cstdint>
#include <filesystem>

namespace solo {

/// For OFF and PLY files (by extension), reads the header and throws InputError naming `file`
/// when the vertex and face counts it declares need more bytes than `file_size_bytes`, at the
/// smallest size each element can have in the header's encoding (ASCII or binary). Other
/// formats, and headers it cannot parse (left to the reader to reject), pass unchecked.
void requireMeshHeaderFitsFile(const std::filesystem::path& file, std::uintmax_t file_size_bytes);

}  // namespace solo
