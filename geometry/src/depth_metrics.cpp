#include "solo/geometry/depth_metrics.h"

#include "solo/core/error.h"
#include "solo/core/quantile.h"

#include "evaluation_maps.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

namespace solo {
namespace {

constexpr EvaluatedMapKind kDepthMap{1, "depth needs", "readDepth"};

bool isValidDepth(double d) { return std::isfinite(d) && d > 0; }

}  // namespace

DepthMetrics evaluateDepth(const DepthEvaluationInput& in, const DepthMetricsOptions& options) {
  const cv::Mat pred = evaluatedMapAsDouble(in.prediction_m, kDepthMap, in.prediction_file, "prediction");
  const cv::Mat gt = evaluatedMapAsDouble(in.ground_truth_m, kDepthMap, in.ground_truth_file, "ground truth");
  const cv::Mat mask = checkedEvaluationMask(in, pred, gt);  // CV_8U, 255 where evaluated; or empty
  const double lower = options.min_depth_m.value_or(-HUGE_VAL);
  const double upper = options.max_depth_m.value_or(HUGE_VAL);
  if (!(lower < upper)) {
    char range[96];
    std::snprintf(range, sizeof range, "min depth %g m is not below max depth %g m", lower, upper);
    throw InputError(in.ground_truth_file, std::string("depth range is empty: ") + range);
  }

  DepthMetrics r;
  r.pixels = static_cast<std::int64_t>(gt.total());
  std::vector<double> g, p;  // the valid pixels, row-major
  for (int y = 0; y < gt.rows; ++y) {
    const double* gt_row = gt.ptr<double>(y);
    const double* pred_row = pred.ptr<double>(y);
    const unsigned char* mask_row = mask.empty() ? nullptr : mask.ptr<unsigned char>(y);
    for (int x = 0; x < gt.cols; ++x) {
      if (mask_row && !mask_row[x])
        ++r.masked_out;
      else if (!isValidDepth(gt_row[x]))
        ++r.ground_truth_invalid;
      else if (!(gt_row[x] > lower && gt_row[x] < upper))
        ++r.outside_range;
      else if (!isValidDepth(pred_row[x]))
        ++r.prediction_invalid;
      else {
        g.push_back(gt_row[x]);
        p.push_back(pred_row[x]);
      }
    }
  }
  r.valid_pixels = static_cast<std::int64_t>(g.size());
  if (g.empty())
    throw InputError(in.ground_truth_file, "no valid pixel to evaluate (of " + std::to_string(r.pixels) +
                                               " pixels: " + std::to_string(r.masked_out) + " masked out, " +
                                               std::to_string(r.ground_truth_invalid) + " without ground truth, " +
                                               std::to_string(r.outside_range) + " outside the depth range, " +
                                               std::to_string(r.prediction_invalid) + " without prediction)");

  if (options.median_scaling) {
    std::vector<double> g_copy = g, p_copy = p;
    r.scale = sampleQuantile(g_copy, 0.5) / sampleQuantile(p_copy, 0.5);
    for (double& v : p) v *= r.scale;
  }
  if (options.clamp_prediction)
    for (double& v : p) v = std::clamp(v, std::max(lower, 0.0), upper);

  double abs_rel = 0, sq_rel = 0, squared = 0, squared_log = 0;
  std::int64_t below1 = 0, below2 = 0, below3 = 0;
  for (std::size_t i = 0; i < g.size(); ++i) {
    const double diff = g[i] - p[i];
    abs_rel += std::abs(diff) / g[i];
    sq_rel += diff * diff / g[i];
    squared += diff * diff;
    const double log_diff = std::log(g[i]) - std::log(p[i]);
    squared_log += log_diff * log_diff;
    const double ratio = std::max(g[i] / p[i], p[i] / g[i]);
    below1 += ratio < 1.25;
    below2 += ratio < 1.25 * 1.25;
    below3 += ratio < 1.25 * 1.25 * 1.25;
  }
  const double n = static_cast<double>(g.size());
  r.abs_rel = abs_rel / n;
  r.sq_rel_m = sq_rel / n;
  r.rmse_m = std::sqrt(squared / n);
  r.rmse_log = std::sqrt(squared_log / n);
  r.delta1 = static_cast<double>(below1) / n;
  r.delta2 = static_cast<double>(below2) / n;
  r.delta3 = static_cast<double>(below3) / n;
  return r;
}

}  // namespace solo
