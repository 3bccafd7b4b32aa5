#pragma once
// Measures a light's chromaticity from a raw photo of a gray card it illuminates, as the
// Nighttime Illuminants dataset was made (reference section 2): the raw file (DNG or any
// camera raw LibRaw reads) is decoded through OpenImageIO's LibRaw plugin with no white
// balance scaling beyond the camera matrix's own daylight normalisation, linear output,
// no auto-brightening, black level subtracted, demosaiced and converted from camera RGB to
// CIE XYZ with the file's colour matrix; the region of interest is averaged and
// xy = (X, Y) / (X + Y + Z).

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
