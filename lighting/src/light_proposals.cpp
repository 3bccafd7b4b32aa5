#include "solo/lighting/light_proposals.h"

#include "light_proposal_steps.h"
#include "solo/core/error.h"
#include "solo/lighting/light_geometry.h"
#include "solo/lighting/light_priors.h"
#include "solo/lighting/light_stage.h"

#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <cstdio>
#include <map>

namespace solo {
namespace proposals {

double quantile(std::vector<double>& values, double q) {
  if (values.empty()) return 0;
  const auto k = static_cast<std::size_t>(std::clamp(q, 0.0, 1.0) * static_cast<double>(values.size() - 1) + 0.5);
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(k), values.end());
  return values[k];
}

std::vector<cv::Point> convexPolygonPixels(const std::vector<cv::Point2d>& corners, cv::Size size) {
  std::vector<cv::Point> pixels;
  if (corners.size() < 3) return pixels;
  double u0 = 1e18, v0 = 1e18, u1 = -1e18, v1 = -1e18;
  for (const cv::Point2d& c : corners) {
    if (!std::isfinite(c.x) || !std::isfinite(c.y)) return pixels;
    u0 = std::min(u0, c.x), u1 = std::max(u1, c.x), v0 = std::min(v0, c.y), v1 = std::max(v1, c.y);
  }
  const cv::Rect box = cv::Rect(cv::Point(static_cast<int>(std::floor(u0)), static_cast<int>(std::floor(v0))),
                                cv::Point(static_cast<int>(std::ceil(u1)) + 2, static_cast<int>(std::ceil(v1)) + 2)) &
                       cv::Rect(0, 0, size.width, size.height);
  if (box.empty()) return pixels;
  cv::Mat mask = cv::Mat::zeros(box.size(), CV_8U);
  std::vector<cv::Point> poly;
  // Fixed point with 4 fractional bits keeps sub-pixel corners of small lamps.
  for (const cv::Point2d& c : corners)
    poly.emplace_back(static_cast<int>(std::lround((c.x - box.x) * 16)), static_cast<int>(std::lround((c.y - box.y) * 16)));
  cv::fillConvexPoly(mask, poly, cv::Scalar(255), cv::LINE_8, 4);
  for (int v = 0; v < mask.rows; ++v)
    for (int u = 0; u < mask.cols; ++u)
      if (mask.at<std::uint8_t>(v, u)) pixels.emplace_back(u + box.x, v + box.y);
  return pixels;
}

std::string fixed(double value, int decimals) {
  char text[64];
  std::snprintf(text, sizeof text, "%.*f", decimals, value);
  return text;
}

}  // namespace proposals

