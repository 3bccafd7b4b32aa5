// solo synth: the ground truth is self-consistent, the hard variants hold what they promise,
// and generation is deterministic.

#include <solo/core/image_io.h>
#include <solo/geometry/prediction_noise.h>
#include <solo/core/scene.h>
#include <solo/geometry/triangle_mesh.h>
#include <solo/lighting/light_category.h>
#include <solo/synth/scene_raster.h>
#include <solo/synth/street_scene.h>

#include "test_support.h"

#include <Eigen/Geometry>

#include <map>
#include <set>

using solo::test::TempDir;

namespace {

struct Synth {
  solo::StreetScene scene;
  solo::GroundTruthMaps truth;
};

Synth make(solo::StreetVariant variant, std::uint64_t seed = 1, int width = 480, int height = 270) {
  solo::StreetSceneOptions o;
  o.seed = seed;
  o.variant = variant;
  o.width = width;
  o.height = height;
  Synth s{solo::buildStreetScene(o), {}};
  s.truth = solo::rasterizeGroundTruth(s.scene);
  return s;
}

Eigen::Vector3d pointAt(const Synth& s, int x, int y) {
  return s.scene.camera.backproject(x, y, s.truth.depth_m.at<float>(y, x));
}

}  // namespace

TEST(Synth, NormalsFromTrueDepthMatchTrueNormalsAwayFromEdges) {
  const Synth s = make(solo::StreetVariant::Default);
  int tested = 0, within = 0;
  double worst = 0;
  for (int y = 1; y + 1 < s.truth.depth_m.rows; ++y)
    for (int x = 1; x + 1 < s.truth.depth_m.cols; ++x) {
      // Away from edges: the 3x3 neighbourhood is one face of one box.
      const int part = s.truth.part.at<int>(y, x);
      const cv::Vec3f n0 = s.truth.normals.at<cv::Vec3f>(y, x);
      bool flat = part >= 0;
      for (int dy = -1; dy <= 1 && flat; ++dy)
        for (int dx = -1; dx <= 1 && flat; ++dx)
          flat = s.truth.part.at<int>(y + dy, x + dx) == part && s.truth.normals.at<cv::Vec3f>(y + dy, x + dx) == n0;
      if (!flat) continue;
      const Eigen::Vector3d p = pointAt(s, x, y);
      Eigen::Vector3d n = (pointAt(s, x + 1, y) - pointAt(s, x - 1, y)).cross(pointAt(s, x, y + 1) - pointAt(s, x, y - 1));
      n.normalize();
      if (n.dot(p) > 0) n = -n;
      const Eigen::Vector3d truth(n0[0], n0[1], n0[2]);
      const double angle_deg = std::atan2(n.cross(truth).norm(), n.dot(truth)) * 180 / M_PI;
      worst = std::max(worst, angle_deg);
      ++tested;
      within += angle_deg < 1.0;
    }
  EXPECT_GT(tested, 480 * 270 / 2) << "most of the image is flat faces";
  EXPECT_EQ(within, tested) << "worst angle " << worst << " deg";
}

TEST(Synth, BackprojectedDepthLiesOnTheGroundTruthSurface) {
  const Synth s = make(solo::StreetVariant::Default);
  double worst_relative = 0;
  int checked = 0;
  for (int y = 0; y < s.truth.depth_m.rows; ++y)
    for (int x = 0; x < s.truth.depth_m.cols; ++x) {
      const int part = s.truth.part.at<int>(y, x);
      if (part < 0) {
        EXPECT_EQ(s.truth.depth_m.at<float>(y, x), 0.f);
        EXPECT_EQ(s.truth.labels.at<int>(y, x), 23) << "no hit = sky";
        continue;
      }
      const Eigen::Vector3d p = pointAt(s, x, y);
      const solo::AxisBox& box = s.scene.parts[static_cast<std::size_t>(part)].box;
      // Distance from p to the box surface: inside-or-on the box and at a face plane.
      double outside = 0, nearest_face = 1e30;
      for (int k = 0; k < 3; ++k) {
        outside = std::max({outside, box.min[k] - p[k], p[k] - box.max[k]});
        nearest_face = std::min({nearest_face, std::abs(p[k] - box.min[k]), std::abs(p[k] - box.max[k])});
      }
      const double distance = std::max(outside, nearest_face);
      worst_relative = std::max(worst_relative, distance / p.z());
      ++checked;
    }
  EXPECT_GT(checked, 0);
  EXPECT_LT(worst_relative, 1e-4);
}

