#pragma once
// The light-source taxonomy of the scene format: categoryId * 1000 + k in a light map.

#include <opencv2/core.hpp>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace solo {

enum class LightCategory : int {
  WindowBuilding = 1,
  WindowParked = 2,
  WindowTransport = 3,
  TrafficLightRed = 4,
  TrafficLightOrange = 5,
  TrafficLightGreen = 6,
  StreetLightHighCct = 7,
  StreetLightLowCct = 8,
  ParkedFront = 9,
  MovingFront = 10,
  ParkedRear = 11,
  MovingRear = 12,
  Advertisement = 13,
  Clock = 14,
  Inferred = 15,
};

constexpr int kFirstLightCategory = 1;
constexpr int kLastLightCategory = 15;

/// Annotation name: "window_building", ..., "street_light_HT", ..., "inferred".
const char* lightCategoryName(LightCategory category);
/// Inverse of lightCategoryName; throws std::invalid_argument for an unknown name.
LightCategory lightCategoryFromName(const std::string& name);

/// Category of a light-map value (categoryId * 1000 + k), or nullopt-like 0 for "no light".
inline int lightCategoryOfId(int light_id) { return light_id / 1000; }

/// Per-category census of a light map: distinct instance ids and their pixel counts.
struct LightCensus {
  std::array<std::int64_t, kLastLightCategory + 1> instances{};  ///< indexed by category id
  std::array<std::int64_t, kLastLightCategory + 1> pixels{};
  std::int64_t total_instances() const;
};

/// Counts instances and pixels per category in a CV_32S light map (0 = no light).
/// Precondition: every non-zero id has a category in 1..15 (loadScene checks this).
LightCensus countLights(const cv::Mat& light_map);

}  // namespace solo
