#pragma once
// The largest image solo decodes, checked from a file's header before any pixel memory is
// taken: a small compressed file can declare billions of pixels.

#include <cstdint>
#include <filesystem>

namespace solo {

/// Default maximum pixel count of an image or map: 2^28 (268435456, e.g. 16384 x 16384).
constexpr std::uint64_t kDefaultMaxImagePixels = std::uint64_t{1} << 28;

/// The maximum pixel count: the environment variable SOLO_MAX_IMAGE_PIXELS when set (a
/// positive decimal integer), else kDefaultMaxImagePixels. Throws InputError naming the
/// variable when it is set to anything else.
std::uint64_t maxImagePixels();

/// Throws InputError naming `file` when `width` x `height` (pixels) is zero or more than
/// maxImagePixels(), or a side exceeds 2^31 - 1; the product is computed without overflow.
void requireImageSizeWithinLimit(const std::filesystem::path& file, std::uint64_t width, std::uint64_t height);

}  // namespace solo