TEST(Synth, GroundTruthMeshIsClosed) {
  const Synth s = make(solo::StreetVariant::Default, 3, 64, 36);
  const solo::TriangleMesh mesh = solo::streetSceneMesh(s.scene);
  ASSERT_EQ(mesh.faces.size(), s.scene.parts.size() * 12);
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> directed;
  for (const auto& f : mesh.faces)
    for (int k = 0; k < 3; ++k) ++directed[{f[k], f[(k + 1) % 3]}];
  for (const auto& [edge, count] : directed) {
    EXPECT_EQ(count, 1) << "an edge used twice in the same direction: inconsistent orientation";
    EXPECT_EQ(directed.count({edge.second, edge.first}), 1u) << "a boundary edge";
  }
  // Outward orientation: the signed volume of each box is positive and equals its volume.
  for (std::size_t b = 0; b < s.scene.parts.size(); b += 97) {
    double volume = 0;
    for (std::size_t t = 12 * b; t < 12 * b + 12; ++t) {
      const auto& f = mesh.faces[t];
      volume += mesh.vertices[f[0]].dot(mesh.vertices[f[1]].cross(mesh.vertices[f[2]])) / 6;
    }
    const Eigen::Vector3d size = s.scene.parts[b].box.max - s.scene.parts[b].box.min;
    EXPECT_NEAR(volume, size.prod(), 1e-9 * std::max(1.0, size.prod()));
  }
}

TEST(Synth, EveryLightLiesOnTheObjectItsGroupSays) {
  const Synth s = make(solo::StreetVariant::Default, 5, 960, 540);
  std::map<int, std::set<int>> instances_of_light;
  int light_pixels = 0;
  for (int y = 0; y < s.truth.lights.rows; ++y)
    for (int x = 0; x < s.truth.lights.cols; ++x) {
      const int light = s.truth.lights.at<int>(y, x);
      if (light == 0) continue;
      ++light_pixels;
      const auto category = static_cast<solo::LightCategory>(solo::lightCategoryOfId(light));
      const int label = s.truth.labels.at<int>(y, x);
      instances_of_light[light].insert(s.truth.instances.at<int>(y, x));
      switch (category) {
        case solo::LightCategory::WindowBuilding:
          EXPECT_EQ(label, 11);
          EXPECT_GT(s.truth.light_groups.at<int>(y, x), 0) << "building windows belong to a floor group";
          break;
        case solo::LightCategory::StreetLightHighCct:
        case solo::LightCategory::StreetLightLowCct: EXPECT_EQ(label, 17); break;
        case solo::LightCategory::TrafficLightRed:
        case solo::LightCategory::TrafficLightOrange:
        case solo::LightCategory::TrafficLightGreen: EXPECT_EQ(label, 19); break;
        default: {
          const std::set<int> vehicles = {26, 27, 28, 31, 33};
          EXPECT_TRUE(vehicles.count(label)) << "vehicle light on label " << label;
          EXPECT_GE(s.truth.instances.at<int>(y, x), 1000) << "vehicle lights sit on a vehicle instance";
          EXPECT_EQ(s.truth.light_groups.at<int>(y, x), 0);
        }
      }
    }
  EXPECT_GT(light_pixels, 1000);
  for (const auto& [light, instances] : instances_of_light)
    EXPECT_EQ(instances.size(), 1u) << "light " << light << " spans several objects";
  // At least one traffic light is lit, and both front and rear lights are in view.
  std::set<int> categories;
  for (const auto& entry : instances_of_light) categories.insert(solo::lightCategoryOfId(entry.first));
  EXPECT_TRUE(categories.count(4) + categories.count(5) + categories.count(6) == 1);
  EXPECT_TRUE(categories.count(10) || categories.count(9));
  EXPECT_TRUE(categories.count(12) || categories.count(11));
}

