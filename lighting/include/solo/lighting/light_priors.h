#pragma once
// Physical priors per light category (docs/lighting.md, "Physical priors"): how far from the
// camera, how high above the ground plane, how large and which way a light of each category can
// plausibly be. Every light is checked against them after its depth is measured. An implausible
// light is moved onto its supporting surface (a street lamp onto its pole, a window onto its
// facade, a vehicle lamp onto its vehicle) when that makes it plausible, or flagged; a light
// without valid depth is placed at its supporting surface's depth, else at its category's prior
// distance along its pixels' rays, so that a light that is on always emits.
//
// The ground plane comes from the 3D points of the road and sidewalk pixels (Cityscapes labelIds
// 7 and 8): RANSAC with a seeded generator, then a least-squares refit on the inliers. Without
// enough of them (or with a plane no camera on a car could stand on) the camera-height prior
// stands in: a level camera kCameraHeightPriorM above the ground.

#include "solo/lighting/light_category.h"
#include "solo/lighting/light_geometry.h"
#include "solo/lighting/light_groups.h"
#include "solo/lighting/light_record.h"

#include <solo/core/camera.h>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include <array>
#include <cmath>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace solo {

struct ValueRange {
  double min = 0, max = 0;
  bool contains(double value) const { return value >= min && value <= max; }
};

/// Bits of LightGeometry::implausible.
enum class LightPriorCheck : std::uint32_t { Distance = 1, Height = 2, Area = 4, Facing = 8 };
/// "distance", "height", "area", "facing".
const char* lightPriorCheckName(LightPriorCheck check);
/// The names of the checks set in `bits`, in the order above.
std::vector<std::string> lightPriorCheckNames(std::uint32_t bits);
/// Inverse; throws std::invalid_argument for an unknown name.
std::uint32_t lightPriorChecksFromNames(const std::vector<std::string>& names);

/// The surface a light hangs on or is set in, whose depth stands in for the light's.
enum class LightSupport { None, Pole, Facade, TrafficLight, Vehicle };

struct LightCategoryPrior {
  ValueRange distance_m;               ///< of the centroid from the camera
  std::optional<ValueRange> height_m;  ///< of the centroid above the ground plane
  std::optional<ValueRange> area_m2;   ///< emitting area
  /// Where a light without depth and without support goes: along its pixels' rays to where they
  /// are this high above the ground, when that lies within distance_m; else typical_distance_m.
  std::optional<double> typical_height_m;
  double typical_distance_m = 25;
  bool in_facade = false;  ///< faces the camera side of a vertical facade
  LightSupport support = LightSupport::None;
};
/// The prior of a category (documented in docs/lighting.md with its sources).
const LightCategoryPrior& lightCategoryPrior(LightCategory category);

/// How far past a category's prior range a measured light may lie and still be plausible.
struct LightPriorTolerance {
  /// Heights: the prior range widened by height_m plus height_fraction of the light's distance
  /// each side (depth errors grow with distance), metres.
  double height_m = 0.2;
  double height_fraction = 0.05;
  /// Areas: above the prior's maximum times area_factor is implausible. Too small an area is not
  /// checked: a light partly hidden or cut by the frame shows less of itself.
  double area_factor = 1.5;
};
/// A facade light's normal lies within this angle of horizontal, degrees.
inline constexpr double kFacadeNormalTiltDeg = 45;

/// Height of the camera above the road when no ground plane can be fitted, metres (Cityscapes
/// 1.22 m, KITTI 1.65 m, solo synth 1.5 m).
inline constexpr double kCameraHeightPriorM = 1.5;

struct GroundPlaneFit {
  Eigen::Vector3d up = Eigen::Vector3d(0, -1, 0);  ///< unit normal pointing up, camera frame
  double offset_m = kCameraHeightPriorM;           ///< heightOf(p) = up . p + offset_m; the camera's own height
  bool fitted = false;                             ///< from road and sidewalk points; false = the prior
  std::int64_t points = 0, inliers = 0;            ///< candidate points used, and the plane's inliers
  double heightOf(const Eigen::Vector3d& p) const { return up.dot(p) + offset_m; }
};

