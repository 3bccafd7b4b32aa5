#include "solo/lighting/light_overlay.h"

#include "solo/lighting/colorimetry.h"

#include <solo/core/srgb.h>

#include <opencv2/imgproc.hpp>

#include <algorithm>

namespace solo {

Eigen::Vector3d displayColour(const Eigen::Vector2d& xy) {
  const Eigen::Vector3d rgb = (xyzToLinearSrgb() * bradfordEToD65() * xyzFromChromaticity(xy, 1.0)).cwiseMax(0.0);
  const double peak = rgb.maxCoeff();
  if (!(peak > 0)) return Eigen::Vector3d::Ones();
  const Eigen::Vector3d scaled = rgb / peak;
  const auto encode = [](double linear) { return linearToSrgb(std::clamp(linear, 0.0, 1.0)); };
  return {encode(scaled.x()), encode(scaled.y()), encode(scaled.z())};
}

cv::Mat drawLightOverlay(const cv::Mat& day_image, const LightGroupTree& tree, const std::vector<LightState>& states,
                         const LightOverlayOptions& options) {
  CV_Assert(day_image.type() == CV_32FC3 && day_image.cols == tree.width && day_image.rows == tree.height);
  CV_Assert(states.size() == tree.lights.size());
  cv::Mat canvas;
  day_image.convertTo(canvas, CV_8UC3, 255.0 * options.background_scale);
  for (std::size_t i = 0; i < tree.lights.size(); ++i) {
    const Eigen::Vector3d colour = displayColour(states[i].xy) * (states[i].on ? 1.0 : options.off_scale) * 255.0;
    const cv::Vec3b pixel(cv::saturate_cast<uchar>(colour.x()), cv::saturate_cast<uchar>(colour.y()),
                          cv::saturate_cast<uchar>(colour.z()));
    for (const PixelRun& run : tree.lights[i].runs)
      for (int x = run.first_col; x <= run.last_col; ++x) canvas.at<cv::Vec3b>(run.row, x) = pixel;
  }
  for (const LightGroup& group : tree.groups) {
    if (group.kind == LightGroupKind::Root || group.bbox.empty()) continue;
    const cv::Scalar colour = group.kind == LightGroupKind::BuildingFloor ? cv::Scalar(255, 220, 0) : cv::Scalar(0, 220, 255);
    cv::rectangle(canvas, group.bbox, colour, 1);
  }
  if (options.proposed)
    for (const Light& light : tree.lights)
      cv::rectangle(canvas, cv::Rect(light.bbox.x - 1, light.bbox.y - 1, light.bbox.width + 2, light.bbox.height + 2),
                    cv::Scalar(255, 0, 255), 1);
  return canvas;
}

}  // namespace solo
