#pragma once
// A picture of the instantiated lights for checking them by eye: the day image darkened,
// every light's pixels in the colour of its chromaticity (bright when on, dimmed when off),
// and each group's outline (its mask's bounding box: vehicles cyan, floors yellow). Lights
// proposed from the labels (no light map given) are each framed in magenta.

#include "solo/lighting/light_groups.h"
#include "solo/lighting/light_instantiation.h"

#include <Eigen/Core>
#include <opencv2/core.hpp>

namespace solo {

struct LightOverlayOptions {
  double background_scale = 0.5;  ///< the day image's brightness under the lights
  double off_scale = 0.3;         ///< brightness of a light that is off, relative to on
  /// The lights were proposed from the labels (light_proposals.h): each light gets a 1-pixel
  /// magenta (RGB 255, 0, 255) frame one pixel outside its bounding box, drawn over the groups.
  bool proposed = false;
};

/// sRGB-encoded display colour of a chromaticity relative to white E, at the largest
/// brightness that fits in [0, 1]: XYZ -> Bradford E to D65 -> linear sRGB (negatives
/// clipped) -> scaled to a maximum of 1 -> sRGB curve.
Eigen::Vector3d displayColour(const Eigen::Vector2d& xy);

/// `day_image`: CV_32FC3 sRGB-encoded RGB at the tree's resolution; `states` per
/// tree.lights. Returns CV_8UC3, RGB order.
cv::Mat drawLightOverlay(const cv::Mat& day_image, const LightGroupTree& tree, const std::vector<LightState>& states,
                         const LightOverlayOptions& options = {});

}  // namespace solo
