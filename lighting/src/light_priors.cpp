#include "solo/lighting/light_priors.h"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <bitset>
#include <cstdio>
#include <random>
#include <stdexcept>

namespace solo {

namespace {

// Cityscapes labelIds the priors look at.
constexpr int kRoad = 7, kSidewalk = 8, kBuilding = 11, kPole = 17, kPoleGroup = 18, kTrafficLight = 19;
constexpr int kFirstVehicleClass = 26, kLastVehicleClass = 33;  // car .. bicycle
// A support's depth needs at least this many of its pixels with valid depth.
constexpr std::size_t kMinSupportPixels = 5;

constexpr LightPriorCheck kAllChecks[] = {LightPriorCheck::Distance, LightPriorCheck::Height, LightPriorCheck::Area,
                                          LightPriorCheck::Facing};

std::uint32_t bit(LightPriorCheck check) { return static_cast<std::uint32_t>(check); }

int checkCount(std::uint32_t bits) { return static_cast<int>(std::bitset<32>(bits).count()); }

// The table behind lightCategoryPrior, indexed by category id (docs/lighting.md gives the sources).
std::array<LightCategoryPrior, kLastLightCategory + 1> makePriorTable() {
  std::array<LightCategoryPrior, kLastLightCategory + 1> t{};
  const auto set = [&](std::initializer_list<LightCategory> categories, const LightCategoryPrior& prior) {
    for (LightCategory c : categories) t[static_cast<std::size_t>(c)] = prior;
  };
  for (auto& p : t) p = {{0.5, 300}, std::nullopt, std::nullopt, std::nullopt, 25, false, LightSupport::None};
  set({LightCategory::WindowBuilding},
      {{1, 250}, ValueRange{0, 100}, ValueRange{0.5, 6}, std::nullopt, 25, true, LightSupport::Facade});
  set({LightCategory::WindowParked},
      {{0.5, 150}, ValueRange{0.5, 2.5}, ValueRange{0.1, 2.5}, 1.3, 15, false, LightSupport::Vehicle});
  set({LightCategory::WindowTransport},
      {{0.5, 150}, ValueRange{0.8, 4.5}, ValueRange{0.2, 4}, 2.0, 15, false, LightSupport::Vehicle});
  set({LightCategory::TrafficLightRed, LightCategory::TrafficLightOrange, LightCategory::TrafficLightGreen},
      {{1, 150}, ValueRange{2, 7.5}, ValueRange{0.01, 0.5}, 4.0, 25, false, LightSupport::TrafficLight});
  set({LightCategory::StreetLightHighCct, LightCategory::StreetLightLowCct},
      {{1, 250}, ValueRange{4, 12}, ValueRange{0.02, 1.5}, 8.0, 25, false, LightSupport::Pole});
  set({LightCategory::ParkedFront, LightCategory::MovingFront, LightCategory::ParkedRear, LightCategory::MovingRear},
      {{0.5, 150}, ValueRange{0.3, 1.3}, ValueRange{0.005, 0.4}, 0.8, 15, false, LightSupport::Vehicle});
  set({LightCategory::Advertisement, LightCategory::Clock},
      {{0.5, 250}, std::nullopt, std::nullopt, std::nullopt, 25, false, LightSupport::Facade});
  return t;
}

std::optional<double> median(std::vector<double> values) {
  if (values.empty()) return std::nullopt;
  const auto middle = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), middle, values.end());
  return *middle;
}

Eigen::Vector3d rayOf(const PinholeCamera& camera, double x, double y) {
  return {(x - camera.cx) / camera.fx, (y - camera.cy) / camera.fy, 1.0};
}

// The unit mean ray of a light's pixels.
Eigen::Vector3d centreRay(const Light& light, const PinholeCamera& camera) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (const PixelRun& run : light.runs)
    for (int x = run.first_col; x <= run.last_col; ++x) sum += rayOf(camera, x, run.row);
  return sum.normalized();
}

bool isVehicleClass(int label) { return label >= kFirstVehicleClass && label <= kLastVehicleClass; }

