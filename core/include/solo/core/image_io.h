#pragma once
// Readers and writers for the maps a scene is made of. All images are cv::Mat with
// channels in RGB order (not OpenCV's BGR). Every reader validates and throws
// InputError naming the file and the problem.

#include <opencv2/core.hpp>

#include <cstdint>
#include <filesystem>
#include <string>

namespace solo {

/// What a file holds, as found in its header.
struct ImageFileInfo {
  int width = 0, height = 0, channels = 0;
  std::string pixel_type;  ///< "uint8", "uint16", "half", "float", "double", ...
  std::string format;      ///< "png", "openexr", "tiff", "pfm", "npy", ...
};

/// "WxH", e.g. "640x480", for messages and reports.
std::string sizeText(int width, int height);
/// The image's size as "WxH" (columns x rows).
std::string sizeText(const cv::Mat& image);

/// Header of an image file (any format OpenImageIO reads, plus .npy).
ImageFileInfo probeImage(const std::filesystem::path& file);

/// Whole image as stored, converted to CV_32F with the given channel count kept.
/// Integer pixel values are kept as numbers (not normalised): a uint16 65535 is 65535.0f.
/// Throws when the file is missing, unreadable, truncated, or cannot be decoded.
cv::Mat readImageRaw(const std::filesystem::path& file, ImageFileInfo* info = nullptr);

/// Counts of what the depth reader found. Invalid = 0, NaN, inf or negative.
struct DepthReadStats {
  std::int64_t valid = 0, zero = 0, nan = 0, inf = 0, negative = 0;
  double min_m = 0, max_m = 0;  ///< over valid pixels, metres
  std::int64_t invalid() const { return zero + nan + inf + negative; }
};

/// Metric z-depth, CV_32F, metres, invalid pixels set to 0.
/// scale_m_per_unit <= 0 means "not given". 16-bit PNG/TIFF (and integer NPY) need it:
/// metres = value * scale. Float EXR/TIFF, PFM and NPY (float32/float64) hold metres,
/// multiplied by the scale when one is given. One channel; a multi-channel EXR is read
/// from its "Z" or "depth" channel.
cv::Mat readDepth(const std::filesystem::path& file, double scale_m_per_unit,
                  DepthReadStats* stats = nullptr, ImageFileInfo* info = nullptr);

struct NormalReadStats {
  std::int64_t valid = 0;
  std::int64_t invalid = 0;       ///< zero vectors (or 0,0,0 stored in a PNG), or non-finite
  std::int64_t renormalised = 0;  ///< length off 1 by more than the format's precision
  std::int64_t back_facing = 0;   ///< n . viewing ray > 0; counted by loadScene, which knows the camera
};

/// Unit normals, CV_32FC3, camera frame (x right, y down, z forward), invalid = (0,0,0).
/// Float EXR/TIFF/PFM/NPY store n directly; 8/16-bit PNG stores n = v / max * 2 - 1 with
/// v = (0,0,0) meaning invalid. Three channels (a fourth, alpha, is ignored).
cv::Mat readNormals(const std::filesystem::path& file, NormalReadStats* stats = nullptr,
                    ImageFileInfo* info = nullptr);

/// Integer label map (Cityscapes labelIds/instanceIds, light ids, group ids), CV_32S.
/// 8- or 16-bit single-channel PNG/TIFF, or integer NPY.
cv::Mat readLabels(const std::filesystem::path& file, ImageFileInfo* info = nullptr);

/// Colour image, CV_32FC3, RGB, values as encoded (sRGB for PNG/JPEG) scaled to [0, 1].
/// 8/16-bit with 3 or 4 channels (alpha dropped), or a single grey channel (replicated).
cv::Mat readColorImage(const std::filesystem::path& file, ImageFileInfo* info = nullptr);

/// Single-channel material map (roughness) in [0, 1], CV_32F. Integer files are divided by
/// their maximum code value.
cv::Mat readScalarMap(const std::filesystem::path& file, ImageFileInfo* info = nullptr);

/// Writes a CV_32F depth map in metres, atomically, in the format of the extension:
/// .exr / .tif / .pfm / .npy store float metres (0 = invalid);
/// .png stores uint16 round(metres / scale_m_per_unit), clamped, 0 = invalid.
void writeDepth(const std::filesystem::path& file, const cv::Mat& depth_m,
                double scale_m_per_unit = 1.0 / 256.0);

/// Writes any CV_8U/CV_16U/CV_32F image with 1, 3 or 4 channels (RGB order) atomically,
/// choosing the format by extension (.png .jpg .exr .tif .pfm via OpenImageIO, .npy).
void writeImage(const std::filesystem::path& file, const cv::Mat& image);

/// Writes normals (CV_32FC3) atomically: float for .exr/.pfm/.npy/.tif; for .png 16-bit
/// v = (n + 1) / 2 * 65535 with invalid normals stored as (0,0,0).
void writeNormals(const std::filesystem::path& file, const cv::Mat& normals);

/// NumPy .npy (format 1.0/2.0, little endian, C order): float32/float64/uint8/uint16/
/// int32/int64 arrays of shape (H, W) or (H, W, C). Returned with its own depth
/// (CV_32F, CV_64F, CV_8U, CV_16U, CV_32S; int64 narrowed to CV_32S with a range check).
cv::Mat readNpy(const std::filesystem::path& file);
/// Writes a CV_32F/CV_64F/CV_8U/CV_16U/CV_32S Mat as .npy (not atomic: use writeImage).
void writeNpyTo(const std::filesystem::path& file, const cv::Mat& array);

}  // namespace solo
