#pragma once
// Writes tiny synthetic DNG files with known content (libtiff), so the raw gray-card path can be
// tested against a hand-computed answer: no camera raw with a known answer exists otherwise.

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include <cstdint>
#include <filesystem>
#include <string>

namespace solo::test {

struct SyntheticDng {
  enum class Layout {
    kLinearRaw,  ///< PhotometricInterpretation LinearRaw (34892): 3 samples per pixel, no demosaicing
    kBayerRggb,  ///< PhotometricInterpretation CFA (32803): one sample per pixel, RGGB 2x2 pattern
  };
  Layout layout = Layout::kLinearRaw;
  /// Raw sensor values including the black level, CV_16UC3 (channel 0 = camera R). For the Bayer
  /// layout only the channel of each pixel's filter colour is written.
  cv::Mat camera_raw;
  /// DNG ColorMatrix1: XYZ -> camera RGB, rows camera channels (stored as signed rationals).
  Eigen::Matrix3d color_matrix = Eigen::Matrix3d::Identity();
  int calibration_illuminant = 21;  ///< EXIF LightSource code of the matrix (21 = D65)
  Eigen::Vector3d as_shot_neutral{1, 1, 1};
  std::uint16_t black_level = 0;
  std::uint16_t white_level = 65535;
  std::string make = "Solo";
  std::string model = "Synthetic gray card";
};

/// Writes `dng` to `file` (uncompressed, little endian, one IFD). Throws std::runtime_error when
/// libtiff refuses a tag or the file cannot be written.
void writeSyntheticDng(const std::filesystem::path& file, const SyntheticDng& dng);

}  // namespace solo::test
