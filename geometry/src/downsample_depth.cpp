#include "solo/geometry/downsample_depth.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace solo {

cv::Mat downsampleDepth(const cv::Mat& depth_m, int factor, double max_relative_spread) {
  if (depth_m.type() != CV_32F) throw std::invalid_argument("downsampleDepth: depth map must be CV_32F");
  if (factor < 1) throw std::invalid_argument("downsampleDepth: factor must be at least 1");
  if (factor == 1) return depth_m.clone();
  const int width = depth_m.cols / factor, height = depth_m.rows / factor;
  cv::Mat out(std::max(height, 0), std::max(width, 0), CV_32F, cv::Scalar(0));
  cv::parallel_for_(cv::Range(0, height), [&](const cv::Range& rows) {
    for (int y = rows.start; y < rows.end; ++y)
      for (int x = 0; x < width; ++x) {
        double inverse_sum = 0, nearest = std::numeric_limits<double>::infinity(), farthest = 0;
        int valid = 0;
        for (int dy = 0; dy < factor; ++dy) {
          const float* row = depth_m.ptr<float>(y * factor + dy) + x * factor;
          for (int dx = 0; dx < factor; ++dx) {
            const double d = row[dx];
            if (!(d > 0) || !std::isfinite(d)) continue;
            ++valid;
            inverse_sum += 1.0 / d;
            nearest = std::min(nearest, d);
            farthest = std::max(farthest, d);
          }
        }
        if (valid == 0) continue;
        out.at<float>(y, x) = farthest <= nearest * (1 + max_relative_spread)
                                  ? static_cast<float>(valid / inverse_sum)
                                  : static_cast<float>(nearest);
      }
  });
  return out;
}

}  // namespace solo
