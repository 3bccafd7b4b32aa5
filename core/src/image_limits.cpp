#include "solo/core/image_limits.h"

#include "solo/core/error.h"

#include <algorithm>
#include <cstdlib>
#include <limits>
#include <string>

namespace solo {

std::uint64_t maxImagePixels() {
  const char* text = std::getenv("SOLO_MAX_IMAGE_PIXELS");
  if (text == nullptr) return kDefaultMaxImagePixels;
  const std::string value(text);
  const bool digits = !value.empty() && value.size() <= 19 &&
                      std::all_of(value.begin(), value.end(), [](unsigned char c) { return std::isdigit(c); });
  if (!digits || std::stoull(value) == 0)
    throw InputError("SOLO_MAX_IMAGE_PIXELS", "expected a positive whole number of pixels, got \"" + value + "\"");
  return std::stoull(value);
}

void requireImageSizeWithinLimit(const std::filesystem::path& file, std::uint64_t width, std::uint64_t height) {
  if (width == 0 || height == 0) throw InputError(file, "image has no pixels");
  std::uint64_t pixels = 0;
  const std::uint64_t limit = maxImagePixels();
  const std::uint64_t side_limit = std::numeric_limits<int>::max();  // an OpenCV image's rows and columns
  if (__builtin_mul_overflow(width, height, &pixels) || pixels > limit || width > side_limit || height > side_limit)
    throw InputError(file, "image is " + std::to_string(width) + "x" + std::to_string(height) +
                               " pixels, more than the limit of " + std::to_string(limit) +
                               " pixels (raise it with the environment variable SOLO_MAX_IMAGE_PIXELS)");
}

}  // namespace solo
