// Mesh from depth: backprojection, spurious faces (hand-built depth maps with known answers and
// the embedded synthetic scene's ground truth), and the whole depth cleanup with its hard cases.

#include <solo/geometry/boundary_loops.h>
#include <solo/geometry/depth_mesh.h>
#include <solo/geometry/mesh_cleanup.h>
#include <solo/geometry/mesh_metrics.h>
#include <solo/geometry/scene.h>
#include <solo/geometry/spurious_faces.h>

#include "test_support.h"

#include <cmath>

namespace {

const solo::PinholeCamera kCamera{100.0, 100.0, 15.5, 11.5, 32, 24};

std::int64_t metricInt(const solo::StageReport& report, const std::string& name) {
  const solo::MetricValue* v = report.find(name);
  if (!v) ADD_FAILURE() << "no metric " << name;
  return v ? std::get<std::int64_t>(*v) : -1;
}

double metricDouble(const solo::StageReport& report, const std::string& name) {
  const solo::MetricValue* v = report.find(name);
  if (!v) ADD_FAILURE() << "no metric " << name;
  return v ? std::get<double>(*v) : -1;
}

bool hasEdge(const solo::DepthMesh& m, int u0, int v0, int u1, int v1) {
  const auto a = OpenMesh::VertexHandle(m.vertexAt(u0, v0)), b = OpenMesh::VertexHandle(m.vertexAt(u1, v1));
  return m.mesh.find_halfedge(a, b).is_valid();
}

TEST(DepthMesh, BackprojectsEveryValidPixelAndFacesTheCamera) {
  cv::Mat depth(3, 3, CV_32F, cv::Scalar(4.0f));
  depth.at<float>(0, 2) = 0.0f;  // invalid corner: its quad keeps one triangle
  const solo::PinholeCamera camera{2.0, 2.0, 1.0, 1.0, 3, 3};
  const solo::DepthMesh m = solo::meshFromDepth(depth, camera);
  EXPECT_EQ(m.mesh.n_vertices(), 8u);
  EXPECT_EQ(m.mesh.n_faces(), 2u + 2u + 2u + 1u);
  EXPECT_EQ(m.vertexAt(2, 0), -1);
  const auto v = OpenMesh::VertexHandle(m.vertexAt(2, 2));
  const auto p = m.mesh.point(v);
  EXPECT_DOUBLE_EQ(p[0], 4.0 * (2 - 1.0) / 2.0);
  EXPECT_DOUBLE_EQ(p[1], 4.0 * (2 - 1.0) / 2.0);
  EXPECT_DOUBLE_EQ(p[2], 4.0);
  EXPECT_EQ(m.mesh.property(m.properties.pixel, v), OpenMesh::Vec2i(2, 2));
  for (const auto f : m.mesh.faces()) {
    std::vector<solo::SurfaceMesh::Point> q;
    for (const auto w : m.mesh.fv_range(f)) q.push_back(m.mesh.point(w));
    const auto normal = (q[1] - q[0]) % (q[2] - q[0]);
    EXPECT_LT(normal | (q[0] + q[1] + q[2]), 0.0) << "face " << f.idx() << " faces away from the camera";
  }
}

TEST(DepthMesh, SkyMakesNoVertexAndLabelsAreKept) {
  cv::Mat depth(2, 3, CV_32F, cv::Scalar(10.0f));
  cv::Mat ids = (cv::Mat_<int>(2, 3) << 23, 26001, 26001, 7, 7, 26001);
  const solo::DepthMesh m = solo::meshFromDepth(depth, solo::PinholeCamera{5, 5, 1, 0.5, 3, 2}, ids);
  EXPECT_EQ(m.mesh.n_vertices(), 5u);
  EXPECT_EQ(m.vertexAt(0, 0), -1);
  EXPECT_EQ(m.mesh.property(m.properties.instance, OpenMesh::VertexHandle(m.vertexAt(1, 0))), 26001);
  EXPECT_EQ(m.mesh.property(m.properties.instance, OpenMesh::VertexHandle(m.vertexAt(0, 1))), 7);
}

TEST(DepthMesh, DiagonalJoinsTheCornersCloserInInverseDepth) {
  // Corner (0,0) and (1,1) at 5 m, (1,0) at 5 m, (0,1) at 20 m: the 00-11 diagonal keeps one
  // triangle (00, 11, 10) wholly on the near surface.
  cv::Mat depth = (cv::Mat_<float>(2, 2) << 5, 5, 20, 5);
  const solo::DepthMesh a = solo::meshFromDepth(depth, solo::PinholeCamera{5, 5, 0.5, 0.5, 2, 2});
  EXPECT_TRUE(hasEdge(a, 0, 0, 1, 1));
  EXPECT_FALSE(hasEdge(a, 1, 0, 0, 1));
  depth = (cv::Mat_<float>(2, 2) << 20, 5, 5, 5);
  const solo::DepthMesh b = solo::meshFromDepth(depth, solo::PinholeCamera{5, 5, 0.5, 0.5, 2, 2});
  EXPECT_TRUE(hasEdge(b, 1, 0, 0, 1));
}

/// Depth of the plane y = 1.5 m (a road 1.5 m below the camera) until it meets a wall.
cv::Mat roadAndWall(const solo::PinholeCamera& camera, double wall_depth_m) {
  cv::Mat depth(camera.height, camera.width, CV_32F);
  for (int v = 0; v < depth.rows; ++v)
    for (int u = 0; u < depth.cols; ++u) {
      const double ray_y = (v - camera.cy) / camera.fy;
      const double road = ray_y > 0 ? 1.5 / ray_y : 1e9;
      depth.at<float>(v, u) = static_cast<float>(std::min(road, wall_depth_m));
    }
  return depth;
}

TEST(SpuriousFaces, GrazingRoadAndItsCreaseWithAWallAreKept) {
  // Near the 60 m wall the road is seen at 88.6 degrees from its normal and its depth changes by
  // up to 2.5 m (17 footprints) per row; where it meets the wall there is a crease.
  const solo::PinholeCamera camera{400.0, 400.0, 31.5, 9.5, 64, 48};
  const cv::Mat depth = roadAndWall(camera, 60.0);
  const solo::DepthMesh m = solo::meshFromDepth(depth, camera);
  const solo::SpuriousFaceResult r = solo::findSpuriousFaces(m, depth, {}, {});
  EXPECT_EQ(r.faces_checked, static_cast<std::int64_t>(m.mesh.n_faces()));
  EXPECT_EQ(r.removed, 0);
  // Without the extrapolation test, the plain footprint criterion cuts the far road.
  solo::SpuriousFaceOptions plain;
  plain.extrapolation_test = false;
  EXPECT_GT(solo::findSpuriousFaces(m, depth, {}, {}, plain).by_depth_jump, 100);
}

TEST(SpuriousFaces, OcclusionStepIsCutExactlyAlongItsEdge) {
  // A 10 m wall with a 4 m wide frontal board at 5 m covering columns 10..19: every face touching
  // both depths bridges the occlusion, and only those.
  cv::Mat depth(kCamera.height, kCamera.width, CV_32F, cv::Scalar(10.0f));
  depth(cv::Rect(10, 0, 10, kCamera.height)).setTo(5.0f);
  const solo::DepthMesh m = solo::meshFromDepth(depth, kCamera);
  const solo::SpuriousFaceResult r = solo::findSpuriousFaces(m, depth, {}, {});
  std::int64_t bridging = 0;
  for (const auto f : m.mesh.faces()) {
    double zmin = 1e9, zmax = 0;
    for (const auto v : m.mesh.fv_range(f)) {
      zmin = std::min(zmin, m.mesh.point(v)[2]);
      zmax = std::max(zmax, m.mesh.point(v)[2]);
    }
    const bool bridges = zmax - zmin > 1.0;
    bridging += bridges;
    EXPECT_EQ(r.spurious[f.idx()] != 0, bridges) << "face " << f.idx();
  }
  EXPECT_EQ(bridging, 2 * 2 * (kCamera.height - 1));  // two columns of quads, two triangles each
  EXPECT_EQ(r.by_depth_jump, bridging);
  // The same cut by the uncertain mask alone, and by the instance boundary of a thing.
  solo::SpuriousFaceOptions jumps_off;
  jumps_off.depth_jump_factor = 1e9;
  cv::Mat uncertain(depth.size(), CV_8U, cv::Scalar(0));
  uncertain(cv::Rect(9, 0, 2, kCamera.height)).setTo(1);
  // Faces with a corner in columns 9..10 are the quads starting at columns 8, 9 and 10; only
  // those of quad 9 also jump (10 m to 5 m, over the mask's 8 footprints): the mask alone
  // removes nothing.
  const solo::SpuriousFaceResult by_mask = solo::findSpuriousFaces(m, depth, {}, uncertain, jumps_off);
  EXPECT_EQ(by_mask.by_uncertain, 2 * (kCamera.height - 1));
  for (const auto f : m.mesh.faces()) {
    int left = 0, right = 0;
    for (const auto v : m.mesh.fv_range(f)) {
      const int u = m.mesh.property(m.properties.pixel, v)[0];
      left += u == 9;
      right += u == 10;
    }
    EXPECT_EQ(by_mask.criteria[f.idx()] == solo::kUncertain, left > 0 && right > 0) << "face " << f.idx();
  }
  cv::Mat flat_mask(depth.size(), CV_8U, cv::Scalar(0));
  flat_mask(cv::Rect(2, 0, 4, kCamera.height)).setTo(1);  // over the wall only
  EXPECT_EQ(solo::findSpuriousFaces(m, depth, {}, flat_mask, jumps_off).by_uncertain, 0);
  cv::Mat ids(depth.size(), CV_32S, cv::Scalar(11));
  ids(cv::Rect(10, 0, 10, kCamera.height)).setTo(26001);
  const solo::SpuriousFaceResult by_ids = solo::findSpuriousFaces(m, depth, ids, {}, jumps_off);
  EXPECT_EQ(by_ids.by_instance_boundary, bridging);
  EXPECT_EQ(by_ids.by_depth_jump, 0);
}

TEST(SpuriousFaces, PrecisionAndRecallOnTheDefaultSyntheticScene) {
  // The embedded scene's exact depth, normals and instances (960x540). Measured: precision
  // 0.923, recall 0.889 of the occlusion criteria (docs/mesh.md); the target is 0.95.
  const solo::Scene truth = solo::loadScene(std::filesystem::path(SOLO_PROJECT_DATA_DIR) / "default/gt/scene.json");
  const solo::DepthMesh m = solo::meshFromDepth(truth.depth_m, truth.camera, truth.instances);
  const std::vector<std::uint8_t> spurious = solo::spuriousFacesFromGroundTruth(m, truth.depth_m, truth.normals);
  const solo::SpuriousFaceResult r = solo::findSpuriousFaces(m, truth.depth_m, truth.instances, {});
  std::vector<std::uint8_t> occlusion(r.criteria.size());
  for (std::size_t i = 0; i < occlusion.size(); ++i) occlusion[i] = (r.criteria[i] & solo::kOcclusionCriteria) != 0;
  const solo::DetectionScore score = solo::scoreDetection(occlusion, spurious);
  EXPECT_EQ(score.true_positives + score.false_negatives, 15627);
  EXPECT_NEAR(score.precision, 0.923, 0.002);
  EXPECT_NEAR(score.recall, 0.889, 0.002);
}

/// A 10 m wall filling the view, and a car (instance 26001) at 5 m over `rect`.
solo::StageReport cleanWallWithCar(const cv::Rect& rect, solo::DepthMesh* out = nullptr) {
  cv::Mat depth(kCamera.height, kCamera.width, CV_32F, cv::Scalar(10.0f));
  cv::Mat ids(depth.size(), CV_32S, cv::Scalar(11));
  depth(rect).setTo(5.0f);
  ids(rect).setTo(26001);
  solo::DepthMesh m = solo::meshFromDepth(depth, kCamera, ids);
  const solo::StageReport report = solo::cleanDepthMesh(m, depth, ids, {});
  if (out) *out = std::move(m);
  return report;
}

TEST(DepthMeshCleanup, HoleBehindAnOccluderIsFilledAndTheOccluderClosed) {
  solo::DepthMesh m;
  const solo::StageReport r = cleanWallWithCar(cv::Rect(10, 8, 10, 8), &m);
  EXPECT_EQ(metricInt(r, "found_inner_holes"), 1);
  EXPECT_EQ(metricInt(r, "found_silhouette_loops"), 1);
  EXPECT_EQ(metricInt(r, "holes_filled"), 1);
  EXPECT_EQ(metricInt(r, "foreground_solids"), 1);
  EXPECT_EQ(metricInt(r, "after_boundary_loops_total"), 1);  // the image frame only
  EXPECT_EQ(metricInt(r, "after_border_loops"), 1);
  EXPECT_EQ(metricInt(r, "after_inner_holes"), 0);
  EXPECT_EQ(metricInt(r, "after_components"), 2);
  EXPECT_EQ(metricInt(r, "after_non_manifold_edges"), 0);
  EXPECT_EQ(metricInt(r, "after_non_manifold_vertices"), 0);
  EXPECT_EQ(metricInt(r, "after_self_intersecting_pairs"), 0);
  EXPECT_EQ(metricInt(r, "after_degenerate_faces"), 0);
  // The car's back lies 1.8 m behind its front, clamped 5 cm in front of the wall: 4.95 m deep
  // at most; the filled wall is flat at 10 m.
  double deepest_back = 0;
  for (const auto v : m.mesh.vertices()) {
    const auto origin = static_cast<solo::VertexOrigin>(m.mesh.property(m.properties.origin, v));
    if (origin == solo::VertexOrigin::solid_back) deepest_back = std::max(deepest_back, m.mesh.point(v)[2]);
    if (origin == solo::VertexOrigin::hole_fill) {
      EXPECT_NEAR(m.mesh.point(v)[2], 10.0, 1e-6);
    }
  }
  EXPECT_NEAR(deepest_back, 6.8, 1e-9);
}

TEST(DepthMeshCleanup, CarStandingOnTheRoadDoesNotPierceTheRoadBehindIt) {
  // Camera 1.5 m above a road (y = 1.5, z = 75 / (v - 23.5)), a wall at 20 m above row 27, and
  // a frontal car board at 8.8 m (instance 26001) whose bottom row stands on the road. The road
  // patch behind the car's bottom row lies about 2 cm behind the board: a back pushed the full
  // 1.8 m would go through it.
  const solo::PinholeCamera camera{50.0, 50.0, 31.5, 23.5, 64, 48};
  cv::Mat depth(48, 64, CV_32F), ids(48, 64, CV_32S);
  for (int v = 0; v < 48; ++v)
    for (int u = 0; u < 64; ++u) {
      const bool road = v >= 28;
      depth.at<float>(v, u) = road ? static_cast<float>(75.0 / (v - 23.5)) : 20.0f;
      ids.at<int>(v, u) = road ? 7 : 11;
    }
  const cv::Rect car(20, 18, 21, 15);  // rows 18..32; the road is at 8.82 m at row 32
  depth(car).setTo(8.8f);
  ids(car).setTo(26001);
  solo::DepthMesh m = solo::meshFromDepth(depth, camera, ids);
  const solo::StageReport r = solo::cleanDepthMesh(m, depth, ids, {});
  EXPECT_EQ(metricInt(r, "foreground_solids"), 1);
  EXPECT_EQ(metricInt(r, "holes_left_open"), 0);
  EXPECT_GT(metricInt(r, "solid_back_vertices_clamped"), 0);
  EXPECT_EQ(metricInt(r, "after_non_manifold_edges"), 0);
  EXPECT_EQ(metricInt(r, "after_degenerate_faces"), 0);
  EXPECT_EQ(metricInt(r, "after_self_intersecting_pairs"), 0);
}

TEST(DepthMeshCleanup, HoleTouchingTheFrameIsClosedAlongTheFrame) {
  const solo::StageReport r = cleanWallWithCar(cv::Rect(10, 14, 10, kCamera.height - 14));
  EXPECT_EQ(metricInt(r, "found_inner_holes"), 0);
  EXPECT_EQ(metricInt(r, "found_frame_holes"), 1);
  EXPECT_EQ(metricInt(r, "holes_filled"), 1);
  EXPECT_EQ(metricInt(r, "foreground_solids"), 1);
  EXPECT_EQ(metricInt(r, "after_boundary_loops_total"), 1);
  EXPECT_EQ(metricInt(r, "after_frame_holes"), 0);
  EXPECT_EQ(metricInt(r, "after_self_intersecting_pairs"), 0);
  EXPECT_EQ(metricInt(r, "after_non_manifold_vertices"), 0);
}

TEST(DepthMeshCleanup, SkySeenThroughAGapStaysOpen) {
  // A wall with a window of sky (no depth) in its middle: an inner loop next to missing depth.
  cv::Mat depth(kCamera.height, kCamera.width, CV_32F, cv::Scalar(10.0f));
  depth(cv::Rect(12, 8, 6, 6)).setTo(0.0f);
  solo::DepthMesh m = solo::meshFromDepth(depth, kCamera);
  const solo::StageReport r = solo::cleanDepthMesh(m, depth, {}, {});
  EXPECT_EQ(metricInt(r, "found_sky_openings"), 1);
  EXPECT_EQ(metricInt(r, "found_inner_holes"), 0);
  EXPECT_EQ(metricInt(r, "after_boundary_loops_total"), 2);
  EXPECT_GE(metricDouble(r, "seconds_hole_filling"), 0.0);
}

}  // namespace
