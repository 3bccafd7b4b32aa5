#include "solo/geometry/uncertain_regions.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>

namespace solo {

UncertainRegionResult findUncertainRegions(const cv::Mat& depth_m, const cv::Mat& labels,
                                           const UncertainRegionOptions& options) {
  CV_Assert(depth_m.type() == CV_32F && labels.type() == CV_32S && labels.size() == depth_m.size());
  CV_Assert(options.window_px >= 1);
  Stopwatch clock;
  UncertainRegionResult result;
  result.report.name = "uncertain";
  result.mask = cv::Mat(depth_m.size(), CV_8U, cv::Scalar(0));
  const int kx = std::min(options.window_px, depth_m.cols), ky = std::min(options.window_px, depth_m.rows);

  cv::Mat valid = depth_m > 0;
  double min_depth = 0, max_depth = 0;
  if (cv::countNonZero(valid) > 0) cv::minMaxLoc(depth_m, &min_depth, &max_depth, nullptr, nullptr, valid);
  const double r = options.max_depth_m > 0 ? options.max_depth_m : (min_depth + max_depth) / 2;

  // Window sums of valid count, depth and depth^2 from double integral images. Depths are
  // centred on the mid-range first so the squares keep their precision.
  cv::Mat centred(depth_m.size(), CV_64F, cv::Scalar(0)), valid_d;
  depth_m.convertTo(centred, CV_64F, 1.0, -r);
  centred.setTo(0, ~valid);
  valid.convertTo(valid_d, CV_64F, 1.0 / 255);
  cv::Mat sum, square_sum, count;
  cv::integral(centred, sum, square_sum, CV_64F, CV_64F);
  cv::integral(valid_d, count, CV_64F);
  const auto box = [&](const cv::Mat& s, int x, int y) {
    return s.at<double>(y + ky, x + kx) - s.at<double>(y, x + kx) - s.at<double>(y + ky, x) + s.at<double>(y, x);
  };

  // Windows with two labels or more: the window's smallest and largest label differ.
  cv::Mat labels_f, label_min, label_max, depth_max;
  labels.convertTo(labels_f, CV_32F);  // ids < 2^24 are exact in float
  const cv::Mat kernel = cv::Mat::ones(ky, kx, CV_8U);
  cv::erode(labels_f, label_min, kernel, cv::Point(0, 0), 1, cv::BORDER_REPLICATE);
  cv::dilate(labels_f, label_max, kernel, cv::Point(0, 0), 1, cv::BORDER_REPLICATE);
  cv::dilate(depth_m, depth_max, kernel, cv::Point(0, 0), 1, cv::BORDER_REPLICATE);

  cv::Mat flagged(depth_m.size(), CV_8U, cv::Scalar(0));  // window anchors (top-left corners)
  std::int64_t windows = 0, uncertain_windows = 0;
  for (int y = 0; y + ky <= depth_m.rows; ++y)
    for (int x = 0; x + kx <= depth_m.cols; ++x) {
      ++windows;
      if (label_min.at<float>(y, x) == label_max.at<float>(y, x)) continue;
      if (depth_max.at<float>(y, x) > r) continue;
      const double n = box(count, x, y);
      if (n < 2) continue;
      const double s = box(sum, x, y), s2 = box(square_sum, x, y);
      const double variance = std::max(0.0, (s2 - s * s / n) / n);
      if (variance > options.variance_threshold_m2) {
        flagged.at<uchar>(y, x) = 255;
        ++uncertain_windows;
      }
    }
  // Every pixel of a flagged window: a pixel is covered by anchors up to k - 1 above/left.
  cv::dilate(flagged, result.mask, kernel, cv::Point(kx - 1, ky - 1), 1, cv::BORDER_CONSTANT, cv::Scalar(0));

  const auto uncertain = static_cast<std::int64_t>(cv::countNonZero(result.mask));
  result.report.add("window", std::int64_t{options.window_px}, "px");
  result.report.add("variance_threshold", options.variance_threshold_m2, "m^2");
  result.report.add("max_depth", r, "m");
  result.report.add("windows", windows);
  result.report.add("uncertain_windows", uncertain_windows);
  result.report.add("uncertain_pixels", uncertain);
  result.report.add("uncertain_share", depth_m.total() ? static_cast<double>(uncertain) / depth_m.total() : 0.0);
  result.report.seconds = clock.seconds();
  return result;
}

}  // namespace solo
