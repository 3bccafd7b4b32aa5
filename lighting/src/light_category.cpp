#include "solo/lighting/light_category.h"

#include <solo/core/scene.h>

#include <stdexcept>
#include <unordered_set>

namespace solo {

static_assert(kLastLightCategory == kLightCategoryCount, "the scene format and the taxonomy must agree");

namespace {
constexpr const char* kNames[] = {"",
                                  "window_building",
                                  "window_parked",
                                  "window_transport",
                                  "traffic_light_red",
                                  "traffic_light_orange",
                                  "traffic_light_green",
                                  "street_light_HT",
                                  "street_light_LT",
                                  "parked_front",
                                  "moving_front",
                                  "parked_rear",
                                  "moving_rear",
                                  "advertisement",
                                  "clock",
                                  "inferred"};
}  // namespace

const char* lightCategoryName(LightCategory category) {
  const int id = static_cast<int>(category);
  if (id < kFirstLightCategory || id > kLastLightCategory) throw std::invalid_argument("light category out of range");
  return kNames[id];
}

LightCategory lightCategoryFromName(const std::string& name) {
  for (int id = kFirstLightCategory; id <= kLastLightCategory; ++id)
    if (name == kNames[id]) return static_cast<LightCategory>(id);
  throw std::invalid_argument("unknown light category \"" + name + "\"");
}

std::int64_t LightCensus::total_instances() const {
  std::int64_t total = 0;
  for (std::int64_t n : instances) total += n;
  return total;
}

LightCensus countLights(const cv::Mat& light_map) {
  CV_Assert(light_map.type() == CV_32S);
  LightCensus census;
  std::unordered_set<int> seen;
  for (int y = 0; y < light_map.rows; ++y) {
    const int* row = light_map.ptr<int>(y);
    for (int x = 0; x < light_map.cols; ++x) {
      const int id = row[x];
      if (id == 0) continue;
      const int category = lightCategoryOfId(id);
      CV_Assert(category >= kFirstLightCategory && category <= kLastLightCategory);
      ++census.pixels[category];
      if (seen.insert(id).second) ++census.instances[category];
    }
  }
  return census;
}

}  // namespace solo
