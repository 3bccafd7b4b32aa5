#include "solo/lighting/light_geometry.h"

#include <Eigen/Eigenvalues>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace solo {

namespace {

struct WeightedPoint {
  Eigen::Vector3d point;
  Eigen::Vector3d ray;  ///< unnormalised: ((u - cx) / fx, (v - cy) / fy, 1)
  double z = 0;
};

/// Area-weighted plane fit; returns false when the points do not span a plane.
bool fitPlane(const std::vector<WeightedPoint>& points, const std::vector<double>& weights,
              Eigen::Vector3d& centroid, Eigen::Vector3d& normal) {
  double total = 0;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < points.size(); ++i) total += weights[i], mean += weights[i] * points[i].point;
  if (total <= 0) return false;
  mean /= total;
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3d d = points[i].point - mean;
    covariance += weights[i] * d * d.transpose();
  }
  covariance /= total;
  centroid = mean;
  if (points.size() < 3) return false;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(covariance);
  const Eigen::Vector3d eigenvalues = solver.eigenvalues();  // ascending
  // Collinear (or a single point): the middle eigenvalue vanishes against the largest.
  if (!(eigenvalues(2) > 0) || eigenvalues(1) < 1e-6 * eigenvalues(2)) return false;
  normal = solver.eigenvectors().col(0).normalized();
  if (normal.dot(mean) > 0) normal = -normal;
  return true;
}

/// The sum of the normal map over the light's pixels (invalid pixels add zero); zero without a map.
Eigen::Vector3d normalMapSum(const Light& light, const cv::Mat& normals) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  if (!normals.empty())
    for (const PixelRun& run : light.runs)
      for (int x = run.first_col; x <= run.last_col; ++x) {
        const cv::Vec3f n = normals.at<cv::Vec3f>(run.row, x);
        sum += Eigen::Vector3d(n[0], n[1], n[2]);
      }
  return sum;
}

}  // namespace

const char* normalSourceName(NormalSource source) {
  switch (source) {
    case NormalSource::NormalMap: return "normal_map";
    case NormalSource::PlaneFit: return "plane_fit";
    case NormalSource::FacingCamera: return "facing_camera";
  }
  return "facing_camera";
}

NormalSource normalSourceFromName(const std::string& name) {
  for (NormalSource s : {NormalSource::NormalMap, NormalSource::PlaneFit, NormalSource::FacingCamera})
    if (name == normalSourceName(s)) return s;
  throw std::invalid_argument("unknown normal source \"" + name + "\"");
}

const char* lightPlacementName(LightPlacement placement) {
  switch (placement) {
    case LightPlacement::Measured: return "measured";
    case LightPlacement::MovedToSupport: return "moved_to_support";
    case LightPlacement::SupportDepth: return "support_depth";
    case LightPlacement::PriorDistance: return "prior_distance";
  }
  return "measured";
}

LightPlacement lightPlacementFromName(const std::string& name) {
  for (LightPlacement p : {LightPlacement::Measured, LightPlacement::MovedToSupport, LightPlacement::SupportDepth,
                           LightPlacement::PriorDistance})
    if (name == lightPlacementName(p)) return p;
  throw std::invalid_argument("unknown light placement \"" + name + "\"");
}

LightDepthBand lightDepthBand(std::vector<double> depths_m) {
  if (depths_m.empty()) throw std::invalid_argument("lightDepthBand: no depths");
  const auto middle = depths_m.begin() + static_cast<std::ptrdiff_t>(depths_m.size() / 2);
  std::nth_element(depths_m.begin(), middle, depths_m.end());
  LightDepthBand band;
  band.median_m = *middle;
  for (double& d : depths_m) d = std::abs(d - band.median_m);
  std::nth_element(depths_m.begin(), middle, depths_m.end());
  band.half_width_m = std::max(3.0 * *middle, 0.25);
  return band;
}

