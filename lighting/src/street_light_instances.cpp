#include "solo/lighting/street_light_instances.h"

#include "solo/lighting/light_category.h"

#include <opencv2/imgproc.hpp>

namespace solo {

cv::Mat streetLightsAsPoles(const cv::Mat& instances, const cv::Mat& lights, std::int64_t* changed) {
  if (changed) *changed = 0;
  if (instances.empty() || lights.empty()) return instances;
  CV_Assert(instances.type() == CV_32S && lights.type() == CV_32S);
  cv::Mat light_map = lights;
  if (lights.size() != instances.size()) cv::resize(lights, light_map, instances.size(), 0, 0, cv::INTER_NEAREST);
  cv::Mat out = instances.clone();
  std::int64_t count = 0;
  for (int y = 0; y < out.rows; ++y) {
    const int* light = light_map.ptr<int>(y);
    int* instance = out.ptr<int>(y);
    for (int x = 0; x < out.cols; ++x) {
      const auto category = static_cast<LightCategory>(lightCategoryOfId(light[x]));
      if (light[x] <= 0 || (category != LightCategory::StreetLightHighCct && category != LightCategory::StreetLightLowCct))
        continue;
      const int pole_instance = kCityscapesPoleClass * 1000 + light[x] % 1000;
      count += instance[x] != pole_instance;
      instance[x] = pole_instance;
    }
  }
  if (changed) *changed = count;
  return out;
}

}  // namespace solo
