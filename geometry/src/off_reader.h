#pragma once
// solo's own reader of plain ASCII OFF: CGAL's scanner converts negative and huge face counts and
// indices from double to size_t (undefined behaviour), sizes faces from counts before reading
// them, and reads colour variants past its buffers; its comment and keyword handling differ
// from the files' in ways a check in front of it cannot follow.

#include <array>
#include <cstddef>
#include <filesystem>
#include <vector>

namespace solo {

/// Reads `file` as plain ASCII OFF: the word OFF, the vertex, face and edge counts, the vertices
/// (three numbers each, read as a stream of numbers: the counts' line may carry the first), then
/// one face a line (its vertex count n, then n indices; what follows them, a colour, is
/// ignored). '#' starts a comment to the end of its line; blank lines are skipped. Throws
/// InputError naming `file` for any other keyword (COFF, NOFF, 4OFF, OFF BINARY, ...), counts
/// that are not whole numbers, a coordinate that is not a number, a face whose count or index
/// is not a whole number from 0 to 2^53 or that lists fewer indices than it declares, and a
/// file that ends before its vertices and faces. Indices are not checked against the vertex
/// count here (readMesh names a face that refers to a missing vertex). Coordinates may be
/// non-finite (readMesh refuses them naming the vertex).
void readPlainOff(const std::filesystem::path& file, std::vector<std::array<double, 3>>& points,
                  std::vector<std::vector<std::size_t>>& polygons);

}  // namespace solo