TEST(SynthVariants, HardCasesHoldWhatTheyPromise) {
  const Synth pole = make(solo::StreetVariant::ThinPole, 1, 960, 540);
  // A 5 cm pole at 3 m spans 0.05 * 890 / 3 = 14.8 px at 960x540.
  int widest = 0;
  for (int y = 0; y < 540; ++y) {
    int run = 0;
    for (int x = 0; x < 960; ++x) {
      const float d = pole.truth.depth_m.at<float>(y, x);
      run = (d >= 2.999f && d <= 3.0001f && pole.truth.labels.at<int>(y, x) == 17) ? run + 1 : 0;
      widest = std::max(widest, run);
    }
  }
  EXPECT_NEAR(widest, 14.8, 1.0);

  double lo, hi;
  const Synth near = make(solo::StreetVariant::NearObject);
  cv::minMaxLoc(near.truth.depth_m, nullptr, &hi);
  cv::Mat valid = near.truth.depth_m > 0;
  cv::minMaxLoc(near.truth.depth_m, &lo, nullptr, nullptr, nullptr, valid);
  EXPECT_NEAR(lo, 0.6, 1e-4);

  const Synth grazing = make(solo::StreetVariant::Grazing, 1, 960, 540);
  cv::minMaxLoc(grazing.truth.depth_m, nullptr, &hi);
  EXPECT_GT(hi, 450.0) << "ground plane to 500 m";
  EXPECT_LE(hi, 800.0);

  const Synth dark = make(solo::StreetVariant::NoLights);
  EXPECT_EQ(cv::countNonZero(dark.truth.lights), 0);
  EXPECT_EQ(cv::countNonZero(dark.truth.light_groups), 0);

  const Synth sky = make(solo::StreetVariant::WideSky);
  const Synth normal = make(solo::StreetVariant::Default);
  EXPECT_GT(cv::countNonZero(sky.truth.depth_m <= 0), 3 * cv::countNonZero(normal.truth.depth_m <= 0));
  EXPECT_THROW(solo::streetVariantFromName("foggy"), std::invalid_argument);
}

TEST(SynthPredictions, PerturbationsHaveTheDocumentedSize) {
  const Synth s = make(solo::StreetVariant::Default, 2, 480, 270);
  solo::PredictionNoiseOptions o;
  const auto p = solo::simulatePredictions(s.truth.depth_m, s.truth.normals, s.truth.albedo, s.truth.labels,
                                           s.truth.instances, o, 11);
  EXPECT_EQ(p.depth_m.size(), cv::Size(240, 135));
  EXPECT_EQ(p.normals.size(), cv::Size(240, 135));
  EXPECT_EQ(p.albedo.size(), cv::Size(120, 67));
  EXPECT_LE(std::abs(p.depth_scale_bias - 1), o.depth_bias_max);
  // The median ratio to the truth (sampled at the same place) is the drawn bias.
  std::vector<double> ratios;
  for (int y = 0; y < 135; ++y)
    for (int x = 0; x < 240; ++x) {
      const float g = s.truth.depth_m.at<float>(2 * y, 2 * x), e = p.depth_m.at<float>(y, x);
      if (g > 0 && e > 0) ratios.push_back(e / g);
    }
  std::nth_element(ratios.begin(), ratios.begin() + ratios.size() / 2, ratios.end());
  EXPECT_NEAR(ratios[ratios.size() / 2], p.depth_scale_bias, 0.01);
  // Labels move only near boundaries: a few percent of pixels change, never most.
  const double changed = cv::countNonZero(p.labels != s.truth.labels) / double(480 * 270);
  EXPECT_GT(changed, 0.002);
  EXPECT_LT(changed, 0.1);
  // Deterministic per seed, different across seeds.
  const auto again = solo::simulatePredictions(s.truth.depth_m, s.truth.normals, s.truth.albedo, s.truth.labels,
                                               s.truth.instances, o, 11);
  EXPECT_EQ(cv::norm(p.depth_m, again.depth_m, cv::NORM_INF), 0.0);
  const auto other = solo::simulatePredictions(s.truth.depth_m, s.truth.normals, s.truth.albedo, s.truth.labels,
                                               s.truth.instances, o, 12);
  EXPECT_GT(cv::norm(p.depth_m, other.depth_m, cv::NORM_INF), 0.0);
}

