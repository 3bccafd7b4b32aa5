#pragma once
// The steps of proposeLights (light_proposals.h) and what they share: the scene's maps at the
// image resolution, the ground frame, and the draft lights each category's step appends.

#include "solo/lighting/light_proposals.h"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include <algorithm>
#include <string>
#include <vector>

namespace solo::proposals {

// Cityscapes labelIds the proposals read.
enum CityscapesClass : int {
  kRoad = 7, kSidewalk = 8, kParking = 9, kBuilding = 11, kPole = 17, kTrafficLight = 19, kTerrain = 22,
  kSky = 23, kCar = 26, kTruck = 27, kBus = 28, kCaravan = 29, kTrailer = 30, kTrain = 31, kMotorcycle = 32,
  kBicycle = 33,
};

/// The scene's maps at the image resolution and the ground frame: up (the plane's normal),
/// forward (the optical axis on the ground) and right, orthonormal.
struct ProposalInputs {
  cv::Mat labels;     ///< CV_32S
  cv::Mat instances;  ///< CV_32S, may be empty
  cv::Mat image;      ///< CV_32FC3 sRGB
  cv::Mat depth_m;    ///< CV_32F, 0 = invalid
  PinholeCamera camera;
  GroundPlaneFit ground;
  Eigen::Vector3d right{1, 0, 0}, forward{0, 0, 1};
  double pixel_scale = 1;  ///< image width / 1920: pixel thresholds are given at 1920 px wide

  int width() const { return labels.cols; }
  int height() const { return labels.rows; }
  /// The viewing ray of a pixel with z = 1.
  Eigen::Vector3d ray(double u, double v) const {
    return {(u - camera.cx) / camera.fx, (v - camera.cy) / camera.fy, 1.0};
  }
  Eigen::Vector3d point(double u, double v, double depth) const { return ray(u, v) * depth; }
  double lateral(const Eigen::Vector3d& p) const { return right.dot(p); }
  double along(const Eigen::Vector3d& p) const { return forward.dot(p); }
  /// The camera-frame point at lateral x, height h above ground and distance f along the ground.
  Eigen::Vector3d groundFramePoint(double x, double h, double f) const {
    return right * x + ground.up * (h - ground.offset_m) + forward * f;
  }
  /// Depth (z) where the ray of (u, v) meets the ground at height h; <= 0 when it does not.
  double rayHeightDepth(double u, double v, double h) const {
    const double rise = ground.up.dot(ray(u, v));
    return std::abs(rise) < 1e-9 ? -1.0 : (h - ground.offset_m) / rise;
  }
  float depthAt(int u, int v) const { return depth_m.at<float>(v, u); }
  int labelAt(int u, int v) const { return labels.at<int>(v, u); }
  /// Pixels scaled from 1920 px wide, at least `least`.
  int scaledPixels(double at_1920, int least = 1) const {
    return std::max(least, static_cast<int>(std::lround(at_1920 * pixel_scale)));
  }
};

/// A proposal before it gets its map id.
struct DraftLight {
  LightCategory category = LightCategory::Inferred;
  std::vector<cv::Point> pixels;
  Eigen::Vector3d position_m{0, 0, 0};
  double height_m = 0;
  double score = 0;
  std::string rule, evidence;
  long group_key = 0;  ///< windows: facade * 1000 + floor + 1; 0 = no group
  int source_instance = 0;
};

/// The q-quantile (0..1) of `values` (reordered); 0 for none.
double quantile(std::vector<double>& values, double q);

/// Pixels of `points` inside the image whose label is one of `labels`... filled convex polygon.
std::vector<cv::Point> convexPolygonPixels(const std::vector<cv::Point2d>& corners, cv::Size size);

/// "%.2f"-style formatting for evidence strings.
std::string fixed(double value, int decimals = 2);

void proposeStreetLights(const ProposalInputs& in, const LightProposalOptions& options, std::vector<DraftLight>& out,
                         StageReport& report);
void proposeTrafficLights(const ProposalInputs& in, const LightProposalOptions& options, std::vector<DraftLight>& out,
                          StageReport& report);
void proposeVehicleLamps(const ProposalInputs& in, const LightProposalOptions& options, std::vector<DraftLight>& out,
                         StageReport& report);
void proposeWindows(const ProposalInputs& in, const LightProposalOptions& options, std::vector<DraftLight>& out,
                    StageReport& report);

}  // namespace solo::proposals
