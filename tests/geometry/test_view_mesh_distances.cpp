// measureViewMeshDistances: the split of a depth mesh's distance to the true surfaces by face
// origin and depth band, on hand-computed planes and on a small synthetic street, where it pins
// down why the refined depth's mesh is metres from the truth (docs/accuracy.md).

#include <solo/geometry/depth_metrics.h>
#include <solo/geometry/depth_refinement.h>
#include <solo/geometry/mesh_cleanup.h>
#include <solo/geometry/mesh_metrics.h>
#include <solo/geometry/prediction_noise.h>
#include <solo/core/scene.h>
#include <solo/geometry/view_mesh_distances.h>
#include <solo/synth/scene_raster.h>
#include <solo/synth/street_scene.h>

#include <gtest/gtest.h>

#include <cmath>

namespace {

using solo::FaceOrigin;
using solo::TriangleMesh;

/// An axis-aligned square facing the camera: centre (0, 0, z), side `side`, two triangles.
void addSquare(TriangleMesh& mesh, double z, double side) {
  const auto base = static_cast<std::uint32_t>(mesh.vertices.size());
  const double h = side / 2;
  mesh.vertices.emplace_back(-h, -h, z);
  mesh.vertices.emplace_back(h, -h, z);
  mesh.vertices.emplace_back(h, h, z);
  mesh.vertices.emplace_back(-h, h, z);
  mesh.faces.push_back({base, base + 1, base + 2});
  mesh.faces.push_back({base, base + 2, base + 3});
}

solo::PinholeCamera smallCamera() {
  solo::PinholeCamera c;
  c.fx = c.fy = 10;
  c.cx = c.cy = 1.5;
  c.width = c.height = 4;
  return c;
}

// Two squares that subtend the same angle, one at 10 m and one at 100 m, each 5 % of its depth in
// front of its true plane. Relative error is the same (0.05); the far one has 100x the area and
// 10x the distance, so it makes 1000/1001 of the area-weighted mean: what depth does to the mean.
TEST(ViewMeshDistances, FarSurfacesDominateTheAreaWeightedMeanNotTheRelativeOne) {
  TriangleMesh mesh, truth;
  addSquare(mesh, 10, 2);
  addSquare(mesh, 100, 20);
  // The true planes are larger, so every nearest point is straight behind the sample.
  addSquare(truth, 10.5, 4);
  addSquare(truth, 105, 40);
  const std::vector<FaceOrigin> origin = {FaceOrigin::DepthSurface, FaceOrigin::DepthSurface, FaceOrigin::Solid,
                                          FaceOrigin::Solid};
  solo::ViewMeshDistanceOptions options;
  options.samples = 100000;
  options.depth_band_edges_m = {50};
  const solo::ViewMeshDistances d =
      solo::measureViewMeshDistances(mesh, origin, truth, cv::Mat(), smallCamera(), options);

  EXPECT_NEAR(d.area_m2, 404.0, 1e-9);
  // Every sample is exactly 0.05 of its depth from the truth.
  EXPECT_NEAR(d.mean_relative_to_truth, 0.05, 1e-12);
  // Per part: exact distances (0.5 m near, 5 m far) and area shares.
  ASSERT_EQ(d.by_depth.size(), 2u);
  EXPECT_NEAR(d.by_depth[0].mean_m, 0.5, 1e-12);
  EXPECT_NEAR(d.by_depth[1].mean_m, 5.0, 1e-12);
  EXPECT_NEAR(d.by_depth[0].area_share, 4.0 / 404, 1e-12);
  EXPECT_NEAR(d.by_depth[1].area_share, 400.0 / 404, 1e-12);
  const auto& surface = d.by_origin[static_cast<int>(FaceOrigin::DepthSurface)];
  const auto& solid = d.by_origin[static_cast<int>(FaceOrigin::Solid)];
  EXPECT_NEAR(surface.mean_m, 0.5, 1e-12);
  EXPECT_NEAR(solid.mean_m, 5.0, 1e-12);
  EXPECT_EQ(d.by_origin[static_cast<int>(FaceOrigin::HoleFill)].samples, 0);
  // The mean: (4 x 0.5 + 400 x 5) / 404 = 4.955; the near square's share of it is 0.1 %. The
  // share of samples on the near square has a standard deviation sqrt(p (1 - p) / N) = 3.1e-4,
  // times the 4.5 m difference: 1.4e-3; the bound is 7 sigma.
  EXPECT_NEAR(d.mean_to_truth_m, 2002.0 / 404, 0.01);
  EXPECT_NEAR(d.by_depth[0].contribution_m + d.by_depth[1].contribution_m, d.mean_to_truth_m, 1e-9);
  EXPECT_NEAR(surface.contribution_m + solid.contribution_m, d.mean_to_truth_m, 1e-9);
  // The same as measureMeshDistances' one-sided mean (same samples drawn differently: within noise).
  solo::MeshDistanceOptions plain;
  plain.samples = 100000;
  EXPECT_NEAR(solo::measureMeshDistances(mesh, truth, plain).mean_to_reference, d.mean_to_truth_m, 0.02);
}

// The true pixels: a 4x4 depth map of the 10.5 m plane behind a mesh at 10 m covering every ray.
// d(p, mesh) = 0.5 m, relative 0.5 / 10.5 = 0.0476: covered at 5 %, not at 4 %.
TEST(ViewMeshDistances, TruePixelsCoveredWithinTheirRelativeTolerance) {
  TriangleMesh mesh, truth;
  addSquare(mesh, 10, 200);
  addSquare(truth, 10.5, 400);
  const cv::Mat depth(4, 4, CV_32F, cv::Scalar(10.5));
  cv::Mat with_sky = depth.clone();
  with_sky.at<float>(0, 0) = 0;  // sky: not a true surface
  solo::ViewMeshDistanceOptions options;
  options.samples = 1000;
  options.depth_band_edges_m = {10, 20};
  solo::ViewMeshDistances d = solo::measureViewMeshDistances(mesh, {}, truth, with_sky, smallCamera(), options);
  EXPECT_EQ(d.truth_pixels, 15);
  EXPECT_NEAR(d.truth_mean_relative_to_mesh, 0.5 / 10.5, 1e-12);
  EXPECT_DOUBLE_EQ(d.truth_covered, 1.0);
  ASSERT_EQ(d.truth_pixels_by_depth.size(), 3u);
  EXPECT_EQ(d.truth_pixels_by_depth[1], 15);  // 10.5 m: band 10-20 m
  EXPECT_DOUBLE_EQ(d.truth_covered_by_depth[1], 1.0);
  EXPECT_DOUBLE_EQ(d.truth_covered_by_depth[0], 0.0);  // no pixel there
  options.covered_relative = 0.04;
  d = solo::measureViewMeshDistances(mesh, {}, truth, depth, smallCamera(), options);
  EXPECT_EQ(d.truth_pixels, 16);
  EXPECT_DOUBLE_EQ(d.truth_covered, 0.0);
  // Subsampled true pixels: at most `samples` of them.
  options.samples = 5;
  EXPECT_EQ(solo::measureViewMeshDistances(mesh, {}, truth, depth, smallCamera(), options).truth_pixels, 5);
}

TEST(ViewMeshDistances, RefusesBadInput) {
  TriangleMesh mesh, truth;
  addSquare(mesh, 10, 2);
  addSquare(truth, 10.5, 4);
  const solo::PinholeCamera camera = smallCamera();
  EXPECT_THROW(solo::measureViewMeshDistances(mesh, {FaceOrigin::Solid}, truth, cv::Mat(), camera),
               std::invalid_argument);
  solo::ViewMeshDistanceOptions options;
  options.depth_band_edges_m = {20, 10};
  EXPECT_THROW(solo::measureViewMeshDistances(mesh, {}, truth, cv::Mat(), camera, options), std::invalid_argument);
  options = {};
  options.samples = 0;
  EXPECT_THROW(solo::measureViewMeshDistances(mesh, {}, truth, cv::Mat(), camera, options), std::invalid_argument);
  EXPECT_THROW(solo::measureViewMeshDistances(TriangleMesh{}, {}, truth, cv::Mat(), camera), std::invalid_argument);
}

// ---- a small synthetic street ----------------------------------------------------------------

struct Street {
  solo::StreetScene scene;
  solo::GroundTruthMaps truth;
  TriangleMesh truth_mesh;
};

const Street& street() {
  static const Street s = [] {
    solo::StreetSceneOptions o;
    o.seed = 3;
    o.width = 320;
    o.height = 180;
    Street out{solo::buildStreetScene(o), {}, {}};
    out.truth = solo::rasterizeGroundTruth(out.scene);
    out.truth_mesh = solo::streetSceneMesh(out.scene);
    return out;
  }();
  return s;
}

struct MeasuredMesh {
  solo::ViewMeshDistances view;
  solo::ViewMeshDistances surface;  ///< the depth-surface faces alone
  std::vector<double> band_abs_rel;  ///< depth AbsRel of the meshed depth per band (of the true depth)
};

MeasuredMesh measure(const cv::Mat& depth_m, const cv::Mat& instances, const cv::Mat& uncertain,
                     bool backdrops = true) {
  const Street& s = street();
  solo::StageReport report;
  solo::DepthMeshCleanupOptions cleanup;
  cleanup.evaluate = false;
  cleanup.backdrops = backdrops;
  const solo::DepthMesh mesh = solo::meshFromScene(depth_m, s.scene.camera, instances, uncertain, cleanup, report);
  solo::ViewMeshDistanceOptions options;
  options.samples = 50000;
  MeasuredMesh out;
  const TriangleMesh soup = solo::toTriangleMesh(mesh.mesh);
  const std::vector<FaceOrigin> origin = solo::faceOrigins(mesh.mesh);
  out.view = solo::measureViewMeshDistances(soup, origin, s.truth_mesh, s.truth.depth_m, s.scene.camera, options);
  TriangleMesh surface = soup;
  surface.faces.clear();
  for (std::size_t f = 0; f < soup.faces.size(); ++f)
    if (origin[f] == FaceOrigin::DepthSurface) surface.faces.push_back(soup.faces[f]);
  out.surface = solo::measureViewMeshDistances(surface, {}, s.truth_mesh, cv::Mat(), s.scene.camera, options);
  const std::vector<double>& edges = options.depth_band_edges_m;
  for (std::size_t b = 0; b <= edges.size(); ++b) {
    solo::DepthEvaluationInput input;
    input.prediction_m = depth_m;
    input.ground_truth_m = s.truth.depth_m;
    solo::DepthMetricsOptions range;
    if (b > 0) range.min_depth_m = edges[b - 1];
    if (b < edges.size()) range.max_depth_m = edges[b];
    out.band_abs_rel.push_back(solo::evaluateDepth(input, range).abs_rel);
  }
  return out;
}

// The exact depth's mesh lies on the true surfaces: the metric, its units and the true mesh agree
// with the depth maps. Measured (320x180, seed 3): depth-surface faces 0.16 % of their depth
// from the truth on average (the faces left across occlusions; the rest is exact), 99.8 % of the
// true pixels within 5 % of their depth from the mesh, 0.023 % of the depth on average; the bounds
// leave 5-9x margin. Solids and patches are guesses behind the surface and are not bounded here;
// without backdrops, since a backdrop's faces between three of its runs' vertices (grid
// neighbours on the depth surface's boundary) count as depth surface by their vertices' origin.
TEST(ViewMeshDistances, ExactDepthMeshLiesOnTheTrueSurfaces) {
  const Street& s = street();
  const MeasuredMesh m = measure(s.truth.depth_m, s.truth.instances, cv::Mat(), false);
  const auto& surface = m.view.by_origin[static_cast<int>(FaceOrigin::DepthSurface)];
  EXPECT_GT(surface.area_share, 0.7);
  EXPECT_LT(surface.mean_relative, 0.01);
  EXPECT_GT(m.view.truth_covered, 0.99);
  EXPECT_LT(m.view.truth_mean_relative_to_mesh, 0.002);
}

// The finding behind docs/accuracy.md's 5 m: the mesh of the refined estimate is as far from the
// truth as its depth error allows in every depth band, and the far bands make the mean. A
// depth-surface point whose pixel's depth is off by e z is at most e z |ray| / z = e |ray|
// (|ray| <= 1.2 in this field of view) of its depth from the truth, so each band's mean relative
// distance of depth-surface faces stays under 1.2 x the band's AbsRel, plus 0.01 for faces left
// across occlusions (measured: 0.2 to 0.8 x AbsRel; the nearest surface is often nearer than the
// one along the ray); solids and hole patches are not the cause (together under a fifth of the
// mean); beyond 80 m, under 15 % of the pixels, is most of the mean; and the true surfaces are
// covered. The estimate is simulatePredictions' (seed 3: per-pixel noise 1 % x (1 + z / 50 m),
// depth at half resolution), refined with refineDepth's defaults, meshed as `solo mesh` does.
TEST(ViewMeshDistances, RefinedDepthMeshErrorIsTheDepthErrorWeightedByArea) {
  const Street& s = street();
  solo::PredictionNoiseOptions noise;
  const solo::SimulatedPredictions est = solo::simulatePredictions(s.truth.depth_m, s.truth.normals, s.truth.albedo,
                                                                   s.truth.labels, s.truth.instances, noise, 3);
  solo::Scene scene;
  scene.image = cv::Mat(s.truth.depth_m.size(), CV_32FC3, cv::Scalar::all(0.5));
  scene.depth_m = est.depth_m;
  scene.normals = est.normals;
  scene.instances = est.instances;
  scene.labels = est.labels;
  scene.camera = s.scene.camera;
  const solo::DepthRefinementResult refined = solo::refineDepth(scene);
  const MeasuredMesh m = measure(refined.depth_m, refined.maps.instances, refined.uncertain);
  const solo::ViewMeshDistances& v = m.view;

  const std::vector<double>& edges = solo::ViewMeshDistanceOptions{}.depth_band_edges_m;
  double far_contribution_m = 0;
  std::int64_t far_pixels = 0, pixels = 0;
  for (std::size_t b = 0; b < v.by_depth.size(); ++b) {
    SCOPED_TRACE("depth band " + std::to_string(b));
    pixels += v.truth_pixels_by_depth[b];
    if (b > 0 && edges[b - 1] >= 80) {
      far_contribution_m += v.by_depth[b].contribution_m;
      far_pixels += v.truth_pixels_by_depth[b];
    }
    if (m.surface.by_depth[b].samples > 0) {
      EXPECT_LT(m.surface.by_depth[b].mean_relative, 1.2 * m.band_abs_rel[b] + 0.01);
    }
  }
  // Measured (320x180, seed 3): 7 % of the true pixels lie beyond 80 m and make 98 % of the
  // 6.2 m mean (the far end: 6.1 m).
  EXPECT_LT(static_cast<double>(far_pixels), 0.15 * static_cast<double>(pixels));
  EXPECT_GT(far_contribution_m, 0.5 * v.mean_to_truth_m);
  // Measured: the mean is 6.2 m (11.8 m without depth completion: a few pixels at the street's
  // far end without depth left its frame hole open there); solids 0.04 m; the far end's hole
  // patch 3.2 m, the depth surface 2.9 m.
  EXPECT_LT(v.mean_to_truth_m, 8.0);
  EXPECT_LT(v.by_origin[static_cast<int>(FaceOrigin::Solid)].contribution_m, 0.05 * v.mean_to_truth_m);
  EXPECT_LT(v.by_origin[static_cast<int>(FaceOrigin::HoleFill)].contribution_m, 0.6 * v.mean_to_truth_m);
  // The refined mesh keeps the true surfaces (measured 0.94 of the pixels within 5 % of their depth;
  // the half-resolution estimate's own mesh keeps 0.93 at 960x540 but only 0.3 % of those beyond 160 m).
  EXPECT_GT(v.truth_covered, 0.9);
}

}  // namespace
