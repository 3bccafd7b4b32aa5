#pragma once
// Surface normals of a depth map: the cross product of the backprojected surface's tangents
// along the image axes, oriented toward the camera. Used to write the refined depth's normals
// and to measure a depth map against true normals.

#include "solo/core/camera.h"

#include <opencv2/core.hpp>

namespace solo {

/// depth_m: CV_32F z-depth in metres (0 = invalid); camera at this resolution. Returns
/// CV_32FC3 unit normals in the camera frame with n . ray < 0, (0,0,0) where the pixel or
/// both neighbours along an axis are invalid. Along each axis the one-sided difference to the
/// neighbour of closer depth is used, so a normal never straddles a depth edge.
cv::Mat normalsFromDepth(const cv::Mat& depth_m, const PinholeCamera& camera);

}  // namespace solo
