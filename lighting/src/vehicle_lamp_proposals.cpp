// Vehicle lamps: a symmetric pair (one lamp for two-wheelers) on the end face a vehicle
// instance shows the camera. The face is the vehicle's nearest 3D extent along the street. A
// vehicle off the street's centre line shows a flank toward it, a vertical plane whose points
// share one lateral position: the face ends there, and its outer side is the class's width away
// (or the instance's outline, when that agrees), so a neighbour hiding or mixing its depth into
// the outer side does not move the lamps. Front or rear from the day image (red lamps: rear;
// lamps brighter and whiter than the body: front), else from the lane (right-hand traffic: a
// vehicle ahead in or right of the camera's lane shows its rear). Parked when its kerb-side
// flank is within LightProposalOptions::parked_kerb_gap_m of the kerb.

#include "light_proposal_steps.h"

#include <opencv2/imgproc.hpp>

#include <cmath>
#include <limits>
#include <unordered_map>

namespace solo::proposals {
namespace {

// Lamp layout of a vehicle class: prior width (m), lamp size and heights above ground (m).
struct LampLayout {
  double vehicle_width_m = 0;
  double lamp_width_m = 0, lamp_height_m = 0;
  double front_centre_m = 0, rear_centre_m = 0;
  double inset_m = 0;   ///< from the face's side to the lamp's outer edge
  bool single = false;  ///< one lamp in the middle (two-wheelers)
};

bool layoutOf(int class_id, LampLayout& layout) {
  switch (class_id) {
    case kCar: layout = {1.8, 0.35, 0.16, 0.78, 0.88, 0.1, false}; return true;
    case kTruck: case kBus: case kCaravan: case kTrailer: case kTrain:
      layout = {2.5, 0.35, 0.16, 0.78, 0.88, 0.1, false};
      return true;
    case kMotorcycle: layout = {0.8, 0.2, 0.12, 1.0, 0.85, 0.0, true}; return true;
    case kBicycle: layout = {0.6, 0.12, 0.09, 0.95, 0.84, 0.0, true}; return true;
    default: return false;
  }
}

struct Kerbs {
  double left = -1e9, right = 1e9;  ///< lateral position of each kerb, metres; +-1e9: none seen
};

// The kerbs: the inner edge of the sidewalk on each side (else the road's outer edge).
Kerbs findKerbs(const ProposalInputs& in) {
  std::vector<double> walk_left, walk_right, road;
  const int step = std::max(1, in.scaledPixels(4));
  for (int v = 0; v < in.height(); v += step)
    for (int u = 0; u < in.width(); u += step) {
      const float z = in.depthAt(u, v);
      if (!(z > 0) || z > 80) continue;
      const int label = in.labelAt(u, v);
      if (label != kSidewalk && label != kRoad) continue;
      const double x = in.lateral(in.point(u, v, z));
      if (label == kRoad) road.push_back(x);
      else (x < 0 ? walk_left : walk_right).push_back(x);
    }
  Kerbs kerbs;
  std::vector<double> road_copy = road;
  if (walk_right.size() > 20) kerbs.right = quantile(walk_right, 0.03);
  else if (road.size() > 20) kerbs.right = quantile(road, 0.99);
  if (walk_left.size() > 20) kerbs.left = quantile(walk_left, 0.97);
  else if (road_copy.size() > 20) kerbs.left = quantile(road_copy, 0.01);
  return kerbs;
}

std::unordered_map<int, std::vector<cv::Point>> vehicleInstances(const ProposalInputs& in) {
  std::unordered_map<int, std::vector<cv::Point>> vehicles;
  LampLayout unused;
  for (int v = 0; v < in.height(); ++v)
    for (int u = 0; u < in.width(); ++u) {
      const int id = in.instances.at<int>(v, u);
      if (id >= 1000 && layoutOf(id / 1000, unused)) vehicles[id].emplace_back(u, v);
    }
  return vehicles;
}

// The instance's end face: its distance along the street, lateral extent, and its mask.
struct EndFace {
  double along_m = 0;
  double left_m = 0, right_m = 0;
  cv::Rect box;
  cv::Mat mask;         ///< CV_8U over box: the instance
  cv::Mat grown_mask;   ///< the instance dilated by the label maps' boundary error
  int points = 0;
  /// Lateral position of the flank the vehicle shows the street's centre line (a vertical
  /// plane: its points share it), NaN when too few of its points are seen.
  double flank_m = std::numeric_limits<double>::quiet_NaN();
};

// The flank's lateral position: the median lateral of the points 0.8-4 m behind the end face
// on the side toward the street's centre line, when at least 20 agree within 0.3 m (MAD).
double flankLateral(const ProposalInputs& in, const std::vector<cv::Point>& sampled, const std::vector<double>& along,
                    double face_along_m, double face_centre_m) {
  std::vector<double> lateral;
  for (std::size_t i = 0; i < along.size(); ++i) {
    if (along[i] < face_along_m + 0.8 || along[i] > face_along_m + 4.0) continue;
    const double x = in.lateral(in.point(sampled[i].x, sampled[i].y, in.depthAt(sampled[i].x, sampled[i].y)));
    if ((face_centre_m < 0) == (x > face_centre_m)) lateral.push_back(x);
  }
  const double nan = std::numeric_limits<double>::quiet_NaN();
  if (lateral.size() < 20) return nan;
  std::vector<double> copy = lateral;
  const double median = quantile(copy, 0.5);
  std::vector<double> deviation;
  for (double x : lateral) deviation.push_back(std::abs(x - median));
  if (quantile(deviation, 0.5) >= 0.3) return nan;
  // The flank's edge pixels take the depth of what lies behind them, which casts them outward:
  // the quartile toward the centre line.
  return quantile(lateral, face_centre_m < 0 ? 0.75 : 0.25);
}

bool measureEndFace(const ProposalInputs& in, const std::vector<cv::Point>& pixels, EndFace& face) {
  face.box = cv::boundingRect(pixels);
  const int margin = in.scaledPixels(4);
  face.box = cv::Rect(face.box.x - margin, face.box.y - margin, face.box.width + 2 * margin,
                      face.box.height + 2 * margin) & cv::Rect(0, 0, in.width(), in.height());
  face.mask = cv::Mat::zeros(face.box.size(), CV_8U);
  for (const cv::Point& p : pixels) face.mask.at<std::uint8_t>(p - face.box.tl()) = 255;
  cv::Mat inner;
  const cv::Mat kernel = cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * margin + 1, 2 * margin + 1));
  cv::erode(face.mask, inner, kernel);
  cv::dilate(face.mask, face.grown_mask, cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(5, 5)));
  // Distances along the street of the inner pixels (the boundary's depth mixes in the background).
  std::vector<cv::Point> sampled;
  std::vector<double> along;
  for (int pass = 0; pass < 2 && along.size() < 10; ++pass) {
    const cv::Mat& use = pass == 0 ? inner : face.mask;
    along.clear(), sampled.clear();
    for (int v = 0; v < use.rows; ++v)
      for (int u = 0; u < use.cols; ++u)
        if (use.at<std::uint8_t>(v, u)) {
          const float z = in.depthAt(u + face.box.x, v + face.box.y);
          if (!(z > 0)) continue;
          along.push_back(in.along(in.point(u + face.box.x, v + face.box.y, z)));
          sampled.emplace_back(u + face.box.x, v + face.box.y);
        }
  }
  face.points = static_cast<int>(along.size());
  if (face.points < 5) return false;
  std::vector<double> sorted = along;
  face.along_m = quantile(sorted, 0.03);
  if (face.along_m < 0.5) return false;
  // The face's pixels (within the depth noise of the nearest extent) cast onto the face plane:
  // their lateral positions there, widened by the eroded margin.
  const double thickness = 0.3 + 0.02 * face.along_m;
  std::vector<double> lateral;
  const Eigen::Vector3d origin = in.groundFramePoint(0, 0, face.along_m);
  for (std::size_t i = 0; i < along.size(); ++i) {
    if (along[i] > face.along_m + thickness) continue;
    const Eigen::Vector3d r = in.ray(sampled[i].x, sampled[i].y);
    lateral.push_back(in.lateral(r * (in.forward.dot(origin) / in.forward.dot(r))));
  }
  if (lateral.size() < 5) return false;
  const double margin_m = (margin + 0.5) * face.along_m / in.camera.fx;
  face.left_m = quantile(lateral, 0.01) - margin_m;
  face.right_m = quantile(lateral, 0.99) + margin_m;
  face.flank_m = flankLateral(in, sampled, along, face.along_m, (face.left_m + face.right_m) / 2);
  return face.right_m > face.left_m;
}

