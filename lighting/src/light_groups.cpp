#include "solo/lighting/light_groups.h"

#include <solo/core/error.h>

#include <opencv2/imgproc.hpp>

#include <map>
#include <stdexcept>
#include <tuple>

namespace solo {

namespace {

constexpr const char* kKindNames[] = {"root", "building_floor", "car", "truck", "bus", "tram", "motorcycle", "bicycle"};

using C = LightCategory;

bool isMoving(C c) { return c == C::MovingFront || c == C::MovingRear; }
bool isParked(C c) { return c == C::ParkedFront || c == C::ParkedRear; }

/// Bounds of the vehicle lamps and windows of a car or truck.
std::optional<ActivationBounds> carBounds(C c) {
  if (c == C::WindowParked) return ActivationBounds{0.1, 0.4};
  if (isMoving(c)) return ActivationBounds{0.95, 1.0};
  if (isParked(c)) return ActivationBounds{0.1, 0.3};
  return std::nullopt;
}

/// A group a light may join: kind and source id (vehicles before floors in no particular
/// sense; the ordering only breaks ties deterministically).
using GroupKey = std::pair<int, int>;  // (kind, source_id)

void checkSameSize(const cv::Mat& map, const cv::Mat& light_map, const char* name,
                   const std::filesystem::path& source) {
  if (map.empty()) return;
  if (map.type() != CV_32S) throw InputError(name, "expected an integer label map");
  if (map.size() != light_map.size())
    throw InputError(name, std::to_string(map.cols) + "x" + std::to_string(map.rows) + " differs from the light map " +
                               source.string() + " (" + std::to_string(light_map.cols) + "x" +
                               std::to_string(light_map.rows) + "): resample both to the image first");
}

}  // namespace

const char* lightGroupKindName(LightGroupKind kind) { return kKindNames[static_cast<int>(kind)]; }

LightGroupKind lightGroupKindFromName(const std::string& name) {
  for (int i = 0; i < 8; ++i)
    if (name == kKindNames[i]) return static_cast<LightGroupKind>(i);
  throw std::invalid_argument("unknown light group kind \"" + name + "\"");
}

std::optional<LightGroupKind> vehicleGroupKind(int cityscapes_class) {
  switch (cityscapes_class) {
    case 26: return LightGroupKind::Car;
    case 27: return LightGroupKind::Truck;
    case 28: return LightGroupKind::Bus;
    case 31: return LightGroupKind::Tram;
    case 32: return LightGroupKind::Motorcycle;
    case 33: return LightGroupKind::Bicycle;
    default: return std::nullopt;
  }
}

std::optional<ActivationBounds> activationBounds(LightGroupKind kind, LightCategory c) {
  switch (kind) {
    case LightGroupKind::Root:
      switch (c) {
        case C::Inferred:
        case C::TrafficLightRed:
        case C::TrafficLightOrange:
        case C::TrafficLightGreen:
        case C::StreetLightHighCct:
        case C::StreetLightLowCct: return ActivationBounds{1, 1};
        case C::Advertisement: return ActivationBounds{0.6, 0.8};
        case C::Clock: return ActivationBounds{0.8, 1};
        case C::WindowBuilding: return ActivationBounds{0.3, 0.6};
        case C::WindowTransport: return ActivationBounds{0.9, 1};
        default: return carBounds(c);
      }
    case LightGroupKind::BuildingFloor:
      if (c == C::WindowBuilding) return ActivationBounds{0.3, 0.6};
      return std::nullopt;
    case LightGroupKind::Car:
    case LightGroupKind::Truck: return carBounds(c);
    case LightGroupKind::Bus:
      if (c == C::WindowTransport) return ActivationBounds{0.9, 1};
      if (c == C::Inferred) return ActivationBounds{1, 1};
      return carBounds(c);
    case LightGroupKind::Tram:
      if (c == C::WindowTransport) return ActivationBounds{0.9, 1};
      if (c == C::Inferred) return ActivationBounds{1, 1};
      if (isMoving(c)) return ActivationBounds{0.95, 1};
      if (isParked(c)) return ActivationBounds{0.1, 0.3};
      return std::nullopt;
    case LightGroupKind::Motorcycle:
      if (isMoving(c)) return ActivationBounds{0.95, 1};
      if (isParked(c)) return ActivationBounds{0.1, 0.3};
      return std::nullopt;
    case LightGroupKind::Bicycle:
      if (isMoving(c)) return ActivationBounds{0.95, 1};
      if (isParked(c)) return ActivationBounds{0.1, 0.2};
      return std::nullopt;
  }
  return std::nullopt;
}

bool splitIntoComponents(LightCategory c) {
  return c == C::StreetLightHighCct || c == C::StreetLightLowCct || c == C::ParkedFront || c == C::MovingFront;
}

LightGroupTree buildLightGroups(const cv::Mat& light_map, const cv::Mat& instances, const cv::Mat& window_groups,
                                const std::filesystem::path& source) {
  if (light_map.empty() || light_map.type() != CV_32S) throw InputError(source, "expected an integer light map");
  checkSameSize(instances, light_map, "instances", source);
  checkSameSize(window_groups, light_map, "light_groups", source);

  // One pass: bounding boxes of every light id, vehicle instance and window group.
  std::map<int, cv::Rect> light_boxes;
  std::map<GroupKey, cv::Rect> group_boxes;
  const auto grow = [](cv::Rect& box, int x, int y) {
    box = box.empty() ? cv::Rect(x, y, 1, 1) : (box | cv::Rect(x, y, 1, 1));
  };
  const auto groupKeyAt = [&](int x, int y, bool floor) -> std::optional<GroupKey> {
    if (floor) {
      if (window_groups.empty()) return std::nullopt;
      const int g = window_groups.at<int>(y, x);
      if (g <= 0) return std::nullopt;
      return GroupKey{static_cast<int>(LightGroupKind::BuildingFloor), g};
    }
    if (instances.empty()) return std::nullopt;
    const int id = instances.at<int>(y, x);
    if (id < 1000) return std::nullopt;
    const auto kind = vehicleGroupKind(id / 1000);
    if (!kind) return std::nullopt;
    return GroupKey{static_cast<int>(*kind), id};
  };
  for (int y = 0; y < light_map.rows; ++y)
    for (int x = 0; x < light_map.cols; ++x) {
      const int id = light_map.at<int>(y, x);
      if (id != 0) {
        const int category = lightCategoryOfId(id);
        if (id < 0 || category < kFirstLightCategory || category > kLastLightCategory)
          throw InputError(source, "light id " + std::to_string(id) + " at pixel (" + std::to_string(x) + ", " +
                                       std::to_string(y) + ") has the unknown category " + std::to_string(category) +
                                       " (known: " + std::to_string(kFirstLightCategory) + ".." +
                                       std::to_string(kLastLightCategory) + ")");
        grow(light_boxes[id], x, y);
      }
      for (bool floor : {false, true})
        if (const auto key = groupKeyAt(x, y, floor)) grow(group_boxes[*key], x, y);
    }

  LightGroupTree tree;
  tree.width = light_map.cols;
  tree.height = light_map.rows;
  std::vector<GroupKey> light_group_keys;  // per light; kind Root = no group
  for (const auto& [map_id, box] : light_boxes) {
    const LightCategory category = static_cast<LightCategory>(lightCategoryOfId(map_id));
    const cv::Mat roi = light_map(box);
    cv::Mat mask = roi == map_id;
    cv::Mat component_labels;
    int components = 1;
    if (splitIntoComponents(category)) {
      components = cv::connectedComponents(mask, component_labels, 8, CV_32S) - 1;
    } else {
      mask.convertTo(component_labels, CV_32S, 1.0 / 255.0);
    }
    for (int c = 1; c <= components; ++c) {
      Light light;
      light.id = static_cast<int>(tree.lights.size()) + 1;
      light.map_id = map_id;
      light.component = splitIntoComponents(category) ? c : 0;
      light.category = category;
      std::map<GroupKey, std::int64_t> overlap;
      for (int y = 0; y < box.height; ++y) {
        const int* labels = component_labels.ptr<int>(y);
        int x = 0;
        while (x < box.width) {
          if (labels[x] != c) {
            ++x;
            continue;
          }
          const int first = x;
          while (x < box.width && labels[x] == c) {
            for (bool floor : {false, true})
              if (const auto key = groupKeyAt(box.x + x, box.y + y, floor)) ++overlap[*key];
            ++x;
          }
          light.runs.push_back({box.y + y, box.x + first, box.x + x - 1});
          light.pixels += x - first;
          const cv::Rect run(box.x + first, box.y + y, x - first, 1);
          light.bbox = light.bbox.empty() ? run : (light.bbox | run);
        }
      }
      GroupKey best{static_cast<int>(LightGroupKind::Root), 0};
      std::int64_t best_overlap = 0;
      for (const auto& [key, count] : overlap)  // ascending keys: ties keep the lower key
        if (count > best_overlap && activationBounds(static_cast<LightGroupKind>(key.first), category))
          best = key, best_overlap = count;
      light_group_keys.push_back(best);
      tree.lights.push_back(std::move(light));
    }
  }

  // Groups that hold at least one light, in key order; the root first.
  std::map<GroupKey, int> group_ids;
  group_ids[{static_cast<int>(LightGroupKind::Root), 0}] = 0;
  for (const GroupKey& key : light_group_keys) group_ids.emplace(key, 0);
  for (const auto& [key, unused] : group_ids) {
    (void)unused;
    LightGroup g;
    g.id = static_cast<int>(tree.groups.size());
    g.kind = static_cast<LightGroupKind>(key.first);
    g.source_id = key.second;
    if (g.kind != LightGroupKind::Root) g.bbox = group_boxes[key];
    group_ids[key] = g.id;
    tree.groups.push_back(g);
  }
  for (std::size_t i = 0; i < tree.lights.size(); ++i) {
    tree.lights[i].group = group_ids[light_group_keys[i]];
    tree.groups[tree.lights[i].group].lights.push_back(tree.lights[i].id);
  }
  return tree;
}

}  // namespace solo
