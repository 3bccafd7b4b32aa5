// Traffic lights: the lit lamp of every traffic-light housing (Cityscapes class 19). Label
// blobs a few pixels apart are one housing. Its lamps are the groups of saturated pixels in it
// at least a quarter of its short side in both directions (no slivers of background colour); the
// lit one is the brightest, by at least a quarter over any other lamp shown (an unlit lamp's
// glass is several times darker), and its hue names the category. A housing without a saturated
// lamp (seen from the side or the back) gets none, and so does one whose lamps are equally bright.

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

// The traffic-light housings: class-19 pixels grouped by 8-connectivity after closing gaps of
// a few pixels, so a housing the labels split in two (a pole, a wire, label noise) stays one.
std::vector<std::vector<cv::Point>> housings(const ProposalInputs& in) {
  const cv::Mat mask = in.labels == kTrafficLight;
  const int gap = in.scaledPixels(3);
  cv::Mat joined, ids;
  cv::dilate(mask, joined, cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * gap + 1, 2 * gap + 1)));
  const int n = cv::connectedComponents(joined, ids, 8, CV_32S);
  std::vector<std::vector<cv::Point>> groups(static_cast<std::size_t>(std::max(n, 1)));
  for (int v = 0; v < ids.rows; ++v)
    for (int u = 0; u < ids.cols; ++u)
      if (mask.at<std::uint8_t>(v, u)) groups[static_cast<std::size_t>(ids.at<int>(v, u))].emplace_back(u, v);
  return groups;
}

// A coloured lamp in a housing: a connected group of saturated pixels.
struct LampBlob {
  std::vector<cv::Point> pixels;
  double value = 0;   ///< 80th percentile of the brightest channel: a lit lamp is several times brighter
  double chroma = 0;  ///< 80th percentile of max - min
};

constexpr double kLampChroma = 0.15;       ///< a lamp's pixel is at least this saturated (the housing is grey)
constexpr double kLampSaturation = 0.4;   ///< and chroma / value: pale background at the label's edge is not
constexpr double kLampShortSide = 0.25;    ///< a lamp spans at least this share of the housing's short side
constexpr double kLitOverOthers = 1.25;    ///< the lit lamp is this much brighter than any other lamp shown

// The housing's lamps: saturated pixel groups at least kLampShortSide of the housing's short
// side in both directions (a sliver of background colour at the label's edge is none).
std::vector<LampBlob> lampBlobs(const ProposalInputs& in, const std::vector<cv::Point>& housing, const cv::Rect& box) {
  cv::Mat local = cv::Mat::zeros(box.size(), CV_8U);
  for (const cv::Point& p : housing) {
    const cv::Vec3f c = in.image.at<cv::Vec3f>(p);
    if (chroma(c) >= kLampChroma && chroma(c) >= kLampSaturation * std::max({c[0], c[1], c[2]}))
      local.at<std::uint8_t>(p - box.tl()) = 255;
  }
  cv::Mat ids, stats, centroids;
  const int n = cv::connectedComponentsWithStats(local, ids, stats, centroids, 8, CV_32S);
  const double least = kLampShortSide * std::min(box.width, box.height);
  std::vector<LampBlob> lamps;
  for (int i = 1; i < n; ++i) {
    if (stats.at<int>(i, cv::CC_STAT_WIDTH) < least || stats.at<int>(i, cv::CC_STAT_HEIGHT) < least) continue;
    LampBlob lamp;
    std::vector<double> values, chromas;
    for (int v = 0; v < ids.rows; ++v)
      for (int u = 0; u < ids.cols; ++u)
        if (ids.at<int>(v, u) == i) {
          const cv::Vec3f c = in.image.at<cv::Vec3f>(v + box.y, u + box.x);
          lamp.pixels.emplace_back(u + box.x, v + box.y);
          values.push_back(std::max({c[0], c[1], c[2]}));
          chromas.push_back(chroma(c));
        }
    lamp.value = quantile(values, 0.8);
    lamp.chroma = quantile(chromas, 0.8);
    lamps.push_back(std::move(lamp));
  }
  return lamps;
}

}  // namespace

void proposeTrafficLights(const ProposalInputs& in, const LightProposalOptions&, std::vector<DraftLight>& out,
                          StageReport& report) {
  const int min_pixels = std::max(10, static_cast<int>(40 * in.pixel_scale * in.pixel_scale));
  int dark = 0, undecided = 0, proposed = 0;
  const std::vector<std::vector<cv::Point>> groups = housings(in);
  for (std::size_t i = 1; i < groups.size(); ++i) {
    const std::vector<cv::Point>& housing = groups[i];
    if (static_cast<int>(housing.size()) < min_pixels) continue;
    const cv::Rect box = cv::boundingRect(housing);
    std::vector<LampBlob> lamps = lampBlobs(in, housing, box);
    std::sort(lamps.begin(), lamps.end(), [](const LampBlob& a, const LampBlob& b) { return a.value > b.value; });
    if (lamps.empty() || lamps.front().chroma < 0.2) {
      ++dark;
      continue;
    }
    const double runner_up = lamps.size() > 1 ? lamps[1].value : 0.0;
    if (lamps.front().value < kLitOverOthers * runner_up) {
      ++undecided;
      continue;
    }
    DraftLight light;
    light.pixels = lamps.front().pixels;
    cv::Vec3d colour(0, 0, 0);
    cv::Point2d centre(0, 0);
    for (const cv::Point& p : light.pixels) {
      colour += cv::Vec3d(in.image.at<cv::Vec3f>(p));
      centre += cv::Point2d(p.x, p.y);
    }
    colour *= 1.0 / static_cast<double>(light.pixels.size());
    centre *= 1.0 / static_cast<double>(light.pixels.size());
    const double hue = hueDegrees(cv::Vec3f(static_cast<float>(colour[0]), static_cast<float>(colour[1]),
                                            static_cast<float>(colour[2])));
    light.category = signalCategory(hue);
    std::vector<double> depths;
    for (const cv::Point& p : housing)
      if (const float z = in.depthAt(p.x, p.y); z > 0) depths.push_back(z);
    const double depth = depths.empty() ? 0 : quantile(depths, 0.25);
    if (depth > 0) {
      light.position_m = in.point(centre.x, centre.y, depth);
      light.height_m = in.ground.heightOf(light.position_m);
    }
    light.score = std::clamp(1.0 - runner_up / std::max(lamps.front().value, 1e-6), 0.0, 1.0);
    light.rule = "brightest_lamp";
    light.evidence = "housing " + std::to_string(box.width) + "x" + std::to_string(box.height) + " px, " +
                     std::to_string(lamps.size()) + " lamp(s) shown, brightest " + fixed(lamps.front().value) +
                     " (next " + fixed(runner_up) + "), chroma " + fixed(lamps.front().chroma) + ", hue " +
                     fixed(hue, 0) + " deg";
    light.source_instance = kTrafficLight;
    out.push_back(std::move(light));
    ++proposed;
  }
  report.add("traffic_lights_proposed", static_cast<std::int64_t>(proposed));
  if (dark > 0) report.notes.push_back(std::to_string(dark) + " traffic-light housings show no lit lamp (side or back)");
  if (undecided > 0)
    report.notes.push_back(std::to_string(undecided) +
                           " traffic-light housings show lamps of which none is clearly brighter: none proposed");
}

}  // namespace solo::proposals