// Lateral positions, on the face plane at `along_m`, of the instance's outermost columns in
// the rows between heights h0 and h1 above ground.
bool outlineExtent(const ProposalInputs& in, const EndFace& face, double along_m, double h0, double h1,
                   double& left_m, double& right_m) {
  const Eigen::Vector2d low = in.camera.project(in.groundFramePoint(0, h0, along_m));
  const Eigen::Vector2d high = in.camera.project(in.groundFramePoint(0, h1, along_m));
  const int v0 = std::max(0, static_cast<int>(std::floor(high.y())) - face.box.y);
  const int v1 = std::min(face.mask.rows - 1, static_cast<int>(std::ceil(low.y())) - face.box.y);
  int first = face.mask.cols, last = -1;
  for (int v = v0; v <= v1; ++v)
    for (int u = 0; u < face.mask.cols; ++u)
      if (face.mask.at<std::uint8_t>(v, u)) first = std::min(first, u), last = std::max(last, u);
  if (last < first) return false;
  const Eigen::Vector3d origin = in.groundFramePoint(0, (h0 + h1) / 2, along_m);
  const auto cast = [&](double u) {
    const Eigen::Vector3d r = in.ray(u, (low.y() + high.y()) / 2);
    return in.lateral(r * (in.forward.dot(origin) / in.forward.dot(r)));
  };
  left_m = cast(first + face.box.x);
  right_m = cast(last + face.box.x + 1.0);
  return true;
}

