#pragma once
// Depth completion ("complete", the refinement's step after upsampling): every pixel that is not
// sky gets a depth, so the mesh has no hole and the night image no black speck where a stereo
// matcher or a LiDAR had no return. docs/depth-refinement.md has the method and its measurements.
//
// Method, in inverse depth q = 1/z (a plane's q is affine in the pixel coordinates, so an
// interpolation of q keeps planes planar where a harmonic one of z would bend them):
// 1. Sky: labelIds == 23 when the scene has labels; without labels, an invalid pixel is sky when
//    no pixel above it holds a depth in its column or the columns within sky_column_window of
//    it (the sky is the top of every column; a LiDAR's columns between returns are not sky).
// 2. Above the first depth of its column, a hole takes the nearest depth below it of its own
//    segment: a vertical surface (a facade, the back of a vehicle) keeps its depth along an
//    image column, and nothing above says otherwise (the top of a facade above a LiDAR's
//    highest beam, a textureless wall under the sky). Where its segment has no depth below it
//    in the column (a car is the column's highest return), it is left to step 3 when the
//    segment has depth elsewhere, and takes the nearest depth below it when the segment has none.
//    Labelled scenes only (without labels the holes above a column's first depth lie between a
//    sparse sensor's returns).
// 3. Within each segment (instance id, or label id without instances): the segment's holes are
//    filled from its own valid pixels by pull-push interpolation (Gortler et al. 1996), so a hole
//    is never filled across an instance border from a segment that has depth of its own. A
//    planar segment (its inverse depth fits a plane to planar_tolerance: the road) interpolates
//    its residual from that plane, so a hole at the image's edge continues the plane instead of
//    holding the depth of its far side.
// 4. Segments with no valid pixel at all (a pole the matcher missed, the ego vehicle): filled by
//    the same interpolation from every valid or filled pixel, across their borders.
// 5. Edge-aware relaxation: red-black over-relaxed Gauss-Seidel sweeps of a membrane over the filled pixels (valid pixels
//    fixed), neighbour weights exp(-|I(p) - I(q)|^2 / 2 sigma^2) from the day image and 0 across
//    segment borders, so filled depth follows the image's edges within a segment (the pixels of
//    step 2 keep their column's depth; a planar segment relaxes its residual from the plane).
// Sparse depth (projected LiDAR) goes through the same steps: pull-push is a scattered-data
// interpolator. The output is clamped to the valid depths' range.

#include "solo/core/report.h"

#include <opencv2/core.hpp>

namespace solo {

struct DepthCompletionOptions {
  /// Relaxation sweeps over the filled pixels (0: pull-push only). docs/depth-refinement.md
  /// has the accuracy-versus-time curve.
  int relax_iterations = 40;
  /// Colour sigma of the relaxation's edge weights, sRGB [0, 1] units of the day image.
  double sigma_color = 0.08;
  /// Without labels: the columns each side whose first depth bounds the sky, as a share of the
  /// image width (1 %: 19 px at 1920, wider than a LiDAR's gaps between returns).
  double sky_column_window = 0.01;
  /// A segment is planar when the median distance of its inverse depths from their fitted
  /// plane is below this share of their median (a road: 0.1-0.5 %; two facades: 5-20 %).
  double planar_tolerance = 0.02;
  /// Successive over-relaxation factor of the sweeps, in (0, 2); 1 is plain Gauss-Seidel.
  double over_relaxation = 1.8;
};

struct DepthCompletionResult {
  cv::Mat depth_m;      ///< CV_32F metres; every non-sky pixel > 0, sky 0
  cv::Mat filled;       ///< CV_8U, 255 where the depth was filled
  cv::Mat sky;          ///< CV_8U, 255 where the pixel is sky (left without depth)
  StageReport report;   ///< "complete": pixels filled, their share, the sky rule, segments, time
};

/// depth_m: CV_32F metres, 0 = invalid. image: CV_32FC3 sRGB [0, 1] of the same size (the edge
/// guide; empty: uniform weights). labels, instances: CV_32S of the same size or empty. Valid
/// input pixels are returned unchanged. A depth map with no valid pixel is returned as it is.
DepthCompletionResult completeDepth(const cv::Mat& depth_m, const cv::Mat& image, const cv::Mat& labels,
                                    const cv::Mat& instances, const DepthCompletionOptions& options = {});

/// Pull-push interpolation: `value` (CV_32F) where `weight` (CV_32F in [0, 1]) is positive,
/// interpolated everywhere else from a pyramid of weighted 2x2 averages, each level bilinearly
/// upsampled into the holes of the level below. Returns the dense CV_32F map (all 0 when no
/// weight is positive).
cv::Mat pullPushInterpolate(const cv::Mat& value, const cv::Mat& weight);

}  // namespace solo
