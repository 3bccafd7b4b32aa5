#include "solo/geometry/depth_metrics.h"

#include "solo/core/error.h"
#include "solo/core/quantile.h"

#include "evaluation_maps.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

namespace solo {
namespace {

constexpr EvaluatedMapKind kDepthMap{1, "depth needs", "readDepth"};

bool isValidDepth(double d) { return std::isfinite(d) && d > 0; }

/// The error sums of the valid pixels' ground truth g and prediction p.
DepthErrorSums errorSums(const std::vector<double>& g, const std::vector<double>& p) {
  DepthErrorSums s;
  s.count = static_cast<std::int64_t>(g.size());
  for (std::size_t i = 0; i < g.size(); ++i) {
    const double diff = g[i] - p[i];
    s.abs_rel += std::abs(diff) / g[i];
    s.sq_rel_m += diff * diff / g[i];
    s.squared_m2 += diff * diff;
    const double log_diff = std::log(g[i]) - std::log(p[i]);
    s.squared_log += log_diff * log_diff;
    s.log_difference -= log_diff;
    const double ratio = std::max(g[i] / p[i], p[i] / g[i]);
    s.below1 += ratio < 1.25;
    s.below2 += ratio < 1.25 * 1.25;
    s.below3 += ratio < 1.25 * 1.25 * 1.25;
  }
  return s;
}

/// Sets r's metrics (and valid_pixels) to those of `s` (s.count > 0).
void setMetricsFromSums(DepthMetrics& r, const DepthErrorSums& s) {
  r.sums = s;
  r.valid_pixels = s.count;
  const double n = static_cast<double>(s.count);
  r.abs_rel = s.abs_rel / n;
  r.sq_rel_m = s.sq_rel_m / n;
  r.rmse_m = std::sqrt(s.squared_m2 / n);
  r.rmse_log = std::sqrt(s.squared_log / n);
  const double mean_log = s.log_difference / n;
  // mean(e^2) - mean(e)^2 >= 0 in exact arithmetic; rounding can take it just below.
  r.silog = std::sqrt(std::max(0.0, s.squared_log / n - mean_log * mean_log));
  r.delta1 = static_cast<double>(s.below1) / n;
  r.delta2 = static_cast<double>(s.below2) / n;
  r.delta3 = static_cast<double>(s.below3) / n;
}

}  // namespace

DepthErrorSums& DepthErrorSums::operator+=(const DepthErrorSums& o) {
  count += o.count;
  abs_rel += o.abs_rel;
  sq_rel_m += o.sq_rel_m;
  squared_m2 += o.squared_m2;
  squared_log += o.squared_log;
  log_difference += o.log_difference;
  below1 += o.below1;
  below2 += o.below2;
  below3 += o.below3;
  return *this;
}

void addDepthPixelAccounting(DepthMetrics& to, const DepthMetrics& other) {
  to.pixels += other.pixels;
  to.masked_out += other.masked_out;
  to.ground_truth_invalid += other.ground_truth_invalid;
  to.outside_range += other.outside_range;
  to.prediction_invalid += other.prediction_invalid;
  to.valid_pixels += other.valid_pixels;
}

DepthDatasetMetrics combineDepthMetrics(const std::vector<DepthMetrics>& per_image) {
  if (per_image.empty()) throw std::invalid_argument("no image to combine depth metrics over");
  DepthMetrics accounting;  // the summed pixel counts
  DepthErrorSums pooled_sums;
  double scale_sum = 0;
  for (const DepthMetrics& m : per_image) {
    addDepthPixelAccounting(accounting, m);
    pooled_sums += m.sums;
    scale_sum += m.scale;
  }
  const double n = static_cast<double>(per_image.size());
  accounting.scale = scale_sum / n;
  DepthDatasetMetrics d;
  d.images = static_cast<std::int64_t>(per_image.size());
  d.pooled = accounting;
  setMetricsFromSums(d.pooled, pooled_sums);

  DepthMetrics& mean = d.mean_per_image = accounting;
  mean.sums = pooled_sums;
  for (const DepthMetrics& m : per_image) {
    mean.abs_rel += m.abs_rel;
    mean.sq_rel_m += m.sq_rel_m;
    mean.rmse_m += m.rmse_m;
    mean.rmse_log += m.rmse_log;
    mean.silog += m.silog;
    mean.delta1 += m.delta1;
    mean.delta2 += m.delta2;
    mean.delta3 += m.delta3;
  }
  for (double* metric : {&mean.abs_rel, &mean.sq_rel_m, &mean.rmse_m, &mean.rmse_log, &mean.silog, &mean.delta1,
                         &mean.delta2, &mean.delta3})
    *metric /= n;
  return d;
}

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

  setMetricsFromSums(r, errorSums(g, p));
  return r;
}

}  // namespace solo