// Road and sidewalk points with valid depth, subsampled evenly to at most max_points.
std::vector<Eigen::Vector3d> groundPoints(const cv::Mat& depth_m, const cv::Mat& labels, const PinholeCamera& camera,
                                          std::int64_t max_points) {
  std::vector<cv::Point> pixels;
  for (int y = 0; y < labels.rows; ++y)
    for (int x = 0; x < labels.cols; ++x) {
      const int label = labels.at<int>(y, x);
      const float z = depth_m.at<float>(y, x);
      if ((label == kRoad || label == kSidewalk) && z > 0 && std::isfinite(z)) pixels.emplace_back(x, y);
    }
  const std::size_t step = std::max<std::size_t>(
      1, (pixels.size() + static_cast<std::size_t>(max_points) - 1) / static_cast<std::size_t>(max_points));
  std::vector<Eigen::Vector3d> points;
  for (std::size_t k = 0; k < pixels.size(); k += step) {
    const cv::Point& p = pixels[k];
    points.push_back(depth_m.at<float>(p.y, p.x) * rayOf(camera, p.x, p.y));
  }
  return points;
}

struct Plane {
  Eigen::Vector3d up = Eigen::Vector3d(0, -1, 0);
  double offset_m = 0;  // up . p + offset_m = height above the plane
};

bool isInlier(const Plane& plane, const Eigen::Vector3d& p, const GroundFitOptions& o) {
  return std::abs(plane.up.dot(p) + plane.offset_m) <= o.inlier_m + o.inlier_fraction * p.z();
}

// The plane through three points, its normal turned up (toward -y); nullopt when they are
// (nearly) collinear or the plane is tilted beyond max_tilt_deg.
std::optional<Plane> planeThrough(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                                  double max_tilt_deg) {
  Eigen::Vector3d n = (b - a).cross(c - a);
  if (!(n.norm() > 1e-9)) return std::nullopt;
  n.normalize();
  if (n.y() > 0) n = -n;
  if (-n.y() < std::cos(max_tilt_deg * M_PI / 180.0)) return std::nullopt;
  return Plane{n, -n.dot(a)};
}

// Least-squares plane (PCA) through the inliers of `plane`, normal up.
std::optional<Plane> refitOnInliers(const std::vector<Eigen::Vector3d>& points, const Plane& plane,
                                    const GroundFitOptions& o, std::int64_t& inliers) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  inliers = 0;
  for (const Eigen::Vector3d& p : points)
    if (isInlier(plane, p, o)) mean += p, ++inliers;
  if (inliers < 3) return std::nullopt;
  mean /= static_cast<double>(inliers);
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (const Eigen::Vector3d& p : points)
    if (isInlier(plane, p, o)) covariance += (p - mean) * (p - mean).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(covariance);
  Eigen::Vector3d n = solver.eigenvectors().col(0).normalized();
  if (n.y() > 0) n = -n;
  if (!n.allFinite() || -n.y() < std::cos(o.max_tilt_deg * M_PI / 180.0)) return std::nullopt;
  return Plane{n, -n.dot(mean)};
}

// RANSAC: the plane through three random points with the most inliers.
std::optional<Plane> ransacPlane(const std::vector<Eigen::Vector3d>& points, const GroundFitOptions& o) {
  std::mt19937_64 rng(o.seed);
  std::uniform_int_distribution<std::size_t> pick(0, points.size() - 1);
  std::optional<Plane> best;
  std::int64_t best_inliers = 0;
  for (int iteration = 0; iteration < o.iterations; ++iteration) {
    const std::size_t a = pick(rng), b = pick(rng), c = pick(rng);
    if (a == b || b == c || a == c) continue;
    const std::optional<Plane> plane = planeThrough(points[a], points[b], points[c], o.max_tilt_deg);
    if (!plane) continue;
    std::int64_t inliers = 0;
    for (const Eigen::Vector3d& p : points) inliers += isInlier(*plane, p, o);
    if (inliers > best_inliers) best = plane, best_inliers = inliers;
  }
  return best;
}

// A light's geometry moved along its rays by `scale` (its pixels' depths times scale).
LightGeometry scaledGeometry(const LightGeometry& g, double scale) {
  LightGeometry moved = g;
  moved.centroid_m = g.centroid_m * scale;
  moved.area_m2 = g.area_m2 * scale * scale;
  return moved;
}

