#include "solo/lighting/street_light_instances.h"

#include "solo/lighting/light_category.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <map>
#include <set>
#include <stdexcept>
#include <string>

namespace solo {

namespace {

bool isStreetLight(int light_id) {
  if (light_id <= 0) return false;
  const auto category = static_cast<LightCategory>(lightCategoryOfId(light_id));
  return category == LightCategory::StreetLightHighCct || category == LightCategory::StreetLightLowCct;
}

}  // namespace

cv::Mat streetLightsAsPoles(const cv::Mat& instances, const cv::Mat& lights, std::int64_t* changed) {
  if (changed) *changed = 0;
  if (instances.empty() || lights.empty()) return instances;
  CV_Assert(instances.type() == CV_32S && lights.type() == CV_32S);
  cv::Mat light_map = lights;
  if (lights.size() != instances.size()) cv::resize(lights, light_map, instances.size(), 0, 0, cv::INTER_NEAREST);

  // The ids the instance map uses off the street lights stay theirs; each lamp takes the first
  // free pole id from 17000 + k on (wrapping within 17001-17999), in ascending order of light
  // id, so the result depends on the maps alone and a second application changes nothing.
  std::set<int> taken, lamps;
  for (int y = 0; y < light_map.rows; ++y) {
    const int* light = light_map.ptr<int>(y);
    const int* instance = instances.ptr<int>(y);
    for (int x = 0; x < light_map.cols; ++x) {
      if (isStreetLight(light[x])) lamps.insert(light[x]);
      else taken.insert(instance[x]);
    }
  }
  constexpr int kFirst = kCityscapesPoleClass * 1000 + 1, kIds = 999;
  std::map<int, int> pole_instance_of;
  for (const int lamp : lamps) {
    const int start = std::max(1, lamp % 1000) - 1;
    int id = -1;
    for (int j = 0; j < kIds && id < 0; ++j) {
      const int candidate = kFirst + (start + j) % kIds;
      if (!taken.count(candidate)) id = candidate;
    }
    if (id < 0)
      throw std::invalid_argument("streetLightsAsPoles: no free pole instance id (17001-17999) is left for street light " +
                                  std::to_string(lamp));
    taken.insert(id);
    pole_instance_of[lamp] = id;
  }

  cv::Mat out = instances.clone();
  std::int64_t count = 0;
  for (int y = 0; y < out.rows; ++y) {
    const int* light = light_map.ptr<int>(y);
    int* instance = out.ptr<int>(y);
    for (int x = 0; x < out.cols; ++x) {
      if (!isStreetLight(light[x])) continue;
      const int pole_instance = pole_instance_of.at(light[x]);
      count += instance[x] != pole_instance;
      instance[x] = pole_instance;
    }
  }
  if (changed) *changed = count;
  return out;
}

}  // namespace solo