namespace {

using namespace proposals;

// The scene's maps at the image resolution.
ProposalInputs resampledInputs(const Scene& scene) {
  if (scene.labels.empty())
    throw InputError(scene.manifest.file, "light proposals need a label map (\"labels\" or \"instances\")");
  ProposalInputs in;
  const cv::Size size = scene.image.size();
  in.image = scene.image;
  in.labels = resampleLabels(scene.labels, size);
  in.instances = resampleLabels(scene.instances, size);
  in.depth_m = scene.depth_m.size() == size ? scene.depth_m : resampleDepthIgnoringInvalid(scene.depth_m, size);
  in.camera = scene.camera;
  in.pixel_scale = size.width / 1920.0;
  return in;
}

// The ground plane of the light priors (light_priors.h: RANSAC over road and sidewalk points,
// seeded, refitted on its inliers), with the proposals' inlier band; the level camera when it
// finds none (inliers = 0).
GroundPlaneFit fitGroundPlane(const ProposalInputs& in) {
  GroundFitOptions options;
  options.inlier_m = 0.08;
  options.inlier_fraction = 0.004;
  options.max_tilt_deg = 35;
  return fitGroundPlaneToRoad(in.depth_m, in.labels, in.camera, options);
}

void setGroundFrame(ProposalInputs& in, const GroundPlaneFit& ground) {
  in.ground = ground;
  const Eigen::Vector3d z(0, 0, 1);
  in.forward = (z - ground.up * ground.up.dot(z)).normalized();
  in.right = in.forward.cross(ground.up).normalized();
}

// Map ids per category in draft order, groups numbered from 1 in order of first use; a pixel
// keeps the first light that claims it.
void paintDrafts(const ProposalInputs& in, std::vector<DraftLight>& drafts, LightProposalResult& result) {
  result.lights = cv::Mat::zeros(in.labels.size(), CV_32S);
  result.light_groups = cv::Mat::zeros(in.labels.size(), CV_32S);
  std::array<int, kLastLightCategory + 1> next_k{};
  std::map<long, int> group_ids;
  for (DraftLight& draft : drafts) {
    const int c = static_cast<int>(draft.category);
    if (next_k[c] >= 999) continue;
    const int map_id = c * 1000 + (++next_k[c]);
    int group = 0;
    if (draft.group_key != 0) {
      const auto [it, added] = group_ids.emplace(draft.group_key, static_cast<int>(group_ids.size()) + 1);
      group = it->second;
    }
    LightProposal p;
    int u0 = in.width(), v0 = in.height(), u1 = -1, v1 = -1;
    for (const cv::Point& q : draft.pixels) {
      int& cell = result.lights.at<int>(q);
      if (cell != 0) continue;
      cell = map_id;
      if (group) result.light_groups.at<int>(q) = group;
      ++p.pixels;
      u0 = std::min(u0, q.x), u1 = std::max(u1, q.x), v0 = std::min(v0, q.y), v1 = std::max(v1, q.y);
    }
    if (p.pixels == 0) {
      --next_k[c];
      continue;
    }
    p.map_id = map_id;
    p.category = draft.category;
    p.box = cv::Rect(u0, v0, u1 - u0 + 1, v1 - v0 + 1);
    p.position_m = draft.position_m;
    p.height_m = draft.height_m;
    p.score = draft.score;
    p.rule = draft.rule;
    p.evidence = draft.evidence;
    p.group = group;
    p.source_instance = draft.source_instance;
    result.proposals.push_back(std::move(p));
  }
}

void summarise(LightProposalResult& result) {
  StageReport& report = result.report;
  report.name = "light_proposals";
  report.seconds = result.total_seconds;
  const LightCensus census = countLights(result.lights);
  report.add("lights", census.total_instances());
  for (int c = kFirstLightCategory; c <= kLastLightCategory; ++c)
    if (census.instances[c] > 0)
      report.add(std::string("lights_") + lightCategoryName(static_cast<LightCategory>(c)), census.instances[c]);
  report.add("ground_plane_points", result.ground.inliers);
  report.add("camera_height", result.ground.offset_m, "m");
  for (const auto& [step, seconds] : result.seconds) report.add(step + "_seconds", seconds, "s");
}

}  // namespace

LightProposalResult proposeLights(const Scene& scene, const LightProposalOptions& options) {
  const Stopwatch total;
  LightProposalResult result;
  ProposalInputs in = resampledInputs(scene);
  Stopwatch clock;
  setGroundFrame(in, fitGroundPlane(in));
  result.ground = in.ground;
  if (in.ground.inliers == 0)
    result.report.notes.push_back("no ground plane from road pixels: a level camera 1.5 m above the ground assumed");
  result.seconds.emplace_back("ground", clock.seconds());

  std::vector<DraftLight> drafts;
  const auto step = [&](bool enabled, const char* name, auto&& propose) {
    if (!enabled) return;
    const Stopwatch step_clock;
    propose(in, options, drafts, result.report);
    result.seconds.emplace_back(name, step_clock.seconds());
  };
  // Order = paint priority: small lamps before the facades' windows.
  step(options.traffic_lights, "traffic_lights", proposeTrafficLights);
  step(options.vehicles, "vehicles", proposeVehicleLamps);
  step(options.street_lights, "street_lights", proposeStreetLights);
  step(options.windows, "windows", proposeWindows);
  clock = Stopwatch();
  paintDrafts(in, drafts, result);
  result.seconds.emplace_back("paint", clock.seconds());
  result.total_seconds = total.seconds();
  summarise(result);
  return result;
}

Scene withProposedLights(const Scene& scene, const LightProposalResult& proposals) {
  Scene out = scene;
  out.lights = proposals.lights;
  out.light_groups = proposals.light_groups;
  return out;
}