// Which side of the face is cut, by an occluder or by the frame: -1 left, +1 right, 0 neither or
// both. Looks just beyond the instance's extreme columns, at a dozen rows, for another vehicle.
int cutSide(const ProposalInputs& in, const EndFace& face, int instance) {
  std::array<int, 2> hits{};
  const int gap = in.scaledPixels(6);
  for (int v = 0; v < face.mask.rows; v += std::max(1, face.mask.rows / 12)) {
    int first = -1, last = -1;
    for (int u = 0; u < face.mask.cols; ++u)
      if (face.mask.at<std::uint8_t>(v, u)) {
        if (first < 0) first = u;
        last = u;
      }
    if (first < 0) continue;
    for (int s = 0; s < 2; ++s) {
      const int edge = face.box.x + (s == 0 ? first : last);
      if (edge <= 1 || edge >= in.width() - 2) {
        ++hits[static_cast<std::size_t>(s)];
        continue;
      }
      const int u = std::clamp(s == 0 ? edge - gap : edge + gap, 0, in.width() - 1);
      const int other = in.instances.at<int>(face.box.y + v, u);
      LampLayout unused;
      if (other != instance && other >= 1000 && layoutOf(other / 1000, unused)) ++hits[static_cast<std::size_t>(s)];
    }
  }
  if (hits[0] > 1 && hits[1] <= 1) return -1;
  if (hits[1] > 1 && hits[0] <= 1) return 1;
  return 0;
}

// Front or rear from the colours inside the lamp regions against the body's colour.
struct LampColours {
  double red_share = 0, bright_share = 0;
  bool body_red = false;
  double body_luma = 0;
};

bool isRed(const cv::Vec3f& c, double floor) { return c[0] > floor && c[0] > 2.2 * c[1] && c[0] > 2.2 * c[2]; }

double luma(const cv::Vec3f& c) { return 0.299 * c[0] + 0.587 * c[1] + 0.114 * c[2]; }

