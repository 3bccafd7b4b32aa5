#pragma once
// Light proposals for a scene without a light map: street lights, traffic lights, vehicle lamps
// and building windows found from the Cityscapes labels and instances, the day image and the
// depth, written as a `lights` map (categoryId * 1000 + k), a `light_groups` map (one group per
// facade floor) and a record of the evidence for each proposal. docs/lighting.md, "Proposals".

#include "solo/core/camera.h"
#include "solo/core/report.h"
#include "solo/core/scene.h"
#include "solo/lighting/light_category.h"
#include "solo/lighting/light_priors.h"

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace solo {

struct LightProposalOptions {
  bool street_lights = true;
  bool traffic_lights = true;
  bool vehicles = true;
  bool windows = true;
  /// A pole's top must lie this high above the ground plane for a street-light head, metres.
  double min_pole_top_m = 4.0;
  double max_pole_top_m = 12.0;
  /// Lamp heads mounted below this height are residential lanterns, warm white
  /// (street_light_LT); at or above it, road luminaires, cool white (street_light_HT). Metres.
  double warm_lantern_below_m = 6.5;
  /// A vehicle whose kerb-side flank lies within this lateral distance of the kerb is parked.
  double parked_kerb_gap_m = 1.2;
  /// Facade cells of the rectified window search, metres.
  double facade_cell_m = 0.1;
};

/// One proposed light and why.
struct LightProposal {
  int map_id = 0;  ///< categoryId * 1000 + k in the written map
  LightCategory category = LightCategory::Inferred;
  cv::Rect box;                   ///< pixel bounding box of its pixels
  std::int64_t pixels = 0;        ///< pixels written to the map
  Eigen::Vector3d position_m{0, 0, 0};  ///< camera frame, metres
  double height_m = 0;            ///< above the ground plane
  double score = 0;               ///< 0..1, how strongly the evidence supports it
  std::string rule;               ///< the rule that fired
  std::string evidence;           ///< the measurements behind it
  int group = 0;                  ///< light_groups id (windows: facade floor), 0 = none
  int source_instance = 0;        ///< the instance id (vehicles) or label component it came from
};

struct LightProposalResult {
  cv::Mat lights;        ///< CV_32S categoryId * 1000 + k at the image resolution, 0 = none
  cv::Mat light_groups;  ///< CV_32S facade-floor group ids, 0 = none
  std::vector<LightProposal> proposals;  ///< in map order
  GroundPlaneFit ground;  ///< inliers = 0: the level-camera prior
  std::vector<std::pair<std::string, double>> seconds;  ///< step -> wall time
  double total_seconds = 0;
  StageReport report;  ///< name "light_proposals": counts per category, timings, notes
};

/// Proposes lights from `scene`'s labels (required), instances, day image and depth (resampled
/// to the image resolution) and camera. The scene's own light map is not read. Throws
/// InputError naming the manifest when the scene has no label map.
LightProposalResult proposeLights(const Scene& scene, const LightProposalOptions& options = {});

/// `scene` with its lights and light_groups replaced by the proposals' (pixels shared).
Scene withProposedLights(const Scene& scene, const LightProposalResult& proposals);

/// The record: {"format": "solo-light-proposals/1", "image", "camera", "ground_plane",
/// "seconds", "counts", "proposals": [{"map_id", "category", "box", "pixels", "position_m",
/// "height_m", "score", "rule", "evidence", "group", "source_instance"}]}.
std::string lightProposalsJson(const LightProposalResult& result, const std::string& scene_name);

/// The day image (CV_32FC3 sRGB) darkened, each proposal's pixels in its category's colour,
/// its box outlined and labelled with the category's short name. CV_8UC3, RGB.
cv::Mat drawLightProposals(const cv::Mat& day_image, const LightProposalResult& result);

/// Category families the accuracy is measured over.
enum class LightFamily : int { StreetLight = 0, TrafficLight = 1, VehicleLamp = 2, Window = 3 };
constexpr int kLightFamilyCount = 4;
const char* lightFamilyName(LightFamily family);
/// The family of a category, or -1 for categories no proposal makes (vehicle windows, signs).
int lightFamilyOf(LightCategory category);

struct ProposalEvaluationOptions {
  double min_iou = 0.3;
  /// True lights with fewer pixels are ignored: missing them costs no recall, and a proposal
  /// that overlaps one mostly counts as neither right nor wrong.
  int min_true_pixels = 30;
};

/// Matches of one family: instance precision/recall at IoU >= min_iou (greedy by IoU), the 3D
/// error of the matched ones, and how often the finer category agreed.
struct FamilyScore {
  std::int64_t true_lights = 0, proposals = 0, matched = 0, ignored_true = 0, ignored_proposals = 0;
  std::int64_t category_agrees = 0;  ///< matched pairs with the same category
  std::int64_t side_agrees = 0;      ///< vehicle lamps: front/rear agrees
  std::int64_t state_agrees = 0;     ///< vehicle lamps: parked/moving agrees
  std::vector<double> error_m;       ///< 3D centroid error of each match, metres
  double precision() const;
  double recall() const;
  void add(const FamilyScore& other);
};

/// A true light left unmatched or a proposal matching nothing, for looking at the misses.
struct ProposalMiss {
  bool proposal = false;  ///< false: a true light missed; true: a proposal matching no true light
  int map_id = 0;
  cv::Rect box;
  std::int64_t pixels = 0;
  double best_iou = 0;  ///< with any light of the other map in its family
};

struct ProposalEvaluation {
  std::array<FamilyScore, kLightFamilyCount> families;
  std::vector<ProposalMiss> misses;  ///< ignored lights left out
};

/// `proposed`/`truth`: CV_32S light maps at one size; `true_depth_m`: the exact z-depth (the
/// true 3D position of a light is the median backprojection of its pixels); `proposals` give
/// the proposed positions by map id.
ProposalEvaluation evaluateLightProposals(const LightProposalResult& proposed, const cv::Mat& truth,
                                          const cv::Mat& true_depth_m, const PinholeCamera& camera,
                                          const ProposalEvaluationOptions& options = {});

/// A Markdown table of the evaluation: one row per family.
std::string proposalEvaluationTable(const ProposalEvaluation& evaluation);
/// One line per miss: "missed|false <category> <id> box x,y,w,h pixels N best IoU I".
std::string proposalMissesText(const ProposalEvaluation& evaluation);

}  // namespace solo