TEST(SynthCli, SameSeedSameFilesDifferentSeedDifferentScene) {
  TempDir dir;
  for (const char* run : {"a", "b"}) {
    const auto r = solo::test::runSolo("synth --size 160x90 --seed 4 -o \"" + (dir / run).string() + "\"");
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }
  ASSERT_EQ(solo::test::runSolo("synth --size 160x90 --seed 5 -o \"" + (dir / "c").string() + "\"").exit_code, 0);
  for (const char* file : {"day.png", "gt/depth.exr", "gt/mesh.ply", "est/depth.exr", "est/normals.png",
                           "est/instanceIds.png", "lightIds.png", "scene.json", "synth.json"}) {
    SCOPED_TRACE(file);
    EXPECT_TRUE(solo::test::readText(dir / "a" / file) == solo::test::readText(dir / "b" / file)) << "files differ";
  }
  EXPECT_FALSE(solo::test::readText(dir / "a/gt/mesh.ply") == solo::test::readText(dir / "c/gt/mesh.ply"));
  EXPECT_FALSE(solo::test::readText(dir / "a/day.png") == solo::test::readText(dir / "c/day.png"));

  // Both manifests load through the scene contract, and the truth is exact.
  const solo::Scene est = solo::loadScene(dir / "a/scene.json");
  const solo::Scene gt = solo::loadScene(dir / "a/gt/scene.json");
  EXPECT_EQ(est.depth_m.size(), cv::Size(80, 45));
  EXPECT_EQ(gt.depth_m.size(), cv::Size(160, 90));
  EXPECT_EQ(gt.normal_stats->back_facing, 0);
  EXPECT_FALSE(est.camera_is_default);
  const solo::TriangleMesh mesh = solo::readMesh(dir / "a/gt/mesh.ply");
  EXPECT_EQ(mesh.faces.size() % 12, 0u);

  const auto again = solo::test::runSolo("synth --size 160x90 -o \"" + (dir / "a").string() + "\"");
  EXPECT_EQ(again.exit_code, 2);
  EXPECT_NE(again.output.find("already exists"), std::string::npos);
  const auto bad = solo::test::runSolo("synth --variant foggy -o \"" + (dir / "d").string() + "\"");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.output.find("unknown scene variant"), std::string::npos);
  EXPECT_FALSE(std::filesystem::exists(dir / "d"));
}

TEST(SynthCli, PathTracedDayImageIsDeterministicAndItsOptionChecked) {
  TempDir dir;
  for (const char* run : {"a", "b"}) {
    const auto r = solo::test::runSolo("synth --size 64x36 --day-render path -o \"" + (dir / run).string() + "\"");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("day_render path"), std::string::npos) << r.output;
  }
  EXPECT_TRUE(solo::test::readText(dir / "a/day.png") == solo::test::readText(dir / "b/day.png"));
  ASSERT_EQ(solo::test::runSolo("synth --size 64x36 -o \"" + (dir / "r").string() + "\"").exit_code, 0);
  EXPECT_FALSE(solo::test::readText(dir / "a/day.png") == solo::test::readText(dir / "r/day.png"));
  EXPECT_TRUE(solo::test::readText(dir / "a/gt/depth.exr") == solo::test::readText(dir / "r/gt/depth.exr"));
  const auto bad = solo::test::runSolo("synth --day-render cycles -o \"" + (dir / "d").string() + "\"");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.output.find("--day-render"), std::string::npos) << bad.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "d"));
}

// --day-samples fixes the path-traced day image's samples per pixel. Against a 256-sample image,
// nested sample sets differ by sigma sqrt(1/n - 1/256): 4 samples 0.50 sigma, 64 samples 0.11
// sigma, a ratio of 0.22 (8-bit rounding adds a floor). The adaptive default (4 to 16) lies
// between. The count is recorded and a count out of range refused.
TEST(SynthCli, DaySamplesSetTheDayImagesNoise) {
  TempDir dir;
  const auto run = [&](const std::string& name, const std::string& samples) {
    const auto r = solo::test::runSolo("synth --size 64x36 --day-render path " + samples + " -o \"" +
                                       (dir / name).string() + "\"");
    EXPECT_EQ(r.exit_code, 0) << r.output;
    return solo::readColorImage(dir / name / "day.png");
  };
  const cv::Mat few = run("few", "--day-samples 4"), adaptive = run("adaptive", ""),
                mid = run("mid", "--day-samples 64"), reference = run("reference", "--day-samples 256");
  ASSERT_FALSE(reference.empty());
  const double few_rms = cv::norm(few, reference, cv::NORM_L2), adaptive_rms = cv::norm(adaptive, reference, cv::NORM_L2),
               mid_rms = cv::norm(mid, reference, cv::NORM_L2);
  EXPECT_LT(mid_rms, 0.35 * few_rms) << "64 spp: " << mid_rms << ", 4 spp: " << few_rms;
  EXPECT_LT(mid_rms, adaptive_rms);
  EXPECT_LT(adaptive_rms, few_rms);
  const std::string record = solo::test::readText(dir / "mid/synth.json");
  EXPECT_NE(record.find("\"day_samples\": 64"), std::string::npos) << record;
  const auto bad = solo::test::runSolo("synth --day-render path --day-samples 5000 -o \"" + (dir / "d").string() + "\"");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.output.find("--day-samples"), std::string::npos) << bad.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "d"));
}