// A lamp-white pixel: brighter than the body and not strongly coloured.
bool isBright(const cv::Vec3f& c, double body_luma) {
  const double l = luma(c);
  const double spread = std::max({c[0], c[1], c[2]}) - std::min({c[0], c[1], c[2]});
  return l > body_luma + 0.12 && spread < 0.25 + 0.3 * l;
}

LampColours lampColours(const ProposalInputs& in, const EndFace& face, const std::vector<std::vector<cv::Point>>& lamps) {
  std::vector<double> body_r, body_g, body_b, body_luma;
  for (int v = 0; v < face.mask.rows; ++v)
    for (int u = 0; u < face.mask.cols; ++u)
      if (face.mask.at<std::uint8_t>(v, u)) {
        const cv::Vec3f c = in.image.at<cv::Vec3f>(v + face.box.y, u + face.box.x);
        body_r.push_back(c[0]), body_g.push_back(c[1]), body_b.push_back(c[2]);
        body_luma.push_back(luma(c));
      }
  LampColours colours;
  const cv::Vec3f body(static_cast<float>(quantile(body_r, 0.5)), static_cast<float>(quantile(body_g, 0.5)),
                       static_cast<float>(quantile(body_b, 0.5)));
  colours.body_luma = quantile(body_luma, 0.5);
  colours.body_red = isRed(body, 0.12);
  std::int64_t total = 0, red = 0, bright = 0;
  for (const auto& lamp : lamps)
    for (const cv::Point& p : lamp) {
      const cv::Vec3f c = in.image.at<cv::Vec3f>(p);
      ++total;
      red += isRed(c, 0.15);
      bright += isBright(c, colours.body_luma);
    }
  if (total > 0) {
    colours.red_share = static_cast<double>(red) / static_cast<double>(total);
    colours.bright_share = static_cast<double>(bright) / static_cast<double>(total);
  }
  return colours;
}

// Pixels of a lamp rectangle on the face (lateral x0..x1, heights h0..h1) that the instance shows.
std::vector<cv::Point> lampPixels(const ProposalInputs& in, const EndFace& face, double x0, double x1, double h0,
                                  double h1, double& visible_share) {
  std::vector<cv::Point2d> corners;
  for (const auto& [x, h] : {std::pair{x0, h0}, {x1, h0}, {x1, h1}, {x0, h1}}) {
    const Eigen::Vector3d p = in.groundFramePoint(x, h, face.along_m);
    if (p.z() <= 0.05) return {};
    const Eigen::Vector2d uv = in.camera.project(p);
    corners.emplace_back(uv.x(), uv.y());
  }
  std::vector<cv::Point> all = convexPolygonPixels(corners, in.labels.size()), shown;
  for (const cv::Point& p : all) {
    const cv::Point local = p - face.box.tl();
    if (face.box.contains(p) && face.grown_mask.at<std::uint8_t>(local)) shown.push_back(p);
  }
  visible_share = all.empty() ? 0 : static_cast<double>(shown.size()) / static_cast<double>(all.size());
  return shown;
}

// Replaces the prior box `pixels` by the lamp-coloured pixels (red for a rear lamp on a body
// that is not red, lamp-white for a front lamp) around it, 0.25 m up or down and half a lamp
// sideways, when they are at least 30 % of the box: the day image outlines the lamp better
// than a prior height on a depth with a scale error.
bool snapToLampColour(const ProposalInputs& in, const EndFace& face, const LampColours& colours, bool rear, double x0,
                      double x1, double h_centre, std::vector<cv::Point>& pixels) {
  if (rear && colours.body_red) return false;
  const double half = (x1 - x0) / 2;
  double visible = 0;
  std::vector<cv::Point> found;
  for (const cv::Point& p : lampPixels(in, face, x0 - half, x1 + half, h_centre - 0.33, h_centre + 0.33, visible)) {
    const cv::Vec3f c = in.image.at<cv::Vec3f>(p);
    if (rear ? isRed(c, 0.15) : isBright(c, colours.body_luma)) found.push_back(p);
  }
  if (found.size() < 3 || static_cast<double>(found.size()) < 0.3 * static_cast<double>(pixels.size())) return false;
  // Lamp-coloured pixels spread well beyond a lamp's size are body or background, not a lamp.
  const cv::Rect prior = cv::boundingRect(pixels), snapped = cv::boundingRect(found);
  if (snapped.width > 1.6 * prior.width + 2 || snapped.height > 1.6 * prior.height + 2) return false;
  pixels.swap(found);
  return true;
}