// The depth of the surface that supports each light, from the maps around it.
class SupportFinder {
 public:
  SupportFinder(const LightGroupTree& tree, const LightPriorInputs& in) : in_(in) {
    light_pixels_ = cv::Mat(in.depth_m.size(), CV_8U, cv::Scalar(0));
    for (const Light& light : tree.lights)
      for (const PixelRun& run : light.runs)
        for (int x = run.first_col; x <= run.last_col; ++x) light_pixels_.at<std::uint8_t>(run.row, x) = 1;
  }

  /// The median z-depth of the light's support near it, if the maps show one.
  std::optional<double> depthOf(const Light& light, LightSupport support) const {
    const auto label_is = [this](int label) {
      return [this, label](int y, int x) { return !in_.labels.empty() && in_.labels.at<int>(y, x) == label; };
    };
    switch (support) {
      case LightSupport::None:
        return std::nullopt;
      case LightSupport::Pole:
        return poleBelow(light);
      case LightSupport::Facade:
        return around(light, label_is(kBuilding));
      case LightSupport::TrafficLight: {
        const std::optional<double> housing = around(light, label_is(kTrafficLight));
        return housing ? housing : poleBelow(light);
      }
      case LightSupport::Vehicle: {
        const int instance = vehicleInstance(light);
        if (instance > 0) return around(light, [&](int y, int x) { return in_.instances.at<int>(y, x) == instance; });
        return around(light,
                      [&](int y, int x) { return !in_.labels.empty() && isVehicleClass(in_.labels.at<int>(y, x)); });
      }
    }
    return std::nullopt;
  }

 private:
  const LightPriorInputs& in_;
  cv::Mat light_pixels_;  // 1 on any light's pixel: never a support pixel

  std::optional<double> depthAt(int y, int x) const {
    const float z = in_.depth_m.at<float>(y, x);
    if (!(z > 0) || !std::isfinite(z) || light_pixels_.at<std::uint8_t>(y, x)) return std::nullopt;
    return z;
  }

  bool isPole(int y, int x) const {
    if (in_.labels.empty() || light_pixels_.at<std::uint8_t>(y, x)) return false;
    const int label = in_.labels.at<int>(y, x);
    return label == kPole || label == kPoleGroup;
  }

  // Support pixels in a band around the light's box (as wide as the box's larger side, at least
  // 3 px; three times that when too few show).
  template <typename IsSupport>
  std::optional<double> around(const Light& light, const IsSupport& is_support) const {
    const int base = std::max(3, std::max(light.bbox.width, light.bbox.height));
    for (const int pad : {base, 3 * base}) {
      const cv::Rect box =
          cv::Rect(light.bbox.x - pad, light.bbox.y - pad, light.bbox.width + 2 * pad, light.bbox.height + 2 * pad) &
          cv::Rect(0, 0, in_.depth_m.cols, in_.depth_m.rows);
      std::vector<double> depths;
      for (int y = box.y; y < box.y + box.height; ++y)
        for (int x = box.x; x < box.x + box.width; ++x)
          if (is_support(y, x))
            if (const std::optional<double> z = depthAt(y, x)) depths.push_back(*z);
      if (depths.size() >= kMinSupportPixels) return median(std::move(depths));
    }
    return std::nullopt;
  }

  // The pole under a lamp head: of the columns below the head (within four head widths each side,
  // an arm's reach), the one nearest the head's centre with pole pixels; the median depth of the
  // pole pixels below the head within 2 columns of it.
  std::optional<double> poleBelow(const Light& light) const {
    const int reach = std::max(8, 4 * light.bbox.width);
    const int first = std::max(0, light.bbox.x - reach);
    const int last = std::min(in_.depth_m.cols - 1, light.bbox.x + light.bbox.width - 1 + reach);
    const int top = light.bbox.y + light.bbox.height;
    const double centre = light.bbox.x + 0.5 * (light.bbox.width - 1);
    int best = -1;
    for (int x = first; x <= last; ++x) {
      bool pole = false;
      for (int y = top; y < in_.depth_m.rows && !pole; ++y) pole = isPole(y, x) && depthAt(y, x);
      if (pole && (best < 0 || std::abs(x - centre) < std::abs(best - centre))) best = x;
    }
    if (best < 0) return std::nullopt;
    std::vector<double> depths;
    for (int x = std::max(first, best - 2); x <= std::min(last, best + 2); ++x)
      for (int y = top; y < in_.depth_m.rows; ++y)
        if (isPole(y, x))
          if (const std::optional<double> z = depthAt(y, x)) depths.push_back(*z);
    if (depths.size() < kMinSupportPixels) return std::nullopt;
    return median(std::move(depths));
  }