std::vector<LightGeometry> measureLightGeometry(const LightGroupTree& tree, const cv::Mat& depth_m,
                                                const PinholeCamera& camera, const LightGeometryOptions& options,
                                                const cv::Mat& normals) {
  CV_Assert(depth_m.type() == CV_32F && depth_m.cols == tree.width && depth_m.rows == tree.height);
  CV_Assert(normals.empty() || (normals.type() == CV_32FC3 && normals.size() == depth_m.size()));
  const double min_cosine = std::cos(options.max_incidence_deg * M_PI / 180.0);
  std::vector<LightGeometry> result(tree.lights.size());
  std::vector<WeightedPoint> points;
  for (std::size_t i = 0; i < tree.lights.size(); ++i) {
    points.clear();
    for (const PixelRun& run : tree.lights[i].runs) {
      const float* depth_row = depth_m.ptr<float>(run.row);
      for (int x = run.first_col; x <= run.last_col; ++x) {
        const double z = depth_row[x];
        if (!(z > 0) || !std::isfinite(z)) continue;
        const Eigen::Vector3d ray((x - camera.cx) / camera.fx, (run.row - camera.cy) / camera.fy, 1.0);
        points.push_back({z * ray, ray, z});
      }
    }
    LightGeometry& g = result[i];
    g.pixels_with_depth = static_cast<std::int64_t>(points.size());
    if (points.empty()) continue;
    // Mixed pixels at the light's silhouette see the background, metres to hundreds of metres
    // behind a lamp, and a pixel's footprint grows with its depth squared: a few of them would
    // dominate the area and drag the centroid away. Only the pixels in the light's depth band count.
    {
      std::vector<double> z(points.size());
      for (std::size_t k = 0; k < points.size(); ++k) z[k] = points[k].z;
      const LightDepthBand band = lightDepthBand(std::move(z));
      const auto off =
          std::remove_if(points.begin(), points.end(), [&](const WeightedPoint& p) { return !band.contains(p.z); });
      g.pixels_off_depth = std::distance(off, points.end());
      points.erase(off, points.end());
    }

    // Fit with equal weights first (the areas depend on the normal), then drop outliers
    // (depth bleeding at the light's border) and refit with area weights.
    std::vector<double> weights(points.size(), 1.0);
    Eigen::Vector3d centroid, normal;
    bool plane = fitPlane(points, weights, centroid, normal);
    NormalSource source = plane ? NormalSource::PlaneFit : NormalSource::FacingCamera;
    const Eigen::Vector3d mean_normal = normalMapSum(tree.lights[i], normals);
    if (mean_normal.norm() > 1e-6) {
      normal = mean_normal.normalized();
      if (normal.dot(centroid) > 0) normal = -normal;
      source = NormalSource::NormalMap;
    } else if (plane && points.size() >= 8) {
      std::vector<double> residuals;
      for (const WeightedPoint& p : points) residuals.push_back(std::abs((p.point - centroid).dot(normal)));
      std::vector<double> sorted = residuals;
      std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
      const double sigma = 1.4826 * sorted[sorted.size() / 2];
      const double limit = std::max(3 * sigma, 1e-6 * centroid.norm());
      std::size_t kept = 0;
      for (std::size_t k = 0; k < points.size(); ++k) {
        weights[k] = residuals[k] <= limit ? 1.0 : 0.0;
        kept += weights[k] > 0;
      }
      if (kept >= 3) {
        Eigen::Vector3d refined_centroid, refined_normal;
        if (fitPlane(points, weights, refined_centroid, refined_normal)) normal = refined_normal;
      }
    }
    if (source == NormalSource::FacingCamera) normal = -centroid.normalized();

    double area = 0;
    Eigen::Vector3d weighted_sum = Eigen::Vector3d::Zero();
    for (const WeightedPoint& p : points) {
      const double cosine_times_ray = std::max(std::abs(normal.dot(p.ray)), min_cosine * p.ray.norm());
      const double a = p.z * p.z / (camera.fx * camera.fy * cosine_times_ray);
      area += a;
      weighted_sum += a * p.point;
    }
    g.area_m2 = area;
    g.centroid_m = weighted_sum / area;
    g.normal = normal;
    g.normal_source = source;
  }
  return result;
}

