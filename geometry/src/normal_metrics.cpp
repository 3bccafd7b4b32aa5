#include "solo/geometry/normal_metrics.h"

#include "solo/core/error.h"
#include "solo/core/quantile.h"

#include "evaluation_maps.h"

#include <cmath>
#include <string>
#include <vector>

namespace solo {
namespace {

constexpr EvaluatedMapKind kNormalMap{3, "normals need", "readNormals"};

bool isValidNormal(const cv::Vec3d& n) {
  return std::isfinite(n[0]) && std::isfinite(n[1]) && std::isfinite(n[2]) && (n[0] != 0 || n[1] != 0 || n[2] != 0);
}

}  // namespace

NormalMetrics evaluateNormals(const NormalEvaluationInput& in) {
  const cv::Mat pred = evaluatedMapAsDouble(in.prediction, kNormalMap, in.prediction_file, "prediction");
  const cv::Mat gt = evaluatedMapAsDouble(in.ground_truth, kNormalMap, in.ground_truth_file, "ground truth");
  const cv::Mat mask = checkedEvaluationMask(in, pred, gt);  // CV_8U, 255 where evaluated; or empty

  NormalMetrics r;
  r.pixels = static_cast<std::int64_t>(gt.total());
  constexpr double kDegPerRad = 180.0 / 3.14159265358979323846;
  std::vector<double> angles_deg;
  for (int y = 0; y < gt.rows; ++y) {
    const cv::Vec3d* gt_row = gt.ptr<cv::Vec3d>(y);
    const cv::Vec3d* pred_row = pred.ptr<cv::Vec3d>(y);
    const unsigned char* mask_row = mask.empty() ? nullptr : mask.ptr<unsigned char>(y);
    for (int x = 0; x < gt.cols; ++x) {
      if (mask_row && !mask_row[x])
        ++r.masked_out;
      else if (!isValidNormal(gt_row[x]))
        ++r.ground_truth_invalid;
      else if (!isValidNormal(pred_row[x]))
        ++r.prediction_invalid;
      else {
        const cv::Vec3d& a = gt_row[x];
        const cv::Vec3d& b = pred_row[x];
        angles_deg.push_back(std::atan2(cv::norm(a.cross(b)), a.dot(b)) * kDegPerRad);
      }
    }
  }
  r.valid_pixels = static_cast<std::int64_t>(angles_deg.size());
  if (angles_deg.empty())
    throw InputError(in.ground_truth_file, "no valid pixel to evaluate (of " + std::to_string(r.pixels) +
                                               " pixels: " + std::to_string(r.masked_out) + " masked out, " +
                                               std::to_string(r.ground_truth_invalid) + " without ground truth, " +
                                               std::to_string(r.prediction_invalid) + " without prediction)");

  double sum = 0, sum_squares = 0;
  std::array<std::int64_t, kNormalAngleThresholdsDeg.size()> under{};
  for (const double angle : angles_deg) {
    sum += angle;
    sum_squares += angle * angle;
    for (std::size_t t = 0; t < under.size(); ++t) under[t] += angle < kNormalAngleThresholdsDeg[t];
  }
  const double n = static_cast<double>(angles_deg.size());
  r.mean_deg = sum / n;
  r.rmse_deg = std::sqrt(sum_squares / n);
  for (std::size_t t = 0; t < under.size(); ++t) r.share_under[t] = static_cast<double>(under[t]) / n;
  r.median_deg = sampleQuantile(angles_deg, 0.5);
  return r;
}

}  // namespace solo