struct GroundFitOptions {
  std::uint64_t seed = 1;  ///< RANSAC's generator
  int iterations = 200;
  double inlier_m = 0.1;                 ///< inlier distance at the camera ...
  double inlier_fraction = 0.01;         ///< ... plus this fraction of the point's depth
  std::int64_t max_points = 20000;       ///< subsampled evenly beyond this
  std::int64_t min_points = 100;         ///< fewer road and sidewalk points: the prior
  double max_tilt_deg = 30;              ///< of the plane's normal from the camera's -y axis
  ValueRange camera_height_m{0.3, 5.0};  ///< a plane outside this: the prior
};

/// Fits the ground plane to the road (labelId 7) and sidewalk (8) pixels with valid depth.
/// `depth_m` CV_32F metres, `labels` CV_32S labelIds at the same size (empty: the prior),
/// `camera` at that size. Never throws for missing or degenerate input: returns the prior.
GroundPlaneFit fitGroundPlaneToRoad(const cv::Mat& depth_m, const cv::Mat& labels, const PinholeCamera& camera,
                                    const GroundFitOptions& options = {});

/// The checks of `category`'s prior that `geometry` fails (LightPriorCheck bits); 0 for a light
/// without a position.
std::uint32_t checkLightPriors(LightCategory category, const LightGeometry& geometry, const GroundPlaneFit& ground,
                               const LightPriorTolerance& tolerance = {});

/// The maps the priors look at, all at the light tree's resolution.
struct LightPriorInputs {
  cv::Mat depth_m;    ///< CV_32F metres, 0 = invalid
  cv::Mat labels;     ///< CV_32S Cityscapes labelIds, or empty (no support but vehicles' instances)
  cv::Mat instances;  ///< CV_32S Cityscapes instanceIds, or empty
  cv::Mat normals;    ///< CV_32FC3, or empty
  PinholeCamera camera;
  GroundPlaneFit ground;
};

struct LightPriorOptions {
  bool enabled = true;  ///< false: lights stay as measured, lights without depth without position
  /// A light is moved only when its support's depth differs from its own by more than this
  /// fraction of it and more than min_move_m.
  double min_move_fraction = 0.1;
  double min_move_m = 1.0;
  LightPriorTolerance tolerance;
};

struct LightPriorCounts {
  std::int64_t checked = 0;         ///< lights with measured depth, checked
  std::int64_t moved = 0;           ///< moved onto their support
  std::int64_t flagged = 0;         ///< still implausible where they are (moved or not)
  std::int64_t support_depth = 0;   ///< without depth, placed at their support's depth
  std::int64_t prior_distance = 0;  ///< without depth or support, placed at the prior distance
};

struct LightPriorSummary {
  std::array<LightPriorCounts, kLastLightCategory + 1> by_category{};  ///< indexed by category id
  LightPriorCounts total;
  std::vector<std::string> lines;  ///< one per moved, flagged or placed light: what and why
};

/// Checks every light of `tree` against its category's prior, moves or flags the implausible
/// ones and places those without depth (see the header comment). `geometry`: per tree.lights,
/// as measureLightGeometry made it; changed in place (placement, implausible, and the geometry of
/// moved and placed lights).
LightPriorSummary applyLightPriors(const LightGroupTree& tree, std::vector<LightGeometry>& geometry,
                                   const LightPriorInputs& inputs, const LightPriorOptions& options = {},
                                   const LightGeometryOptions& geometry_options = {});

/// A light that is on with a usable strength: the lights the night scene makes emit.
inline bool lightIsLit(const LightState& state) {
  return state.on && state.strength > 0 && std::isfinite(state.strength);
}

/// Lights of a record without valid depth under them: all of them, and those lit (lightIsLit).
/// The light stage and the night scene report these same two counts.
struct LightsWithoutDepth {
  std::int64_t all = 0, lit = 0;
};
LightsWithoutDepth countLightsWithoutDepth(const LightRecord& record);

}  // namespace solo
