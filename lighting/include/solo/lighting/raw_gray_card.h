#pragma once
// Measures a light's chromaticity from a raw photo of a gray card it illuminates, as the
// Nighttime Illuminants dataset was made (reference section 2). The raw file (DNG or any camera
// raw LibRaw reads) is decoded through OpenImageIO's LibRaw plugin: black level subtracted,
// demosaiced (a LinearRaw DNG is not), camera RGB -> CIE XYZ with the file's colour matrix (for a
// DNG, XYZ = ColorMatrix^-1 * camera RGB up to one common scale: LibRaw's per-channel daylight
// gains cancel against its matrix), linear, no auto-brightening, and no camera white balance
// (AsShotNeutral is ignored). The region's mean XYZ gives xy = (X, Y) / (X + Y + Z).
// Saturation: a pixel counts as clipped when a camera channel reaches the white level (read a
// second time with unit gains) or an XYZ value reaches the 16-bit output limit. LibRaw 0.20
// scales a LinearRaw DNG with a black level by the white level instead of (white - black), so
// its saturated pixels stay below 1 and are not counted; Bayer files are counted exactly.
// Tested on synthetic DNGs (tests/lighting/test_raw_gray_card.cpp).

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include <cstdint>
#include <filesystem>
#include <string>

namespace solo {

struct GrayCardMeasurement {
  Eigen::Vector3d xyz = Eigen::Vector3d::Zero();  ///< mean over the region, relative units
  Eigen::Vector2d xy{0, 0};
  std::int64_t pixels = 0;   ///< in the region
  std::int64_t clipped = 0;  ///< pixels with a channel at the white level (saturated)
  std::string camera;        ///< make and model from the metadata
};

/// Throws InputError naming the file when it cannot be read as a raw photo, when the
/// region (pixels, x y width height) is empty or leaves the image, or when the region
/// is black.
GrayCardMeasurement measureGrayCard(const std::filesystem::path& raw_file, const cv::Rect& region);

}  // namespace solo