LightGeometry lightGeometryAtDepth(const Light& light, double depth_m, const PinholeCamera& camera,
                                   const LightGeometryOptions& options, const cv::Mat& normals,
                                   const Eigen::Vector3d& fallback_normal) {
  CV_Assert(normals.empty() || normals.type() == CV_32FC3);
  LightGeometry g;
  if (!(depth_m > 0) || !std::isfinite(depth_m) || light.runs.empty()) return g;
  const double min_cosine = std::cos(options.max_incidence_deg * M_PI / 180.0);
  std::vector<Eigen::Vector3d> rays;
  Eigen::Vector3d mean_ray = Eigen::Vector3d::Zero();
  for (const PixelRun& run : light.runs)
    for (int x = run.first_col; x <= run.last_col; ++x) {
      rays.emplace_back((x - camera.cx) / camera.fx, (run.row - camera.cy) / camera.fy, 1.0);
      mean_ray += rays.back();
    }
  const Eigen::Vector3d map_normal = normalMapSum(light, normals);
  Eigen::Vector3d normal = -mean_ray.normalized();
  g.normal_source = NormalSource::FacingCamera;
  if (map_normal.norm() > 1e-6) {
    normal = map_normal.normalized();
    if (normal.dot(mean_ray) > 0) normal = -normal;
    g.normal_source = NormalSource::NormalMap;
  } else if (fallback_normal.norm() > 1e-6) {
    normal = fallback_normal.normalized();
    if (normal.dot(mean_ray) > 0) normal = -normal;
  }
  Eigen::Vector3d weighted_sum = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& ray : rays) {
    const double cosine_times_ray = std::max(std::abs(normal.dot(ray)), min_cosine * ray.norm());
    const double a = depth_m * depth_m / (camera.fx * camera.fy * cosine_times_ray);
    g.area_m2 += a;
    weighted_sum += a * depth_m * ray;
  }
  g.centroid_m = weighted_sum / g.area_m2;
  g.normal = normal;
  return g;
}

cv::Mat resampleNormals(const cv::Mat& normals, cv::Size size) {
  if (normals.empty()) return normals;
  CV_Assert(normals.type() == CV_32FC3);
  if (normals.size() == size) return normals;
  cv::Mat up;
  cv::resize(normals, up, size, 0, 0, cv::INTER_LINEAR);  // invalid (0,0,0) pixels add nothing
  for (int y = 0; y < size.height; ++y)
    for (int x = 0; x < size.width; ++x) {
      cv::Vec3f& n = up.at<cv::Vec3f>(y, x);
      const float length = static_cast<float>(cv::norm(n));
      n = length > 1e-3f ? n / length : cv::Vec3f(0, 0, 0);
    }
  return up;
}

cv::Mat resampleDepthIgnoringInvalid(const cv::Mat& depth_m, cv::Size size) {
  CV_Assert(depth_m.type() == CV_32F);
  if (depth_m.size() == size) return depth_m.clone();
  cv::Mat valid = cv::Mat(depth_m > 0) / 255;
  valid.convertTo(valid, CV_32F);
  cv::Mat masked = depth_m.mul(valid);
  cv::Mat sum, weight;
  cv::resize(masked, sum, size, 0, 0, cv::INTER_LINEAR);
  cv::resize(valid, weight, size, 0, 0, cv::INTER_LINEAR);
  cv::Mat out(size, CV_32F, cv::Scalar(0));
  for (int y = 0; y < size.height; ++y)
    for (int x = 0; x < size.width; ++x) {
      const float w = weight.at<float>(y, x);
      if (w > 1e-6f) out.at<float>(y, x) = sum.at<float>(y, x) / w;
    }
  return out;
}

}  // namespace solo
