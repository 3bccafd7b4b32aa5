#pragma once
// Downsampling a depth map by an integer factor for a coarser mesh (the draft preset's
// `--mesh-downsample`): fewer vertices, faces and a faster BVH, at the cost of detail.

#include <opencv2/core.hpp>

namespace solo {

/// depth_m: CV_32F metres, 0 / negative / non-finite = no depth. factor >= 1 (1 returns a
/// copy). Output: CV_32F of size (cols / factor, rows / factor) (remainder columns and rows are
/// dropped), one value per factor x factor block:
///  - no valid pixel in the block: 0 (no depth);
///  - all valid depths within `max_relative_spread` of each other (max / min - 1): the mean of
///    their inverse depths, inverted. Inverse depth is affine in the image on a plane, so a
///    fully valid block on a plane gives the plane's depth at the block's centre exactly, the
///    centre of the coarse pixel under PinholeCamera::scaledTo;
///  - otherwise (the block straddles an occlusion edge): the nearest depth, so thin occluders
///    (poles, signs one pixel wide) stay in the coarse map instead of averaging into a
///    floating value between the two surfaces.
/// Throws std::invalid_argument for another type or factor < 1.
cv::Mat downsampleDepth(const cv::Mat& depth_m, int factor, double max_relative_spread = 0.05);

}  // namespace solo
