// Traffic lights: the lit lamp of every traffic-light housing (Cityscapes class 19). The
// housing is split into three slots along its long side; the slot whose pixels are the most
// saturated holds the lamp that is on (its pixels: chroma at least a quarter of the slot's
// 95th percentile, the lamp's shaded face included), and its hue names the category. A housing without a
// saturated slot (seen from the side or the back) shows no lamp and gets none.

#include "light_proposal_steps.h"

#include <opencv2/imgproc.hpp>

#include <cmath>

namespace solo::proposals {
namespace {

double chroma(const cv::Vec3f& rgb) {
  return std::max({rgb[0], rgb[1], rgb[2]}) - std::min({rgb[0], rgb[1], rgb[2]});
}

// Hue in degrees of an RGB colour.
double hueDegrees(const cv::Vec3f& rgb) {
  const double r = rgb[0], g = rgb[1], b = rgb[2];
  const double mx = std::max({r, g, b}), mn = std::min({r, g, b});
  if (mx - mn < 1e-9) return 0;
  double h = mx == r ? std::fmod((g - b) / (mx - mn), 6.0) : mx == g ? (b - r) / (mx - mn) + 2 : (r - g) / (mx - mn) + 4;
  h *= 60;
  return h < 0 ? h + 360 : h;
}

LightCategory signalCategory(double hue) {
  if (hue < 22 || hue >= 300) return LightCategory::TrafficLightRed;
  if (hue < 70) return LightCategory::TrafficLightOrange;
  return LightCategory::TrafficLightGreen;
}

// The slot (0..2 along the housing's long side) of a pixel.
int slotOf(const cv::Point& p, const cv::Rect& box, bool vertical) {
  const double t = vertical ? (p.y - box.y + 0.5) / box.height : (p.x - box.x + 0.5) / box.width;
  return std::clamp(static_cast<int>(t * 3), 0, 2);
}

}  // namespace

void proposeTrafficLights(const ProposalInputs& in, const LightProposalOptions&, std::vector<DraftLight>& out,
                          StageReport& report) {
  cv::Mat ids, stats, centroids;
  const int n = cv::connectedComponentsWithStats(in.labels == kTrafficLight, ids, stats, centroids, 8, CV_32S);
  std::vector<std::vector<cv::Point>> blobs(static_cast<std::size_t>(n));
  for (int v = 0; v < ids.rows; ++v)
    for (int u = 0; u < ids.cols; ++u)
      if (const int id = ids.at<int>(v, u); id > 0) blobs[static_cast<std::size_t>(id)].emplace_back(u, v);
  const int min_pixels = std::max(10, static_cast<int>(40 * in.pixel_scale * in.pixel_scale));
  int dark = 0, proposed = 0;
  for (int i = 1; i < n; ++i) {
    const std::vector<cv::Point>& blob = blobs[static_cast<std::size_t>(i)];
    if (static_cast<int>(blob.size()) < min_pixels) continue;
    const cv::Rect box(stats.at<int>(i, cv::CC_STAT_LEFT), stats.at<int>(i, cv::CC_STAT_TOP),
                       stats.at<int>(i, cv::CC_STAT_WIDTH), stats.at<int>(i, cv::CC_STAT_HEIGHT));
    const bool vertical = box.height >= box.width;
    // The 80th and 95th percentiles of each slot's chroma.
    std::array<std::vector<double>, 3> slot_chroma;
    for (const cv::Point& p : blob) slot_chroma[slotOf(p, box, vertical)].push_back(chroma(in.image.at<cv::Vec3f>(p)));
    std::array<double, 3> strength{};
    std::array<double, 3> peak{};
    for (int s = 0; s < 3; ++s) strength[s] = quantile(slot_chroma[s], 0.8), peak[s] = quantile(slot_chroma[s], 0.95);
    const int lit = static_cast<int>(std::max_element(strength.begin(), strength.end()) - strength.begin());
    std::array<double, 3> others = strength;
    others[lit] = 0;
    const double runner_up = *std::max_element(others.begin(), others.end());
    if (strength[lit] < 0.2) {
      ++dark;
      continue;
    }
    DraftLight light;
    cv::Vec3d colour(0, 0, 0);
    for (const cv::Point& p : blob)
      if (slotOf(p, box, vertical) == lit && chroma(in.image.at<cv::Vec3f>(p)) >= 0.25 * peak[lit]) {
        light.pixels.push_back(p);
        colour += cv::Vec3d(in.image.at<cv::Vec3f>(p));
      }
    colour *= 1.0 / static_cast<double>(light.pixels.size());
    const double hue = hueDegrees(cv::Vec3f(static_cast<float>(colour[0]), static_cast<float>(colour[1]),
                                            static_cast<float>(colour[2])));
    light.category = signalCategory(hue);
    std::vector<double> depths;
    for (const cv::Point& p : blob)
      if (const float z = in.depthAt(p.x, p.y); z > 0) depths.push_back(z);
    const double depth = depths.empty() ? 0 : quantile(depths, 0.25);
    cv::Point2d centre(0, 0);
    for (const cv::Point& p : light.pixels) centre += cv::Point2d(p.x, p.y);
    centre *= 1.0 / static_cast<double>(light.pixels.size());
    if (depth > 0) {
      light.position_m = in.point(centre.x, centre.y, depth);
      light.height_m = in.ground.height(light.position_m);
    }
    light.score = std::clamp((strength[lit] - runner_up) / std::max(strength[lit], 1e-6), 0.0, 1.0);
    light.rule = "most_saturated_slot";
    light.evidence = std::string(vertical ? "vertical" : "horizontal") + " housing " + std::to_string(box.width) + "x" +
                     std::to_string(box.height) + " px, slot " + std::to_string(lit + 1) + "/3 chroma " +
                     fixed(strength[lit]) + " (others " + fixed(runner_up) + "), hue " + fixed(hue, 0) + " deg";
    light.source_instance = kTrafficLight;
    out.push_back(std::move(light));
    ++proposed;
  }
  report.add("traffic_lights_proposed", static_cast<std::int64_t>(proposed));
  if (dark > 0) report.notes.push_back(std::to_string(dark) + " traffic-light housings show no lit lamp (side or back)");
}

}  // namespace solo::proposals