  // The vehicle instance (id >= 1000 of a vehicle class) most of the light's pixels lie on; 0 = none.
  int vehicleInstance(const Light& light) const {
    if (in_.instances.empty()) return 0;
    std::vector<int> ids;
    for (const PixelRun& run : light.runs)
      for (int x = run.first_col; x <= run.last_col; ++x) {
        const int id = in_.instances.at<int>(run.row, x);
        if (id >= 1000 && isVehicleClass(id / 1000)) ids.push_back(id);
      }
    if (ids.empty()) return 0;
    std::sort(ids.begin(), ids.end());
    int best = 0;
    std::size_t best_count = 0;
    for (std::size_t k = 0; k < ids.size();) {
      std::size_t end = k;
      while (end < ids.size() && ids[end] == ids[k]) ++end;
      if (end - k > best_count) best = ids[k], best_count = end - k;
      k = end;
    }
    return best;
  }
};

// What the priors do to one light at a time.
class PriorApplier {
 public:
  PriorApplier(const LightGroupTree& tree, const LightPriorInputs& in, const LightPriorOptions& options,
               const LightGeometryOptions& geometry_options, LightPriorSummary& summary)
      : in_(in), options_(options), geometry_options_(geometry_options), summary_(summary), support_(tree, in) {}

  void apply(const Light& light, LightGeometry& g) {
    if (g.valid())
      checkAndMove(light, g);
    else
      placeWithoutDepth(light, g);
  }

 private:
  const LightPriorInputs& in_;
  const LightPriorOptions& options_;
  const LightGeometryOptions& geometry_options_;
  LightPriorSummary& summary_;
  SupportFinder support_;

  LightPriorCounts& counts(const Light& light) {
    return summary_.by_category[static_cast<std::size_t>(light.category)];
  }

  void say(const Light& light, const char* what, const LightGeometry& g) {
    char line[320];
    std::snprintf(line, sizeof line, "light %d (%s) %s: %.1f m away, %.1f m above the ground, %.2f m2", light.id,
                  lightCategoryName(light.category), what, g.centroid_m.norm(), in_.ground.heightOf(g.centroid_m),
                  g.area_m2);
    std::string text = line;
    if (g.implausible) {
      text += "; implausible:";
      for (const std::string& name : lightPriorCheckNames(g.implausible)) text += " " + name;
    }
    summary_.lines.push_back(text);
  }

  // A measured light: checked; an implausible one moved onto its support when that removes some
  // of what is implausible, and flagged when something remains.
  void checkAndMove(const Light& light, LightGeometry& g) {
    ++counts(light).checked;
    const std::uint32_t bad = checkLightPriors(light.category, g, in_.ground, options_.tolerance);
    g.implausible = bad;
    if (!bad) return;
    const double z = g.centroid_m.z();
    const std::optional<double> support_z = support_.depthOf(light, lightCategoryPrior(light.category).support);
    if (support_z && z > 0 &&
        std::abs(*support_z - z) > std::max(options_.min_move_fraction * z, options_.min_move_m)) {
      LightGeometry moved = scaledGeometry(g, *support_z / z);
      moved.implausible = checkLightPriors(light.category, moved, in_.ground, options_.tolerance);
      if (checkCount(moved.implausible) < checkCount(bad)) {
        char what[96];
        std::snprintf(what, sizeof what, "moved from %.1f m to its support at %.1f m depth", z, *support_z);
        moved.placement = LightPlacement::MovedToSupport;
        g = moved;
        ++counts(light).moved;
        if (g.implausible) ++counts(light).flagged;
        say(light, what, g);
        return;
      }
    }
    ++counts(light).flagged;
    say(light, "flagged", g);
  }

