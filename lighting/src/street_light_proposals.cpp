// Street lights: a lamp head at the top of every pole (Cityscapes class 17) whose top reaches
// 4-12 m above the ground plane; on the arm's far end when the pole has an arm. A head whose pole
// is not seen: a small island of non-sky pixels inside the sky, above the horizon, 4-12 m high.

#include "light_proposal_steps.h"

#include <opencv2/imgproc.hpp>

#include <cmath>

namespace solo::proposals {
namespace {

// One 8-connected blob of pole pixels.
struct PoleBlob {
  std::vector<cv::Point> pixels;
  cv::Rect box;
};

std::vector<PoleBlob> poleBlobs(const ProposalInputs& in, int min_pixels) {
  cv::Mat mask = in.labels == kPole;
  cv::Mat ids, stats, centroids;
  const int n = cv::connectedComponentsWithStats(mask, ids, stats, centroids, 8, CV_32S);
  std::vector<PoleBlob> blobs(static_cast<std::size_t>(n));
  for (int v = 0; v < ids.rows; ++v)
    for (int u = 0; u < ids.cols; ++u)
      if (const int id = ids.at<int>(v, u); id > 0) blobs[static_cast<std::size_t>(id)].pixels.emplace_back(u, v);
  std::vector<PoleBlob> kept;
  for (int i = 1; i < n; ++i) {
    if (stats.at<int>(i, cv::CC_STAT_AREA) < min_pixels) continue;
    PoleBlob& b = blobs[static_cast<std::size_t>(i)];
    b.box = cv::Rect(stats.at<int>(i, cv::CC_STAT_LEFT), stats.at<int>(i, cv::CC_STAT_TOP),
                     stats.at<int>(i, cv::CC_STAT_WIDTH), stats.at<int>(i, cv::CC_STAT_HEIGHT));
    kept.push_back(std::move(b));
  }
  return kept;
}

// Median column of the blob's pixels in rows [v0, v1].
double medianColumn(const PoleBlob& blob, int v0, int v1) {
  std::vector<double> columns;
  for (const cv::Point& p : blob.pixels)
    if (p.y >= v0 && p.y <= v1) columns.push_back(p.x);
  return columns.empty() ? blob.box.x + blob.box.width / 2.0 : quantile(columns, 0.5);
}

// The pole's depth: where its foot meets the ground (the ray of the bottom pixel on the ground
// plane) when ground lies under it; else the 5th percentile of its pixels' depths (thin poles
// bleed into the background behind them, never in front).
double poleDepth(const ProposalInputs& in, const PoleBlob& blob, std::string& how) {
  const int bottom = blob.box.y + blob.box.height - 1;
  const double foot_u = medianColumn(blob, bottom - in.scaledPixels(2), bottom);
  bool on_ground = false;
  for (int dv = 1; dv <= in.scaledPixels(3) && bottom + dv < in.height(); ++dv) {
    const int label = in.labelAt(static_cast<int>(foot_u), bottom + dv);
    on_ground = on_ground || label == kRoad || label == kSidewalk || label == kParking || label == kTerrain;
  }
  if (on_ground) {
    const double z = in.rayHeightDepth(foot_u, bottom + 0.5, 0.0);
    if (z > 0.5 && z < 500) {
      how = "foot on the ground plane";
      return z;
    }
  }
  std::vector<double> depths;
  for (const cv::Point& p : blob.pixels)
    if (const float z = in.depthAt(p.x, p.y); z > 0) depths.push_back(z);
  how = "5th percentile of the pole's depths";
  return depths.size() < 3 ? -1.0 : quantile(depths, 0.05);
}

// The head's pixels: on the arm's far end (the blob's upper 1.2 m reaches more than 0.5 m to
// one side of the pole), else the blob's top 0.6 m (a lantern on the pole).
std::vector<cv::Point> headPixels(const ProposalInputs& in, const PoleBlob& blob, double depth, bool& arm) {
  const double metres_per_px = depth / in.camera.fx;
  const int top = blob.box.y;
  const int bottom = blob.box.y + blob.box.height - 1;
  const double axis_u = medianColumn(blob, top + static_cast<int>(0.35 * (bottom - top)), bottom);
  const int upper_end = top + static_cast<int>(1.2 / metres_per_px);
  std::vector<double> offsets;
  for (const cv::Point& p : blob.pixels)
    if (p.y <= upper_end) offsets.push_back((p.x - axis_u) * metres_per_px);
  std::vector<double> sorted = offsets;
  const double reach_left = -quantile(sorted, 0.02), reach_right = quantile(sorted, 0.98);
  const double reach = std::max(reach_left, reach_right);
  const double side = reach_right >= reach_left ? 1.0 : -1.0;
  arm = reach > 0.5;
  std::vector<cv::Point> head;
  const int lantern_end = top + static_cast<int>(0.6 / metres_per_px);
  for (const cv::Point& p : blob.pixels) {
    if (p.y > upper_end) continue;
    const double offset = (p.x - axis_u) * metres_per_px * side;
    if (arm ? offset >= reach - 0.9 : p.y <= lantern_end) head.push_back(p);
  }
  return head;
}

// The street-light category for a head `height_m` above the ground.
LightCategory streetLightCategory(double height_m, const LightProposalOptions& options) {
  return height_m < options.warm_lantern_below_m ? LightCategory::StreetLightLowCct : LightCategory::StreetLightHighCct;
}

// Lamp heads seen against the sky: 8-connected islands of non-sky pixels wholly inside the sky
// (not touching the frame), above the horizon, of at least 8 px, no larger than 1.5 x 1.0 m at the
// median of their valid depths (at least 3 pixels), 4-12 m above the ground, mostly neither
// vegetation, traffic light nor traffic sign, and sharing no pixel with a head already proposed.
int proposeSkyHeads(const ProposalInputs& in, const LightProposalOptions& options, std::vector<DraftLight>& out) {
  cv::Mat taken = cv::Mat::zeros(in.labels.size(), CV_8U);
  for (const DraftLight& light : out)
    for (const cv::Point& p : light.pixels) taken.at<std::uint8_t>(p) = 1;
  cv::Mat mask = in.labels != kSky;
  cv::Mat ids, stats, centroids;
  const int n = cv::connectedComponentsWithStats(mask, ids, stats, centroids, 8, CV_32S);
  const int min_pixels = std::max(8, static_cast<int>(8.0 * in.pixel_scale * in.pixel_scale));
  std::vector<int> candidate(static_cast<std::size_t>(n), 0);
  for (int i = 1; i < n; ++i) {
    const cv::Rect box(stats.at<int>(i, cv::CC_STAT_LEFT), stats.at<int>(i, cv::CC_STAT_TOP),
                       stats.at<int>(i, cv::CC_STAT_WIDTH), stats.at<int>(i, cv::CC_STAT_HEIGHT));
    const bool inside = box.x > 0 && box.y > 0 && box.br().x < in.width() && box.br().y < in.height();
    const bool small = stats.at<int>(i, cv::CC_STAT_AREA) >= min_pixels && box.area() <= in.width() * in.height() / 200;
    candidate[static_cast<std::size_t>(i)] = inside && small ? 1 : 0;
  }
  std::vector<std::vector<cv::Point>> islands(static_cast<std::size_t>(n));
  for (int v = 0; v < ids.rows; ++v)
    for (int u = 0; u < ids.cols; ++u)
      if (const int id = ids.at<int>(v, u); id > 0 && candidate[static_cast<std::size_t>(id)])
        islands[static_cast<std::size_t>(id)].emplace_back(u, v);
  int proposed = 0;
  for (int i = 1; i < n; ++i) {
    const std::vector<cv::Point>& pixels = islands[static_cast<std::size_t>(i)];
    if (pixels.empty()) continue;
    const double cu = centroids.at<double>(i, 0), cv_ = centroids.at<double>(i, 1);
    if (in.rayHeightDepth(cu, cv_, 0.0) > 0) continue;  // below the horizon: the ray meets the ground
    std::vector<double> depths;
    int excluded = 0;
    bool overlaps = false;
    for (const cv::Point& p : pixels) {
      if (const float z = in.depthAt(p.x, p.y); z > 0) depths.push_back(z);
      const int label = in.labelAt(p.x, p.y);
      excluded += label == 21 || label == kTrafficLight || label == 20;
      overlaps = overlaps || taken.at<std::uint8_t>(p) != 0;
    }
    if (overlaps || depths.size() < 3 || 2 * excluded > static_cast<int>(pixels.size())) continue;
    const double depth = quantile(depths, 0.5);
    const double metres_per_px = depth / in.camera.fx;
    if (stats.at<int>(i, cv::CC_STAT_WIDTH) * metres_per_px > 1.5 || stats.at<int>(i, cv::CC_STAT_HEIGHT) * metres_per_px > 1.0)
      continue;
    DraftLight light;
    light.position_m = in.point(cu, cv_, depth);
    light.height_m = in.ground.heightOf(light.position_m);
    if (light.height_m < options.min_pole_top_m || light.height_m > options.max_pole_top_m) continue;
    light.pixels = pixels;
    light.category = streetLightCategory(light.height_m, options);
    light.score = 0.5;
    light.rule = "head_against_sky";
    light.evidence = "non-sky island of " + std::to_string(pixels.size()) + " px inside the sky at " + fixed(depth, 1) +
                     " m (median depth), " + fixed(light.height_m) + " m above ground";
    light.source_instance = kPole;
    out.push_back(std::move(light));
    ++proposed;
  }
  return proposed;
}

}  // namespace

void proposeStreetLights(const ProposalInputs& in, const LightProposalOptions& options, std::vector<DraftLight>& out,
                         StageReport& report) {
  int out_of_range = 0, cut_by_frame = 0, no_depth = 0, proposed = 0;
  for (const PoleBlob& blob : poleBlobs(in, std::max(8, static_cast<int>(40.0 * in.pixel_scale * in.pixel_scale)))) {
    std::string depth_rule;
    const double depth = poleDepth(in, blob, depth_rule);
    if (depth <= 0) {
      ++no_depth;
      continue;
    }
    const double top_u = medianColumn(blob, blob.box.y, blob.box.y + in.scaledPixels(2));
    const double top_height = in.ground.heightOf(in.point(top_u, blob.box.y, depth));
    if (top_height < options.min_pole_top_m || top_height > options.max_pole_top_m) {
      if (blob.box.y > 0 || top_height > options.max_pole_top_m) ++out_of_range;
      else ++cut_by_frame;
      continue;
    }
    if (blob.box.y == 0) {  // the pole leaves the frame: its head is not in view
      ++cut_by_frame;
      continue;
    }
    bool arm = false;
    DraftLight light;
    light.pixels = headPixels(in, blob, depth, arm);
    if (static_cast<double>(light.pixels.size()) < 8 * in.pixel_scale * in.pixel_scale) continue;
    cv::Point2d centre(0, 0);
    for (const cv::Point& p : light.pixels) centre += cv::Point2d(p.x, p.y);
    centre *= 1.0 / static_cast<double>(light.pixels.size());
    light.position_m = in.point(centre.x, centre.y, depth);
    light.height_m = in.ground.heightOf(light.position_m);
    light.category = streetLightCategory(light.height_m, options);
    light.score = std::clamp(1.0 - std::abs(top_height - 8.0) / 8.0, 0.1, 1.0) * (arm ? 1.0 : 0.8);
    light.rule = arm ? "pole_top_arm_end" : "pole_top_lantern";
    light.evidence = "pole top " + fixed(top_height) + " m above ground at " + fixed(depth, 1) + " m (" + depth_rule +
                     "); head " + fixed(light.height_m) + " m: " +
                     (light.category == LightCategory::StreetLightLowCct ? "below" : "at or above") + " the " +
                     fixed(options.warm_lantern_below_m, 1) + " m lantern height";
    light.source_instance = kPole;
    out.push_back(std::move(light));
    ++proposed;
  }
  report.add("street_lights_proposed", static_cast<std::int64_t>(proposed));
  report.add("street_light_heads_against_sky", static_cast<std::int64_t>(proposeSkyHeads(in, options, out)));
  report.notes.push_back("poles: " + std::to_string(out_of_range) + " with a top outside " +
                         fixed(options.min_pole_top_m, 0) + "-" + fixed(options.max_pole_top_m, 0) + " m, " +
                         std::to_string(cut_by_frame) + " leaving the frame, " + std::to_string(no_depth) +
                         " without depth");
}

}  // namespace solo::proposals