// The end face's lateral extent. A vehicle off the street's centre line shows the flank on the
// centre line's side: the face ends where that flank plane is (its own depth, which no neighbour
// mixes into), and the outer side is the instance's outline when it lies the class's width away
// (else an occluder or the frame cuts it: the class's width from the flank). A vehicle on the
// centre line shows no flank: both sides from its outline. Two-wheelers: their outline.
struct FaceExtent {
  double left_m = 0, right_m = 0;
  const char* rule = "outline";
};

FaceExtent placeFace(const ProposalInputs& in, const LampLayout& layout, const EndFace& face, int cut_side) {
  FaceExtent placed{face.left_m, face.right_m, "depth_extent"};
  double left = 0, right = 0;
  const double h0 = layout.front_centre_m - layout.lamp_height_m, h1 = layout.rear_centre_m + layout.lamp_height_m;
  if (!outlineExtent(in, face, face.along_m, h0, h1, left, right)) return placed;
  const double width = layout.vehicle_width_m;
  const double centre = (face.left_m + face.right_m) / 2;
  if (layout.single || (std::abs(centre) < 0.5 * width && cut_side == 0)) return {left, right, "outline"};
  const bool from_flank = !std::isnan(face.flank_m);
  if (centre < 0) {  // the outer side is the left, the flank on the right
    const double inner = from_flank ? face.flank_m : face.right_m;
    const bool outline_fits = cut_side >= 0 && std::abs(inner - left - width) < 0.1 * width;
    placed = {outline_fits ? left : inner - width, inner, ""};
  } else {
    const double inner = from_flank ? face.flank_m : face.left_m;
    const bool outline_fits = cut_side <= 0 && std::abs(right - inner - width) < 0.1 * width;
    placed = {inner, outline_fits ? right : inner + width, ""};
  }
  placed.rule = from_flank ? "flank" : "depth_extent";
  return placed;
}

// Lateral extents of the lamps on a face of width left..right (one or two).
std::vector<std::pair<double, double>> lampSpans(const LampLayout& layout, double left, double right) {
  const double width = right - left;
  if (layout.single) {
    const double mid = (left + right) / 2;
    return {{mid - layout.lamp_width_m / 2, mid + layout.lamp_width_m / 2}};
  }
  const double lamp = std::min(layout.lamp_width_m, 0.22 * width);
  const double inset = std::min(layout.inset_m, 0.06 * width);
  return {{left + inset, left + inset + lamp}, {right - inset - lamp, right - inset}};
}

}  // namespace