  // The z-depth of a light without depth or support on its centre ray: at its category's typical
  // height when that distance is within its distance range, else at the typical distance.
  double priorDepth(const Light& light) const {
    const LightCategoryPrior& prior = lightCategoryPrior(light.category);
    const Eigen::Vector3d ray = centreRay(light, in_.camera);
    double distance = prior.typical_distance_m;
    if (prior.typical_height_m && std::abs(in_.ground.up.dot(ray)) > 1e-3) {
      const double t = (*prior.typical_height_m - in_.ground.offset_m) / in_.ground.up.dot(ray);
      if (prior.distance_m.contains(t)) distance = t;
    }
    return distance * ray.z();
  }

  // A light without depth: placed at its support's depth, else at its prior depth.
  void placeWithoutDepth(const Light& light, LightGeometry& g) {
    if (light.runs.empty()) return;
    const LightCategoryPrior& prior = lightCategoryPrior(light.category);
    const std::optional<double> support_z = support_.depthOf(light, prior.support);
    const double z = support_z ? *support_z : priorDepth(light);
    // A facade light without a normal map faces the camera side of a vertical facade.
    Eigen::Vector3d facade_normal = Eigen::Vector3d::Zero();
    if (prior.in_facade) {
      const Eigen::Vector3d ray = centreRay(light, in_.camera);
      facade_normal = -(ray - ray.dot(in_.ground.up) * in_.ground.up);
    }
    const LightGeometry placed =
        lightGeometryAtDepth(light, z, in_.camera, geometry_options_, in_.normals, facade_normal);
    if (!(placed.area_m2 > 0) || !placed.centroid_m.allFinite()) return;  // no position: counted as such
    const std::int64_t pixels_off_depth = g.pixels_off_depth;
    g = placed;
    g.pixels_off_depth = pixels_off_depth;
    g.placement = support_z ? LightPlacement::SupportDepth : LightPlacement::PriorDistance;
    g.implausible = checkLightPriors(light.category, g, in_.ground, options_.tolerance);
    ++(support_z ? counts(light).support_depth : counts(light).prior_distance);
    if (g.implausible) ++counts(light).flagged;
    say(light,
        support_z ? "without depth, placed at its support's depth"
                  : "without depth or support, placed at its prior distance",
        g);
  }
};

}  // namespace

const char* lightPriorCheckName(LightPriorCheck check) {
  switch (check) {
    case LightPriorCheck::Distance:
      return "distance";
    case LightPriorCheck::Height:
      return "height";
    case LightPriorCheck::Area:
      return "area";
    case LightPriorCheck::Facing:
      return "facing";
  }
  return "distance";
}

std::vector<std::string> lightPriorCheckNames(std::uint32_t bits) {
  std::vector<std::string> names;
  for (LightPriorCheck check : kAllChecks)
    if (bits & bit(check)) names.emplace_back(lightPriorCheckName(check));
  return names;
}

std::uint32_t lightPriorChecksFromNames(const std::vector<std::string>& names) {
  std::uint32_t bits = 0;
  for (const std::string& name : names) {
    bool known = false;
    for (LightPriorCheck check : kAllChecks)
      if (name == lightPriorCheckName(check)) bits |= bit(check), known = true;
    if (!known) throw std::invalid_argument("unknown prior check \"" + name + "\"");
  }
  return bits;
}

const LightCategoryPrior& lightCategoryPrior(LightCategory category) {
  static const std::array<LightCategoryPrior, kLastLightCategory + 1> table = makePriorTable();
  const int id = static_cast<int>(category);
  return table[static_cast<std::size_t>(id >= kFirstLightCategory && id <= kLastLightCategory ? id : 0)];
}

