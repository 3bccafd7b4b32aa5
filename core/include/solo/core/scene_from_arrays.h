#pragma once
// What loadScene does to maps and a camera it has read, for scenes built from arrays already in
// memory (the Python module): the same decoding, camera fitting and counts, the same messages.

#include "solo/core/camera.h"
#include "solo/core/image_io.h"
#include "solo/core/scene.h"

#include <opencv2/core.hpp>

#include <cstdint>
#include <filesystem>
#include <string>

namespace solo {

/// readNormals' decoding of an array (3 or 4 channels, 8/16-bit codes or float): a new
/// CV_32FC3 map, counts in `stats` (back_facing untouched). Errors name `source`.
cv::Mat decodeNormals(const cv::Mat& native, const std::filesystem::path& source, NormalReadStats& stats);

/// The warning of a scene without a camera: defaultSceneCamera's intrinsics in words.
std::string defaultCameraWarning(const PinholeCamera& camera);

/// Sets s.camera from `camera` as loadScene does: a resolution of 0 means the image's; validated
/// (errors name `source`); scaled to s.image, with a warning when the aspect ratios differ by
/// more than 1 %.
void setCameraForImage(PinholeCamera camera, const std::filesystem::path& source, Scene& s);

/// Valid normals facing away from the camera: visible surfaces have n . (K^-1 (u, v, 1)) < 0,
/// taken at the normal map's own resolution.
std::int64_t countBackFacingNormals(const cv::Mat& normals, const PinholeCamera& camera);

}  // namespace solo