std::string lightProposalsJson(const LightProposalResult& result, const std::string& scene_name) {
  using nlohmann::ordered_json;
  ordered_json j;
  j["format"] = "solo-light-proposals/1";
  j["scene"] = scene_name;
  j["image"] = {{"width", result.lights.cols}, {"height", result.lights.rows}};
  j["ground_plane"] = {{"up", {result.ground.up.x(), result.ground.up.y(), result.ground.up.z()}},
                       {"camera_height_m", result.ground.offset_m},
                       {"points", result.ground.inliers}};
  ordered_json seconds = ordered_json::object();
  for (const auto& [step, s] : result.seconds) seconds[step] = s;
  seconds["total"] = result.total_seconds;
  j["seconds"] = seconds;
  ordered_json counts = ordered_json::object();
  for (const LightProposal& p : result.proposals) {
    const char* name = lightCategoryName(p.category);
    counts[name] = counts.value(name, 0) + 1;
  }
  j["counts"] = counts;
  j["notes"] = result.report.notes;
  ordered_json list = ordered_json::array();
  for (const LightProposal& p : result.proposals)
    list.push_back({{"map_id", p.map_id},
                    {"category", lightCategoryName(p.category)},
                    {"box", {p.box.x, p.box.y, p.box.width, p.box.height}},
                    {"pixels", p.pixels},
                    {"position_m", {p.position_m.x(), p.position_m.y(), p.position_m.z()}},
                    {"height_m", p.height_m},
                    {"score", p.score},
                    {"rule", p.rule},
                    {"evidence", p.evidence},
                    {"group", p.group},
                    {"source_instance", p.source_instance}});
  j["proposals"] = list;
  return j.dump(1) + "\n";
}

namespace {

// Display colour (RGB 0-255) and short label of a category in the overlay.
std::pair<cv::Scalar, const char*> categoryStyle(LightCategory category) {
  switch (category) {
    case LightCategory::WindowBuilding: return {cv::Scalar(255, 210, 60), "win"};
    case LightCategory::TrafficLightRed: return {cv::Scalar(255, 30, 30), "TL red"};
    case LightCategory::TrafficLightOrange: return {cv::Scalar(255, 150, 0), "TL orange"};
    case LightCategory::TrafficLightGreen: return {cv::Scalar(30, 255, 90), "TL green"};
    case LightCategory::StreetLightHighCct: return {cv::Scalar(180, 220, 255), "street HT"};
    case LightCategory::StreetLightLowCct: return {cv::Scalar(255, 190, 90), "street LT"};
    case LightCategory::ParkedFront: return {cv::Scalar(255, 255, 255), "front P"};
    case LightCategory::MovingFront: return {cv::Scalar(255, 255, 160), "front M"};
    case LightCategory::ParkedRear: return {cv::Scalar(200, 0, 60), "rear P"};
    case LightCategory::MovingRear: return {cv::Scalar(255, 0, 0), "rear M"};
    default: return {cv::Scalar(255, 0, 255), lightCategoryName(category)};
  }
}

}  // namespace

cv::Mat drawLightProposals(const cv::Mat& day_image, const LightProposalResult& result) {
  cv::Mat canvas;
  day_image.convertTo(canvas, CV_8UC3, 255.0 * 0.45);
  if (canvas.size() != result.lights.size()) cv::resize(canvas, canvas, result.lights.size(), 0, 0, cv::INTER_AREA);
  std::map<int, const LightProposal*> by_id;
  for (const LightProposal& p : result.proposals) by_id[p.map_id] = &p;
  for (int v = 0; v < canvas.rows; ++v)
    for (int u = 0; u < canvas.cols; ++u) {
      const int id = result.lights.at<int>(v, u);
      if (id == 0) continue;
      const cv::Scalar colour = categoryStyle(static_cast<LightCategory>(id / 1000)).first;
      canvas.at<cv::Vec3b>(v, u) = cv::Vec3b(static_cast<std::uint8_t>(colour[0]), static_cast<std::uint8_t>(colour[1]),
                                             static_cast<std::uint8_t>(colour[2]));
    }
  const double font = std::max(0.3, 0.45 * canvas.cols / 1920.0 * 1.4);
  for (const LightProposal& p : result.proposals) {
    const auto [colour, label] = categoryStyle(p.category);
    if (p.category == LightCategory::WindowBuilding) continue;  // windows: their pixels say enough
    const cv::Rect box(p.box.x - 2, p.box.y - 2, p.box.width + 4, p.box.height + 4);
    cv::rectangle(canvas, box, colour, 1);
    cv::putText(canvas, label, cv::Point(box.x, std::max(10, box.y - 3)), cv::FONT_HERSHEY_SIMPLEX, font, colour, 1,
                cv::LINE_AA);
  }
  return canvas;
}

}  // namespace solo