GroundPlaneFit fitGroundPlaneToRoad(const cv::Mat& depth_m, const cv::Mat& labels, const PinholeCamera& camera,
                                    const GroundFitOptions& options) {
  GroundPlaneFit ground;
  if (labels.empty() || depth_m.empty() || labels.size() != depth_m.size() || labels.type() != CV_32S ||
      depth_m.type() != CV_32F || options.max_points <= 0)
    return ground;
  const std::vector<Eigen::Vector3d> points = groundPoints(depth_m, labels, camera, options.max_points);
  ground.points = static_cast<std::int64_t>(points.size());
  if (ground.points < std::max<std::int64_t>(3, options.min_points)) return ground;
  const std::optional<Plane> rough = ransacPlane(points, options);
  if (!rough) return ground;
  std::int64_t inliers = 0;
  const std::optional<Plane> plane = refitOnInliers(points, *rough, options, inliers);
  if (!plane || !options.camera_height_m.contains(plane->offset_m)) return ground;
  ground.up = plane->up;
  ground.offset_m = plane->offset_m;
  ground.inliers = inliers;
  ground.fitted = true;
  return ground;
}

std::uint32_t checkLightPriors(LightCategory category, const LightGeometry& geometry, const GroundPlaneFit& ground,
                               const LightPriorTolerance& tolerance) {
  if (!geometry.positioned() || !geometry.centroid_m.allFinite()) return 0;
  const LightCategoryPrior& prior = lightCategoryPrior(category);
  const double distance = geometry.centroid_m.norm();
  std::uint32_t bits = 0;
  if (!prior.distance_m.contains(distance)) bits |= bit(LightPriorCheck::Distance);
  if (prior.height_m) {
    const double margin_m = tolerance.height_m + tolerance.height_fraction * distance;
    const ValueRange widened{prior.height_m->min - margin_m, prior.height_m->max + margin_m};
    if (!widened.contains(ground.heightOf(geometry.centroid_m))) bits |= bit(LightPriorCheck::Height);
  }
  // Only too large an area is implausible: a light partly hidden or cut by the frame shows less.
  if (prior.area_m2 && !(geometry.area_m2 <= prior.area_m2->max * tolerance.area_factor))
    bits |= bit(LightPriorCheck::Area);
  if (prior.in_facade) {
    const bool toward_camera = geometry.normal.dot(geometry.centroid_m) < 0;
    const bool vertical_facade = std::abs(geometry.normal.dot(ground.up)) <=
                                 std::sin(kFacadeNormalTiltDeg * M_PI / 180.0) * geometry.normal.norm();
    if (!toward_camera || !vertical_facade) bits |= bit(LightPriorCheck::Facing);
  }
  return bits;
}

LightPriorSummary applyLightPriors(const LightGroupTree& tree, std::vector<LightGeometry>& geometry,
                                   const LightPriorInputs& inputs, const LightPriorOptions& options,
                                   const LightGeometryOptions& geometry_options) {
  CV_Assert(geometry.size() == tree.lights.size());
  CV_Assert(inputs.depth_m.type() == CV_32F && inputs.depth_m.cols == tree.width && inputs.depth_m.rows == tree.height);
  CV_Assert(inputs.labels.empty() || (inputs.labels.type() == CV_32S && inputs.labels.size() == inputs.depth_m.size()));
  CV_Assert(inputs.instances.empty() ||
            (inputs.instances.type() == CV_32S && inputs.instances.size() == inputs.depth_m.size()));
  LightPriorSummary summary;
  if (!options.enabled) return summary;
  PriorApplier applier(tree, inputs, options, geometry_options, summary);
  for (std::size_t i = 0; i < tree.lights.size(); ++i) applier.apply(tree.lights[i], geometry[i]);
  for (const LightPriorCounts& c : summary.by_category) {
    summary.total.checked += c.checked;
    summary.total.moved += c.moved;
    summary.total.flagged += c.flagged;
    summary.total.support_depth += c.support_depth;
    summary.total.prior_distance += c.prior_distance;
  }
  return summary;
}

LightsWithoutDepth countLightsWithoutDepth(const LightRecord& record) {
  LightsWithoutDepth count;
  for (std::size_t i = 0; i < record.geometry.size() && i < record.instantiation.lights.size(); ++i) {
    if (record.geometry[i].valid()) continue;
    ++count.all;
    count.lit += lightIsLit(record.instantiation.lights[i]);
  }
  return count;
}

}  // namespace solo
