#pragma once
// The light-group tree (reference section 1 step 7 and section 3). Inputs, all CV_32S at
// one resolution: the light-source map (categoryId * 1000 + k, 0 = none), the Cityscapes
// instanceIds (vehicles: car 26, truck 27, bus 28, train/tram 31, motorcycle 32,
// bicycle 33, instances >= 1000) and the window-group map (building floors, 0 = none).
// Output: the root (id 0), one group per vehicle instance or floor that holds a light,
// and the lights as leaves. Street lights and front lights are split into 8-connected
// components, one light each; other categories keep one light per map id. A light joins
// the compatible group (one with activation bounds for its category) it overlaps most,
// ties going to the lower group key; with no overlap it hangs from the root.

#include "solo/lighting/light_category.h"

#include <opencv2/core.hpp>

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace solo {

enum class LightGroupKind { Root, BuildingFloor, Car, Truck, Bus, Tram, Motorcycle, Bicycle };

/// "root", "building_floor", "car", "truck", "bus", "tram", "motorcycle", "bicycle".
const char* lightGroupKindName(LightGroupKind kind);
/// Inverse; throws std::invalid_argument.
LightGroupKind lightGroupKindFromName(const std::string& name);
/// The vehicle group kind of a Cityscapes class id (26, 27, 28, 31, 32, 33), if any.
std::optional<LightGroupKind> vehicleGroupKind(int cityscapes_class);

/// Activation probability y ~ Uniform(low, high) (reference section 3).
struct ActivationBounds {
  double low = 1, high = 1;
};
/// Bounds for a category in a group of this kind, or nullopt when the group cannot hold
/// that category. Root lights of vehicle categories (a lamp not on any vehicle mask) take
/// the car bounds; window_parked and window_transport at the root take the car and bus
/// bounds.
std::optional<ActivationBounds> activationBounds(LightGroupKind kind, LightCategory category);

/// True for the categories split into connected components (street and front lights).
bool splitIntoComponents(LightCategory category);

/// Pixels [first_col, last_col] of one image row.
struct PixelRun {
  int row = 0, first_col = 0, last_col = 0;
};

struct Light {
  int id = 0;         ///< 1..N in (map_id, component) order
  int map_id = 0;     ///< value in the light map
  int component = 0;  ///< 1.. for split categories, 0 otherwise
  LightCategory category = LightCategory::WindowBuilding;
  int group = 0;  ///< LightGroup::id; 0 = root
  std::vector<PixelRun> runs;
  std::int64_t pixels = 0;
  cv::Rect bbox;  ///< pixels
};

struct LightGroup {
  int id = 0;  ///< 0 = root
  LightGroupKind kind = LightGroupKind::Root;
  int source_id = 0;  ///< instanceId of a vehicle, window-group id of a floor, 0 for the root
  std::vector<int> lights;  ///< Light::id, ascending
  cv::Rect bbox;            ///< of the group's mask (instance or window group) in pixels; empty for the root
};

struct LightGroupTree {
  int width = 0, height = 0;       ///< pixels of the maps
  std::vector<LightGroup> groups;  ///< groups[i].id == i; groups[0] is the root
  std::vector<Light> lights;       ///< lights[i].id == i + 1
};

/// Builds the tree. `instances` and `window_groups` may be empty (no vehicles / no floors).
/// Throws InputError naming `light_map_source` for a light id of unknown category (with
/// its first pixel) and for maps of different sizes.
LightGroupTree buildLightGroups(const cv::Mat& light_map, const cv::Mat& instances, const cv::Mat& window_groups,
                                const std::filesystem::path& light_map_source);

}  // namespace solo
