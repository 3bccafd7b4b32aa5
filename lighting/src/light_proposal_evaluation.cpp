// Accuracy of light proposals against an exact light map: instance matching at an IoU
// threshold per category family, 3D error of the matches, agreement of the finer category.

#include "solo/lighting/light_proposals.h"

#include <algorithm>
#include <cstdio>
#include <map>
#include <unordered_map>

namespace solo {

const char* lightFamilyName(LightFamily family) {
  switch (family) {
    case LightFamily::StreetLight: return "street lights";
    case LightFamily::TrafficLight: return "traffic lights";
    case LightFamily::VehicleLamp: return "vehicle lamps";
    case LightFamily::Window: return "windows";
  }
  return "?";
}

int lightFamilyOf(LightCategory category) {
  switch (category) {
    case LightCategory::WindowBuilding: return static_cast<int>(LightFamily::Window);
    case LightCategory::TrafficLightRed:
    case LightCategory::TrafficLightOrange:
    case LightCategory::TrafficLightGreen: return static_cast<int>(LightFamily::TrafficLight);
    case LightCategory::StreetLightHighCct:
    case LightCategory::StreetLightLowCct: return static_cast<int>(LightFamily::StreetLight);
    case LightCategory::ParkedFront:
    case LightCategory::MovingFront:
    case LightCategory::ParkedRear:
    case LightCategory::MovingRear: return static_cast<int>(LightFamily::VehicleLamp);
    default: return -1;
  }
}

double FamilyScore::precision() const {
  const std::int64_t counted = proposals - ignored_proposals;
  return counted > 0 ? static_cast<double>(matched) / static_cast<double>(counted) : 1.0;
}

double FamilyScore::recall() const {
  const std::int64_t counted = true_lights - ignored_true;
  return counted > 0 ? static_cast<double>(matched) / static_cast<double>(counted) : 1.0;
}

void FamilyScore::add(const FamilyScore& o) {
  true_lights += o.true_lights, proposals += o.proposals, matched += o.matched;
  ignored_true += o.ignored_true, ignored_proposals += o.ignored_proposals;
  category_agrees += o.category_agrees, side_agrees += o.side_agrees, state_agrees += o.state_agrees;
  error_m.insert(error_m.end(), o.error_m.begin(), o.error_m.end());
}

namespace {

int familyOfId(int id) {
  const int c = id / 1000;
  return c >= kFirstLightCategory && c <= kLastLightCategory ? lightFamilyOf(static_cast<LightCategory>(c)) : -1;
}

struct Instance {
  std::int64_t pixels = 0;
  std::vector<double> x, y, z;  ///< backprojected pixels with a true depth
};

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

bool isRear(int category) { return category == 11 || category == 12; }
bool isParked(int category) { return category == 9 || category == 11; }

}  // namespace

ProposalEvaluation evaluateLightProposals(const LightProposalResult& proposed, const cv::Mat& truth,
                                          const cv::Mat& true_depth_m, const PinholeCamera& camera,
                                          const ProposalEvaluationOptions& options) {
  std::map<int, Instance> true_lights;
  std::map<int, std::int64_t> proposal_pixels;
  std::map<int, cv::Rect> true_box, proposal_box;
  std::map<std::pair<int, int>, std::int64_t> overlap;  // (true id, proposed id)
  for (int v = 0; v < truth.rows; ++v)
    for (int u = 0; u < truth.cols; ++u) {
      const int t = truth.at<int>(v, u), p = proposed.lights.at<int>(v, u);
      const int tf = t > 0 ? familyOfId(t) : -1, pf = p > 0 ? familyOfId(p) : -1;
      if (tf >= 0) true_box[t] |= cv::Rect(u, v, 1, 1);
      if (pf >= 0) proposal_box[p] |= cv::Rect(u, v, 1, 1);
      if (tf >= 0) {
        Instance& instance = true_lights[t];
        ++instance.pixels;
        const float z = true_depth_m.at<float>(v, u);
        if (z > 0) {
          const Eigen::Vector3d q = camera.backproject(u, v, z);
          instance.x.push_back(q.x()), instance.y.push_back(q.y()), instance.z.push_back(q.z());
        }
      }
      if (pf >= 0) ++proposal_pixels[p];
      if (tf >= 0 && tf == pf) ++overlap[{t, p}];
    }
  std::map<int, Eigen::Vector3d> proposed_position;
  for (const LightProposal& p : proposed.proposals) proposed_position[p.map_id] = p.position_m;

  struct Pair {
    double iou;
    int t, p;
  };
  std::vector<Pair> pairs;
  for (const auto& [key, count] : overlap) {
    const double uni = static_cast<double>(true_lights[key.first].pixels + proposal_pixels[key.second] - count);
    pairs.push_back({static_cast<double>(count) / uni, key.first, key.second});
  }
  std::sort(pairs.begin(), pairs.end(), [](const Pair& a, const Pair& b) {
    return a.iou != b.iou ? a.iou > b.iou : (a.t != b.t ? a.t < b.t : a.p < b.p);
  });
  ProposalEvaluation result;
  std::map<int, int> true_match, proposal_match;
  std::map<int, double> true_best, proposal_best;
  for (const Pair& pair : pairs) {
    true_best[pair.t] = std::max(true_best[pair.t], pair.iou);
    proposal_best[pair.p] = std::max(proposal_best[pair.p], pair.iou);
  }
  for (const Pair& pair : pairs) {
    if (pair.iou < options.min_iou || true_match.count(pair.t) || proposal_match.count(pair.p)) continue;
    true_match[pair.t] = pair.p;
    proposal_match[pair.p] = pair.t;
  }
  const auto ignored = [&](int t) { return true_lights[t].pixels < options.min_true_pixels; };
  // Share of each unmatched proposal's pixels on ignored true lights.
  std::map<int, std::int64_t> on_ignored;
  for (const auto& [key, count] : overlap)
    if (ignored(key.first)) on_ignored[key.second] += count;
  for (auto& [t, instance] : true_lights) {
    FamilyScore& s = result.families[static_cast<std::size_t>(familyOfId(t))];
    ++s.true_lights;
    if (ignored(t)) {
      ++s.ignored_true;
      continue;
    }
    const auto match = true_match.find(t);
    if (match == true_match.end()) {
      result.misses.push_back({false, t, true_box[t], instance.pixels, true_best[t]});
      continue;
    }
    ++s.matched;
    const int pc = match->second / 1000, tc = t / 1000;
    s.category_agrees += pc == tc;
    s.side_agrees += isRear(pc) == isRear(tc);
    s.state_agrees += isParked(pc) == isParked(tc);
    if (!instance.z.empty()) {
      const Eigen::Vector3d truth_centre(median(instance.x), median(instance.y), median(instance.z));
      s.error_m.push_back((proposed_position[match->second] - truth_centre).norm());
    }
  }
  for (const auto& [p, pixels] : proposal_pixels) {
    FamilyScore& s = result.families[static_cast<std::size_t>(familyOfId(p))];
    ++s.proposals;
    const auto match = proposal_match.find(p);
    const bool on_ignored_light = match != proposal_match.end()
                                      ? ignored(match->second)
                                      : 2 * on_ignored[p] > pixels;
    s.ignored_proposals += on_ignored_light;
    if (match == proposal_match.end() && !on_ignored_light)
      result.misses.push_back({true, p, proposal_box[p], pixels, proposal_best[p]});
  }
  return result;
}

std::string proposalEvaluationTable(const ProposalEvaluation& evaluation) {
  std::string table =
      "| family | true (ignored) | proposed (ignored) | matched | recall | precision | 3D error median / p90, m | "
      "category agrees |\n|---|---|---|---|---|---|---|---|\n";
  for (int f = 0; f < kLightFamilyCount; ++f) {
    const FamilyScore& s = evaluation.families[static_cast<std::size_t>(f)];
    std::vector<double> errors = s.error_m;
    std::sort(errors.begin(), errors.end());
    const double med = errors.empty() ? 0 : errors[errors.size() / 2];
    const double p90 = errors.empty() ? 0 : errors[std::min(errors.size() - 1, errors.size() * 9 / 10)];
    char row[512];
    const double m = std::max<std::int64_t>(1, s.matched);
    std::string agrees = std::to_string(static_cast<int>(std::lround(100.0 * s.category_agrees / m))) + " %";
    if (f == static_cast<int>(LightFamily::VehicleLamp))
      agrees += " (front/rear " + std::to_string(static_cast<int>(std::lround(100.0 * s.side_agrees / m))) +
                " %, parked/moving " + std::to_string(static_cast<int>(std::lround(100.0 * s.state_agrees / m))) + " %)";
    std::snprintf(row, sizeof row, "| %s | %lld (%lld) | %lld (%lld) | %lld | %.2f | %.2f | %.2f / %.2f | %s |\n",
                  lightFamilyName(static_cast<LightFamily>(f)), static_cast<long long>(s.true_lights),
                  static_cast<long long>(s.ignored_true), static_cast<long long>(s.proposals),
                  static_cast<long long>(s.ignored_proposals), static_cast<long long>(s.matched), s.recall(),
                  s.precision(), med, p90, agrees.c_str());
    table += row;
  }
  return table;
}

std::string proposalMissesText(const ProposalEvaluation& evaluation) {
  std::string text;
  for (const ProposalMiss& m : evaluation.misses) {
    char line[256];
    std::snprintf(line, sizeof line, "%s %s %d box %d,%d,%d,%d pixels %lld best IoU %.2f\n", m.proposal ? "false" : "missed",
                  lightCategoryName(static_cast<LightCategory>(m.map_id / 1000)), m.map_id, m.box.x, m.box.y,
                  m.box.width, m.box.height, static_cast<long long>(m.pixels), m.best_iou);
    text += line;
  }
  return text;
}

}  // namespace solo
