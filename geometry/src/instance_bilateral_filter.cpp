#include "solo/geometry/instance_bilateral_filter.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <map>
#include <vector>

namespace solo {
namespace {

struct LabelBox {
  int x0 = 1 << 30, y0 = 1 << 30, x1 = -1, y1 = -1;  // inclusive bounds of the label's valid pixels
};

}  // namespace

InstanceBilateralFilterResult instanceBilateralFilter(const cv::Mat& depth_m, const cv::Mat& instances,
                                                      const InstanceBilateralFilterOptions& options) {
  CV_Assert(depth_m.type() == CV_32F);
  CV_Assert(instances.empty() || (instances.type() == CV_32S && instances.size() == depth_m.size()));
  CV_Assert(options.sigma_spatial_px > 0 && options.window_sigmas > 0);
  Stopwatch clock;
  InstanceBilateralFilterResult result;
  result.report.name = "filter";
  const int radius = std::max(1, static_cast<int>(std::ceil(options.window_sigmas * options.sigma_spatial_px)));
  const cv::Mat kernel = cv::getGaussianKernel(2 * radius + 1, options.sigma_spatial_px, CV_32F);

  const bool have_labels = !instances.empty();
  if (!have_labels)
    result.report.notes.push_back("no instances: the filter ran without the label term (a Gaussian over valid pixels)");

  // Bounding boxes of every label's valid pixels.
  std::map<int, LabelBox> boxes;
  int cached_label = 0;
  LabelBox* cached_box = nullptr;  // labels come in runs along a row: skip most map lookups
  for (int y = 0; y < depth_m.rows; ++y) {
    const float* d = depth_m.ptr<float>(y);
    const int* h = have_labels ? instances.ptr<int>(y) : nullptr;
    for (int x = 0; x < depth_m.cols; ++x) {
      if (!(d[x] > 0) || !std::isfinite(d[x])) continue;
      const int label = h ? h[x] : 0;
      if (!cached_box || label != cached_label) cached_label = label, cached_box = &boxes[label];
      LabelBox& b = *cached_box;
      b.x0 = std::min(b.x0, x), b.x1 = std::max(b.x1, x), b.y0 = std::min(b.y0, y), b.y1 = std::max(b.y1, y);
    }
  }

  result.depth_m = cv::Mat(depth_m.size(), CV_32F, cv::Scalar(0));
  double change_sum = 0;
  std::int64_t filtered = 0;
  std::int64_t summed_box_area = 0;
  for (const auto& [label, box] : boxes) {
    // The label's pixels only influence pixels within `radius` of themselves: filter the box
    // grown by the radius, with zero outside the image (which excludes it from both sums).
    const cv::Rect roi = cv::Rect(box.x0 - radius, box.y0 - radius, box.x1 - box.x0 + 1 + 2 * radius,
                                  box.y1 - box.y0 + 1 + 2 * radius) &
                         cv::Rect(0, 0, depth_m.cols, depth_m.rows);
    summed_box_area += roi.area();
    cv::Mat weight(roi.size(), CV_32F, cv::Scalar(0)), weighted(roi.size(), CV_32F, cv::Scalar(0));
    for (int y = 0; y < roi.height; ++y) {
      const float* d = depth_m.ptr<float>(roi.y + y) + roi.x;
      const int* h = have_labels ? instances.ptr<int>(roi.y + y) + roi.x : nullptr;
      float* w = weight.ptr<float>(y);
      float* wd = weighted.ptr<float>(y);
      for (int x = 0; x < roi.width; ++x)
        if (d[x] > 0 && std::isfinite(d[x]) && (!h || h[x] == label)) w[x] = 1.f, wd[x] = d[x];
    }
    // Depths are centred on the box mean before the sums so float sums keep their precision
    // when near (0.5 m) and far (1000 m) depths share an image.
    const double mean = cv::mean(weighted, weight > 0)[0];
    cv::Mat centred = (weighted - mean).mul(weight);
    cv::Mat weight_sum, depth_sum;
    cv::sepFilter2D(weight, weight_sum, CV_32F, kernel, kernel, cv::Point(-1, -1), 0, cv::BORDER_CONSTANT);
    cv::sepFilter2D(centred, depth_sum, CV_32F, kernel, kernel, cv::Point(-1, -1), 0, cv::BORDER_CONSTANT);
    for (int y = 0; y < roi.height; ++y) {
      const float* w = weight.ptr<float>(y);
      const float* ws = weight_sum.ptr<float>(y);
      const float* ds = depth_sum.ptr<float>(y);
      const float* d = depth_m.ptr<float>(roi.y + y) + roi.x;
      float* out = result.depth_m.ptr<float>(roi.y + y) + roi.x;
      for (int x = 0; x < roi.width; ++x) {
        if (w[x] == 0) continue;  // not this label's pixel
        // ws >= the centre weight > 0: the pixel itself is always in its own sums.
        out[x] = static_cast<float>(mean + ds[x] / ws[x]);
        change_sum += std::abs(out[x] - d[x]);
        ++filtered;
      }
    }
  }

  result.report.add("sigma_spatial", options.sigma_spatial_px, "px");
  result.report.add("window", std::int64_t{2 * radius + 1}, "px");
  result.report.add("label_term", have_labels);
  result.report.add("labels", static_cast<std::int64_t>(boxes.size()));
  result.report.add("filtered_pixels", filtered);
  result.report.add("summed_label_box_area_ratio",
                    depth_m.total() ? static_cast<double>(summed_box_area) / static_cast<double>(depth_m.total()) : 0.0);
  result.report.add("mean_abs_change", filtered ? change_sum / static_cast<double>(filtered) : 0.0, "m");
  result.report.seconds = clock.seconds();
  return result;
}

}  // namespace solo