void proposeVehicleLamps(const ProposalInputs& in, const LightProposalOptions& options, std::vector<DraftLight>& out,
                         StageReport& report) {
  if (in.instances.empty()) {
    report.notes.push_back("no instance map: no vehicle lamps proposed");
    return;
  }
  const Kerbs kerbs = findKerbs(in);
  const int min_pixels = std::max(20, static_cast<int>(150 * in.pixel_scale * in.pixel_scale));
  std::vector<std::pair<int, std::vector<cv::Point>>> vehicles;
  for (auto& entry : vehicleInstances(in)) vehicles.emplace_back(entry.first, std::move(entry.second));
  std::sort(vehicles.begin(), vehicles.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  int proposed = 0, skipped = 0, no_end_face = 0;
  for (const auto& [instance, pixels] : vehicles) {
    LampLayout layout;
    layoutOf(instance / 1000, layout);
    EndFace face;
    if (static_cast<int>(pixels.size()) < min_pixels || !measureEndFace(in, pixels, face)) {
      ++skipped;
      continue;
    }
    // A face much narrower than the class's width is a flank seen along the street, not an end,
    // unless a flank shows beside it and the frame does not cut the vehicle: then it is an end
    // the next vehicle in the row hides.
    const bool in_frame = face.box.x > 0 && face.box.br().x < in.width();
    const bool hidden_end = in_frame && !std::isnan(face.flank_m);
    if (!layout.single && !hidden_end && face.right_m - face.left_m < 0.45 * layout.vehicle_width_m) {
      ++no_end_face;
      continue;
    }
    const FaceExtent extent = placeFace(in, layout, face, cutSide(in, face, instance));
    const double left = extent.left_m, right = extent.right_m;
    const double centre = (left + right) / 2;
    const double gap = centre >= 0 ? kerbs.right - right : left - kerbs.left;
    const bool parked = std::abs(centre) > 1.0 && gap < options.parked_kerb_gap_m;

    // Colour evidence inside the lamps' regions at the rear height (the band both share).
    const auto spans = lampSpans(layout, left, right);
    std::vector<std::vector<cv::Point>> probe;
    double share = 0;
    for (const auto& [x0, x1] : spans)
      probe.push_back(lampPixels(in, face, x0, x1, layout.front_centre_m - layout.lamp_height_m,
                                 layout.rear_centre_m + layout.lamp_height_m, share));
    const LampColours colours = lampColours(in, face, probe);
    bool rear;
    std::string rule;
    if (!colours.body_red && colours.red_share > 0.15) rear = true, rule = "red_lamps_rear";
    else if (colours.bright_share > 0.15) rear = false, rule = "white_lamps_front";
    else if (colours.body_red) rear = true, rule = "red_body_no_white_lamps_rear";
    else if (!parked) rear = centre > -1.2, rule = rear ? "own_direction_lane_rear" : "oncoming_lane_front";
    else rear = false, rule = "no_colour_evidence_front";

    const double h_centre = rear ? layout.rear_centre_m : layout.front_centre_m;
    const LightCategory category = rear ? (parked ? LightCategory::ParkedRear : LightCategory::MovingRear)
                                        : (parked ? LightCategory::ParkedFront : LightCategory::MovingFront);
    for (const auto& [x0, x1] : spans) {
      double visible = 0;
      DraftLight light;
      light.pixels = lampPixels(in, face, x0, x1, h_centre - layout.lamp_height_m / 2,
                                h_centre + layout.lamp_height_m / 2, visible);
      if (visible < 0.3 || light.pixels.size() < 2) continue;
      const bool snapped = snapToLampColour(in, face, colours, rear, x0, x1, h_centre, light.pixels);
      light.category = category;
      light.position_m = in.groundFramePoint((x0 + x1) / 2, h_centre, face.along_m);
      light.height_m = h_centre;
      light.score = std::clamp(0.4 + 0.6 * std::max(colours.red_share, colours.bright_share), 0.0, 1.0) * visible;
      light.rule = rule + (snapped ? "+lamp_pixels" : "+prior_box") + (parked ? "+parked_at_kerb" : "+moving");
      light.evidence = "face at " + fixed(face.along_m, 1) + " m, lateral " + fixed(left) + ".." + fixed(right) +
                       " m (" + extent.rule + "), kerb gap " + fixed(gap) + " m; red share " + fixed(colours.red_share) + ", bright share " +
                       fixed(colours.bright_share) + (colours.body_red ? ", red body" : "") + "; visible " +
                       fixed(visible);
      light.source_instance = instance;
      out.push_back(std::move(light));
    }
    ++proposed;
  }
  report.add("vehicles_with_lamps", static_cast<std::int64_t>(proposed));
  report.notes.push_back("kerbs at lateral " + fixed(kerbs.left) + " and " + fixed(kerbs.right) + " m; " +
                         std::to_string(skipped) + " vehicle instances too small or without depth, " + std::to_string(no_end_face) +
                         " showing no end face");
}

}  // namespace solo::proposals
