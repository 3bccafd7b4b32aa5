#include "solo/geometry/normals_from_depth.h"

#include <Eigen/Geometry>

#include <cmath>

namespace solo {

cv::Mat normalsFromDepth(const cv::Mat& depth_m, const PinholeCamera& camera) {
  CV_Assert(depth_m.type() == CV_32F);
  const int w = depth_m.cols, h = depth_m.rows;
  cv::Mat normals(depth_m.size(), CV_32FC3, cv::Scalar::all(0));
  const auto valid = [&](int x, int y) {
    if (x < 0 || y < 0 || x >= w || y >= h) return false;
    const float d = depth_m.at<float>(y, x);
    return d > 0 && std::isfinite(d);
  };
  const auto point = [&](int x, int y) { return camera.backproject(x, y, depth_m.at<float>(y, x)); };
  normals.forEach<cv::Vec3f>([&](cv::Vec3f& n, const int* p) {
    const int y = p[0], x = p[1];
    if (!valid(x, y)) return;
    const Eigen::Vector3d centre = point(x, y);
    const double z = centre.z();
    // Tangent along an axis: towards the valid neighbour whose depth is closer to ours.
    const auto tangent = [&](int dx, int dy, Eigen::Vector3d& t) {
      const bool after = valid(x + dx, y + dy), before = valid(x - dx, y - dy);
      if (!after && !before) return false;
      const bool use_after =
          after && (!before || std::abs(depth_m.at<float>(y + dy, x + dx) - z) <= std::abs(depth_m.at<float>(y - dy, x - dx) - z));
      t = use_after ? Eigen::Vector3d(point(x + dx, y + dy) - centre) : Eigen::Vector3d(centre - point(x - dx, y - dy));
      return true;
    };
    Eigen::Vector3d tu, tv;
    if (!tangent(1, 0, tu) || !tangent(0, 1, tv)) return;
    Eigen::Vector3d normal = tu.cross(tv);
    const double length = normal.norm();
    if (!(length > 0) || !std::isfinite(length)) return;
    normal /= length;
    if (normal.dot(centre) > 0) normal = -normal;  // face the camera
    n = cv::Vec3f(static_cast<float>(normal.x()), static_cast<float>(normal.y()), static_cast<float>(normal.z()));
  });
  return normals;
}

}  // namespace solo
