#pragma once
// Element counts in mesh headers checked against the file size before a reader sizes its
// arrays from them: an OFF header claiming 10^9 faces in a few bytes must not take gigabytes.

#include <cstdint>
#include <filesystem>

namespace solo {

/// For OFF and PLY files (by extension), reads the header and throws InputError naming `file`
/// when the vertex and face counts it declares need more bytes than `file_size_bytes`, at the
/// smallest size each element can have in the header's encoding (ASCII or binary). Other
/// formats, and headers it cannot parse (left to the reader to reject), pass unchecked. Also
/// refuses what CGAL's readers would dereference or convert with undefined behaviour: a PLY
/// header with a property before any element, a non-numeric element count, a vertex
/// coordinate that is not float or double or no end_header in 64 KiB; a PLY list (ASCII or binary) whose size is negative or needs more bytes than
/// the file has after it (CGAL's reader sizes a vector from it first), found by walking the
/// body as the reader does.
void requireMeshHeaderFitsFile(const std::filesystem::path& file, std::uintmax_t file_size_bytes);

}  // namespace solo
