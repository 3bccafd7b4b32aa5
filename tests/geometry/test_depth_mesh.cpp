// Mesh from depth: backprojection, spurious faces (hand-built depth maps with known answers and
// the embedded synthetic scene's ground truth), and the whole depth cleanup with its hard cases.

#include <solo/geometry/boundary_loops.h>
#include <solo/geometry/depth_mesh.h>
#include <solo/geometry/mesh_cleanup.h>
#include <solo/geometry/mesh_metrics.h>
#include <solo/core/scene.h>
#include <solo/geometry/spurious_faces.h>

#include "test_support.h"

#include <algorithm>
#include <cmath>
#include <set>

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

TEST(SpuriousFaces, UncertainMaskCutsNoFaceInsideOneClassOfAGrazingRoad) {
  // The road and wall above, the whole image uncertain (as the 10 px band around a car's foot
  // is): the far road changes depth by up to 17 footprints per row, over the mask's 8. Labelled
  // road throughout, it keeps every face; with the wall labelled building, the mask cuts only
  // faces with an edge between the classes that jumps; with uncertain_within_class, every face
  // with a jumping edge goes, which left bands without a surface at the foot of every car.
  const solo::PinholeCamera camera{400.0, 400.0, 31.5, 9.5, 64, 48};
  const cv::Mat depth = roadAndWall(camera, 60.0);
  const solo::DepthMesh m = solo::meshFromDepth(depth, camera);
  const cv::Mat uncertain(depth.size(), CV_8U, cv::Scalar(1));
  cv::Mat road(depth.size(), CV_32S, cv::Scalar(7));
  EXPECT_EQ(solo::findSpuriousFaces(m, depth, road, uncertain).removed, 0);

  cv::Mat road_and_wall = road.clone();
  road_and_wall.setTo(11, depth >= 59.99f);
  const solo::SpuriousFaceResult between = solo::findSpuriousFaces(m, depth, road_and_wall, uncertain);
  solo::SpuriousFaceOptions within_too;
  within_too.uncertain_within_class = true;
  const solo::SpuriousFaceResult within = solo::findSpuriousFaces(m, depth, road_and_wall, uncertain, within_too);
  const solo::SpuriousFaceResult unlabelled = solo::findSpuriousFaces(m, depth, {}, uncertain);
  std::int64_t jumping = 0, jumping_between = 0;
  for (const auto f : m.mesh.faces()) {
    std::vector<OpenMesh::Vec2i> px;
    for (const auto v : m.mesh.fv_range(f)) px.push_back(m.mesh.property(m.properties.pixel, v));
    bool jumps = false, jumps_between = false;
    for (int k = 0; k < 3; ++k) {
      const OpenMesh::Vec2i a = px[k], b = px[(k + 1) % 3];
      const double za = depth.at<float>(a[1], a[0]), zb = depth.at<float>(b[1], b[0]);
      const double length_px = std::hypot(double(a[0] - b[0]), double(a[1] - b[1]));
      const bool edge_jumps = std::abs(za - zb) > 8.0 * std::min(za, zb) / camera.fx * length_px;
      jumps = jumps || edge_jumps;
      jumps_between = jumps_between || (edge_jumps && road_and_wall.at<int>(a[1], a[0]) != road_and_wall.at<int>(b[1], b[0]));
    }
    jumping += jumps;
    jumping_between += jumps_between;
    EXPECT_EQ((between.criteria[f.idx()] & solo::kUncertain) != 0, jumps_between) << "face " << f.idx();
  }
  EXPECT_GT(jumping_between, 0);
  EXPECT_GT(jumping, 4 * jumping_between);
  EXPECT_EQ(between.by_uncertain, jumping_between);
  EXPECT_EQ(within.by_uncertain, jumping);
  EXPECT_EQ(unlabelled.by_uncertain, jumping);  // without labels every edge counts
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
  // 0.955, recall 0.9505 of the occlusion criteria, 13 987 of the 14 715 found (docs/mesh.md);
  // the target is 0.95.
  // 912 faces of the 15 627 the per-pixel planes call spurious are sub-pixel window detail of
  // far side facades (the ground truth's exception, spurious_faces.h).
  const solo::Scene truth = solo::loadScene(std::filesystem::path(SOLO_PROJECT_DATA_DIR) / "default/gt/scene.json");
  const solo::DepthMesh m = solo::meshFromDepth(truth.depth_m, truth.camera, truth.instances);
  const std::vector<std::uint8_t> spurious = solo::spuriousFacesFromGroundTruth(m, truth.depth_m, truth.normals);
  const solo::SpuriousFaceResult r = solo::findSpuriousFaces(m, truth.depth_m, truth.instances, {});
  std::vector<std::uint8_t> occlusion(r.criteria.size());
  for (std::size_t i = 0; i < occlusion.size(); ++i) occlusion[i] = (r.criteria[i] & solo::kOcclusionCriteria) != 0;
  const solo::DetectionScore score = solo::scoreDetection(occlusion, spurious);
  EXPECT_EQ(score.true_positives + score.false_negatives, 14715);
  EXPECT_GE(score.precision, 0.95);
  EXPECT_GE(score.recall, 0.95);
  EXPECT_NEAR(score.precision, 0.955, 0.002);
  EXPECT_NEAR(score.recall, 0.9505, 0.002);
  // With the normal map: the window edges of far side facades (most of the false positives)
  // are kept, no spurious face is lost.
  const solo::SpuriousFaceResult n = solo::findSpuriousFaces(m, truth.depth_m, truth.instances, {}, {}, truth.normals);
  for (std::size_t i = 0; i < occlusion.size(); ++i) occlusion[i] = (n.criteria[i] & solo::kOcclusionCriteria) != 0;
  const solo::DetectionScore with_normals = solo::scoreDetection(occlusion, spurious);
  EXPECT_EQ(with_normals.true_positives, score.true_positives);
  EXPECT_LT(with_normals.false_positives, score.false_positives * 0.6);
  EXPECT_GE(with_normals.precision, 0.97);
}

/// Exact depth and normals of axis-aligned boxes (and optionally the road plane y = 1.5 m, the
/// camera 1.5 m above it), ray cast per pixel centre like `solo synth`: the ground truth of the
/// hand-made cases below. Pixels that hit nothing get depth 0 (no vertex).
struct Box {
  Eigen::Vector3d lo, hi;
};
struct RayCast {
  cv::Mat depth_m, normals;
};
RayCast castBoxes(const solo::PinholeCamera& camera, const std::vector<Box>& boxes, bool road) {
  RayCast out{cv::Mat(camera.height, camera.width, CV_32F, cv::Scalar(0.0f)),
              cv::Mat(camera.height, camera.width, CV_32FC3, cv::Scalar(0, 0, 0))};
  for (int v = 0; v < camera.height; ++v)
    for (int u = 0; u < camera.width; ++u) {
      const Eigen::Vector3d ray((u - camera.cx) / camera.fx, (v - camera.cy) / camera.fy, 1.0);
      double best = road && ray.y() > 0 ? 1.5 / ray.y() : 1e30;  // t is the z-depth (ray.z = 1)
      Eigen::Vector3d normal(0, -1, 0);
      for (const Box& b : boxes) {
        double t_in = 0, t_out = 1e30;
        int axis_in = -1;
        for (int k = 0; k < 3; ++k) {
          if (ray[k] == 0) {
            if (0 < b.lo[k] || 0 > b.hi[k]) t_in = 1e30;
            continue;
          }
          double t0 = b.lo[k] / ray[k], t1 = b.hi[k] / ray[k];
          if (t0 > t1) std::swap(t0, t1);
          if (t0 > t_in) t_in = t0, axis_in = k;
          t_out = std::min(t_out, t1);
        }
        if (axis_in < 0 || t_in > t_out || t_in >= best) continue;
        best = t_in;
        normal = Eigen::Vector3d::Zero();
        normal[axis_in] = ray[axis_in] > 0 ? -1 : 1;
      }
      if (best >= 1e29) continue;
      out.depth_m.at<float>(v, u) = static_cast<float>(best);
      out.normals.at<cv::Vec3f>(v, u) = cv::Vec3f(float(normal.x()), float(normal.y()), float(normal.z()));
    }
  return out;
}

struct Removal {
  std::int64_t removed = 0, spurious = 0, removed_not_spurious = 0, spurious_kept = 0;
};
Removal scoreRemoval(const solo::DepthMesh& m, const RayCast& scene, const solo::SpuriousFaceOptions& options = {}) {
  const solo::SpuriousFaceResult r = solo::findSpuriousFaces(m, scene.depth_m, {}, {}, options);
  const std::vector<std::uint8_t> truth = solo::spuriousFacesFromGroundTruth(m, scene.depth_m, scene.normals);
  Removal out;
  for (std::size_t i = 0; i < truth.size(); ++i) {
    out.removed += r.spurious[i];
    out.spurious += truth[i];
    out.removed_not_spurious += r.spurious[i] && !truth[i];
    out.spurious_kept += truth[i] && !r.spurious[i];
  }
  return out;
}

TEST(SpuriousFaces, GroundTruthCallsSubPixelDetailOfAFacadeSurface) {
  // Each pixel of a row sees the camera-facing end of a different window of a side facade (the
  // facade x = -3 m seen at grazing angles, 20 to 60 m away): parallel planes metres apart, but
  // the points lie on the facade and a face through them follows it. The ground truth calls
  // none spurious; with a 30 cm notch in every fourth column (the point 30 cm behind the
  // facade) exactly the edges whose run of four pixels meets a notch are. Faces within one
  // pixel of the frame or the facade's end are left out: their runs leave the image.
  const solo::PinholeCamera camera{400.0, 400.0, 60.0, 4.0, 48, 9};
  const auto facade_depth = [&](int u, double x_m) { return float(x_m / ((u - camera.cx) / camera.fx)); };
  cv::Mat depth(camera.height, camera.width, CV_32F, cv::Scalar(0.0f));
  cv::Mat normals(depth.size(), CV_32FC3, cv::Scalar(0, 0, 0));
  for (int v = 0; v < camera.height; ++v)
    for (int u = 0; u <= 40; ++u) {
      depth.at<float>(v, u) = facade_depth(u, -3.0);
      normals.at<cv::Vec3f>(v, u) = cv::Vec3f(0, 0, -1);
    }
  cv::Mat notched = depth.clone();
  const auto is_notch = [](int u) { return u % 4 == 0 && u >= 4 && u <= 36; };
  for (int u = 4; u <= 36; u += 4) notched.col(u).setTo(facade_depth(u, -3.3));
  const solo::DepthMesh m = solo::meshFromDepth(depth, camera);
  const std::vector<std::uint8_t> truth = solo::spuriousFacesFromGroundTruth(m, depth, normals);
  const std::vector<std::uint8_t> notch_truth = solo::spuriousFacesFromGroundTruth(m, notched, normals);
  std::int64_t interior = 0, notch_faces = 0;
  for (const auto f : m.mesh.faces()) {
    std::vector<OpenMesh::Vec2i> p;
    for (const auto v : m.mesh.fv_range(f)) p.push_back(m.mesh.property(m.properties.pixel, v));
    bool inside = true, meets_notch = false;
    for (int k = 0; k < 3; ++k) {
      const OpenMesh::Vec2i a = p[k], b = p[(k + 1) % 3];
      inside = inside && a[0] >= 1 && a[0] <= 39 && a[1] >= 1 && a[1] <= camera.height - 2;
      if (a[0] == b[0]) continue;  // same column, same plane
      const int du = b[0] - a[0];
      for (const int u : {a[0] - du, a[0], b[0], b[0] + du}) meets_notch = meets_notch || is_notch(u);
    }
    if (!inside) continue;
    ++interior;
    notch_faces += meets_notch;
    EXPECT_EQ(truth[f.idx()], 0) << "face " << f.idx();
    EXPECT_EQ(notch_truth[f.idx()] != 0, meets_notch) << "face " << f.idx();
  }
  EXPECT_EQ(interior, 2 * 38 * 6);
  EXPECT_GT(notch_faces, interior / 2);
}

TEST(SpuriousFaces, SideFacadeWithWindowsSeenAtGrazingAnglesKeepsEveryFace) {
  // A facade at x = -3 m seen at 77 to 83 degrees from its normal, 13 to 24 m away, with a grid
  // of windows 6 cm proud of it (1.3 m wide every 2.6 m, 1.6 m tall every 3.2 m, as `solo
  // synth` builds them): every step is 6 cm, nothing bridges an occlusion.
  const solo::PinholeCamera camera{890.0, 890.0, 200.0, 18.0, 90, 36};
  std::vector<Box> boxes{{{-20, -30, 2}, {-3, 1.5, 400}}};
  for (double z0 = 5; z0 < 400; z0 += 2.6)
    for (double h0 = -30; h0 < 1.5; h0 += 3.2) boxes.push_back({{-3.02, h0, z0}, {-2.94, h0 + 1.6, z0 + 1.3}});
  const RayCast scene = castBoxes(camera, boxes, false);
  const solo::DepthMesh m = solo::meshFromDepth(scene.depth_m, camera);
  ASSERT_EQ(m.mesh.n_faces(), 2u * 89 * 35);  // every pixel sees the facade
  const Removal r = scoreRemoval(m, scene);
  EXPECT_EQ(r.spurious, 0);
  EXPECT_EQ(r.removed, 0);
  solo::SpuriousFaceOptions lines_only;  // the step measured from lines along the edge alone
  lines_only.block_plane_tolerance_footprints = 0;
  EXPECT_GT(scoreRemoval(m, scene, lines_only).removed, 0);  // 7: window edges cut
}

TEST(SpuriousFaces, TyreStandingOnTheRoadKeepsItsContact) {
  // A 0.62 m tall wheel (0.25 m wide, 0.6 m long) standing on the road 15 m ahead, 4.1 m to the
  // left: its side and the road beside it meet at the contact, seen at grazing angles. Only the
  // faces from its top and back edges to the road behind are spurious. (The horizon is out of
  // view: the road's farthest row, 33 m, has no row behind it.)
  const solo::PinholeCamera camera{890.0, 890.0, 280.0, -40.0, 72, 56};
  const RayCast scene = castBoxes(camera, {{{-4.35, 0.88, 15.0}, {-4.10, 1.5, 15.6}}}, true);
  const solo::DepthMesh m = solo::meshFromDepth(scene.depth_m, camera);
  const Removal r = scoreRemoval(m, scene);
  EXPECT_GT(r.spurious, 0);
  EXPECT_EQ(r.removed_not_spurious, 0);
  EXPECT_EQ(r.spurious_kept, 0);
  solo::SpuriousFaceOptions lines_only;
  lines_only.block_plane_tolerance_footprints = 0;
  // 16: the contact faces along the side's and the front's bottom edges, metres from the road's
  // line along the edge but centimetres from its plane.
  EXPECT_GT(scoreRemoval(m, scene, lines_only).removed_not_spurious, 0);
}

TEST(SpuriousFaces, ThinObjectBetweenANearAndAFarSurfaceIsCutFromBoth) {
  // Columns: a far wall at 33 m, a 2-pixel-wide object at 10 m, then a near object at the depth
  // where the line through the object's right column and the wall two pixels behind it meets the
  // near object's first ray. That line runs along the viewing rays and crosses no surface: the
  // near object is 2.6 m in front of the thin one, and every face between them is spurious.
  const solo::PinholeCamera camera = kCamera;
  const auto k = [&](int u) { return (u - camera.cx) / camera.fx; };
  const double z_far = 33.0, z_mid = 10.0;
  const double x1 = k(11) * z_mid, x2 = k(9) * z_far;
  const double t = (k(12) * z_mid - x1) / ((x2 - x1) - k(12) * (z_far - z_mid));
  const double z_near = z_mid + t * (z_far - z_mid);
  ASSERT_GT(z_near, 5.0);
  ASSERT_LT(z_near, 9.0);
  cv::Mat depth(camera.height, camera.width, CV_32F, cv::Scalar(float(z_far)));
  depth(cv::Rect(10, 0, 2, camera.height)).setTo(float(z_mid));
  depth(cv::Rect(12, 0, camera.width - 12, camera.height)).setTo(float(z_near));
  const solo::DepthMesh m = solo::meshFromDepth(depth, camera);
  const solo::SpuriousFaceResult r = solo::findSpuriousFaces(m, depth, {}, {});
  std::int64_t bridging_near = 0, cut_near = 0;
  for (const auto f : m.mesh.faces()) {
    int mid = 0, near = 0, far = 0;
    for (const auto v : m.mesh.fv_range(f)) {
      const int u = m.mesh.property(m.properties.pixel, v)[0];
      mid += u == 10 || u == 11;
      near += u >= 12;
      far += u <= 9;
    }
    const bool bridges = (mid > 0) + (near > 0) + (far > 0) > 1;
    EXPECT_EQ(r.spurious[f.idx()] != 0, bridges) << "face " << f.idx();
    bridging_near += mid > 0 && near > 0;
    cut_near += mid > 0 && near > 0 && r.spurious[f.idx()];
  }
  EXPECT_EQ(bridging_near, 2 * (camera.height - 1));
  EXPECT_EQ(cut_near, bridging_near);
  // Unchecked, the line through the thin object's right column and the wall two pixels behind
  // it explains the step: those faces stay (away from the top and bottom rows, where a
  // diagonal edge has no pixel two or four back).
  solo::SpuriousFaceOptions unchecked;
  unchecked.surface_line_linearity = 1e9;
  const solo::SpuriousFaceResult old = solo::findSpuriousFaces(m, depth, {}, {}, unchecked);
  std::int64_t interior_bridging = 0, interior_kept = 0;
  for (const auto f : m.mesh.faces()) {
    bool mid = false, near = false, interior = true;
    for (const auto v : m.mesh.fv_range(f)) {
      const OpenMesh::Vec2i p = m.mesh.property(m.properties.pixel, v);
      mid = mid || p[0] == 10 || p[0] == 11;
      near = near || p[0] >= 12;
      interior = interior && p[1] >= 4 && p[1] <= camera.height - 5;
    }
    if (!(mid && near && interior)) continue;
    ++interior_bridging;
    interior_kept += !old.spurious[f.idx()];
  }
  EXPECT_EQ(interior_bridging, 2 * (camera.height - 9));
  EXPECT_EQ(interior_kept, interior_bridging);
}

/// Which of `depths_m` (within 1 cm) each vertex of face f lies on; -1 for none.
std::vector<int> surfacesOfFace(const solo::DepthMesh& m, const cv::Mat& depth_m, OpenMesh::FaceHandle f,
                                const std::vector<double>& depths_m) {
  std::vector<int> out;
  for (const auto v : m.mesh.fv_range(f)) {
    const OpenMesh::Vec2i p = m.mesh.property(m.properties.pixel, v);
    const double z = depth_m.at<float>(p[1], p[0]);
    int which = -1;
    for (std::size_t k = 0; k < depths_m.size(); ++k)
      if (std::abs(z - depths_m[k]) < 0.01) which = static_cast<int>(k);
    out.push_back(which);
  }
  return out;
}

TEST(SpuriousFaces, StepOfAFewFootprintsBetweenParallelFacesIsCut) {
  // Two camera-facing boxes side by side 26 m ahead, the left one's front 20 cm behind the
  // right one's (the step of a street light's head or a car's cabin in data/default: 6.9
  // footprints, under the 8 of the criterion), before a wall at 50 m. Every face spanning two
  // of the three surfaces is spurious and removed, the 26 of the step included: the step
  // measured from either side's surface lines and planes is 20 cm, 6.9 footprints (at least
  // half the criterion, small_jump_fraction, are needed). With small jumps untested those 26 stay.
  const solo::PinholeCamera camera{890.0, 890.0, 19.5, 9.5, 40, 20};
  const RayCast scene = castBoxes(camera,
                                  {{{0.0, -0.2, 25.8}, {1.0, 0.2, 26.5}},
                                   {{-1.0, -0.2, 26.0}, {0.0, 0.2, 26.5}},
                                   {{-20.0, -20.0, 50.0}, {20.0, 20.0, 51.0}}},
                                  false);
  const solo::DepthMesh m = solo::meshFromDepth(scene.depth_m, camera);
  const std::vector<std::uint8_t> truth = solo::spuriousFacesFromGroundTruth(m, scene.depth_m, scene.normals);
  const solo::SpuriousFaceResult r = solo::findSpuriousFaces(m, scene.depth_m, {}, {});
  solo::SpuriousFaceOptions untested;
  untested.small_jump_fraction = 0;
  const solo::SpuriousFaceResult old = solo::findSpuriousFaces(m, scene.depth_m, {}, {}, untested);
  std::int64_t step_faces = 0, spurious_faces = 0;
  for (const auto f : m.mesh.faces()) {
    const std::vector<int> s = surfacesOfFace(m, scene.depth_m, f, {25.8, 26.0, 50.0});
    ASSERT_EQ(std::count(s.begin(), s.end(), -1), 0);
    const bool bridges = std::set<int>(s.begin(), s.end()).size() > 1;
    const bool step = bridges && std::count(s.begin(), s.end(), 2) == 0;
    EXPECT_EQ(truth[f.idx()] != 0, bridges) << "face " << f.idx();
    EXPECT_EQ(r.spurious[f.idx()] != 0, bridges) << "face " << f.idx();
    EXPECT_EQ(old.spurious[f.idx()] != 0, bridges && !step) << "face " << f.idx();
    step_faces += step;
    spurious_faces += bridges;
  }
  EXPECT_EQ(step_faces, 2 * 13);  // the rows 3 to 16 see the boxes: 13 quads along the step
  EXPECT_GT(spurious_faces, step_faces);
}

TEST(SpuriousFaces, WindowsProudOfAGrazingFacadeStayWithTheNormalMap) {
  // A side facade (x = -3 m, 10 to 120 m ahead) with windows 6 cm proud of it, 1.2 m long every
  // 2.5 m, seen at grazing angles: far away each pixel falls on a window or on the wall between,
  // and the depth jumps by metres from one to the next with no line or 2x2 block of depths that
  // follows the facade. A pole in front of the facade is a real occlusion. The ground truth calls
  // the window edges surface detail (a 6 cm step); the depths alone cut some of them, the normal
  // map (the facade's normal on windows and wall alike) keeps them all and still cuts every
  // spurious face the depths alone cut.
  const solo::PinholeCamera camera{890.0, 890.0, 120.0, 30.0, 160, 60};
  std::vector<Box> boxes{{{-3.5, -6.0, 10.0}, {-3.0, 6.0, 120.0}}, {{-0.9, -6.0, 14.0}, {-0.7, 6.0, 14.2}}};
  for (double z = 11.0; z < 119.0; z += 2.5)
    for (double y = -5.0; y < 5.0; y += 3.0) boxes.push_back({{-3.0, y, z}, {-2.94, y + 1.5, z + 1.2}});
  const RayCast scene = castBoxes(camera, boxes, false);
  const solo::DepthMesh m = solo::meshFromDepth(scene.depth_m, camera);
  const std::vector<std::uint8_t> truth = solo::spuriousFacesFromGroundTruth(m, scene.depth_m, scene.normals);
  const solo::SpuriousFaceResult depths_only = solo::findSpuriousFaces(m, scene.depth_m, {}, {});
  const solo::SpuriousFaceResult with_normals = solo::findSpuriousFaces(m, scene.depth_m, {}, {}, {}, scene.normals);
  solo::SpuriousFaceOptions off;
  off.use_normals = false;
  const solo::SpuriousFaceResult switched_off = solo::findSpuriousFaces(m, scene.depth_m, {}, {}, off, scene.normals);
  const solo::DetectionScore before = solo::scoreDetection(depths_only.spurious, truth);
  const solo::DetectionScore after = solo::scoreDetection(with_normals.spurious, truth);
  EXPECT_EQ(switched_off.spurious, depths_only.spurious);
  EXPECT_GT(before.true_positives, 0);
  EXPECT_EQ(after.true_positives, before.true_positives);
  EXPECT_LT(after.false_positives, before.false_positives);
  // Faces on window fronts and wall alone (every pixel on the facade with its normal): the depths
  // alone cut some, the normal map none. (A window's end face, 6 cm wide and facing the camera,
  // disagrees with the facade's normal by 90 degrees, more than normal_plane_max_angle_deg: its
  // faces are left to the depth tests.)
  std::int64_t facade_cut_by_depths = 0, facade_cut_with_normals = 0;
  for (const auto f : m.mesh.faces()) {
    bool facade = true;
    for (const auto v : m.mesh.fv_range(f)) {
      const OpenMesh::Vec2i p = m.mesh.property(m.properties.pixel, v);
      const double x_m = camera.backproject(p[0], p[1], scene.depth_m.at<float>(p[1], p[0])).x();
      facade = facade && scene.normals.at<cv::Vec3f>(p[1], p[0])[0] == 1.0f && x_m < -2.9;  // not the pole's side
    }
    if (!facade) continue;
    EXPECT_EQ(truth[f.idx()], 0) << "face " << f.idx();
    facade_cut_by_depths += depths_only.spurious[f.idx()];
    facade_cut_with_normals += with_normals.spurious[f.idx()];
  }
  EXPECT_GT(facade_cut_by_depths, 10);
  EXPECT_EQ(facade_cut_with_normals, 0);
  // A normal map of another size is refused.
  EXPECT_THROW(solo::findSpuriousFaces(m, scene.depth_m, {}, {}, {}, cv::Mat(4, 4, CV_32FC3)), std::invalid_argument);
}

TEST(SpuriousFaces, LineThroughAOnePixelGapDoesNotExplainTheOcclusion) {
  // Columns: a pole 9 m ahead up to column 9, a wall 18 m away seen through a one-pixel gap
  // (column 10), a plate 14 m away from column 11 (a pole before a facade in data/default).
  // The line through the gap's point and the plate's next to it runs along the viewing rays
  // (4 m deeper in one pixel) and passes 4 cm from the pole's point: by that line, a thin
  // step. But those two pixels are no surface (250 footprints apart, inverse depth not linear
  // over three pixels), so the line does not count and all 22 faces between the pole and the
  // gap are removed. With the line counted (occluded_line_factor 0) the 18 of them away from
  // the top and bottom rows stay (there a diagonal edge has no pixel behind it: the
  // edge-of-data rule cuts it). The faces between the gap and the plate are spurious too but
  // stay either way, except on the top and bottom rows: the gap, one pixel wide, has no
  // surface of its own to extrapolate, and its extrapolation from the pole behind it meets the
  // plate (a miss the docs list).
  const solo::PinholeCamera camera{890.0, 890.0, 4.5, 5.5, 24, 12};
  const auto x_at = [&](double u, double z_m) { return (u - camera.cx) / camera.fx * z_m; };
  const RayCast scene = castBoxes(camera,
                                  {{{-5.0, -20.0, 9.0}, {x_at(9.5, 9.0), 20.0, 9.01}},
                                   {{-20.0, -20.0, 18.0}, {20.0, 20.0, 18.01}},
                                   {{x_at(10.5, 14.0), -20.0, 14.0}, {5.0, 20.0, 14.01}}},
                                  false);
  const solo::DepthMesh m = solo::meshFromDepth(scene.depth_m, camera);
  const std::vector<std::uint8_t> truth = solo::spuriousFacesFromGroundTruth(m, scene.depth_m, scene.normals);
  const solo::SpuriousFaceResult r = solo::findSpuriousFaces(m, scene.depth_m, {}, {});
  solo::SpuriousFaceOptions counted;
  counted.occluded_line_factor = 0;
  const solo::SpuriousFaceResult old = solo::findSpuriousFaces(m, scene.depth_m, {}, {}, counted);
  std::int64_t pole_gap = 0, gap_plate = 0, removed = 0, old_kept_pole_gap = 0;
  for (const auto f : m.mesh.faces()) {
    const std::vector<int> s = surfacesOfFace(m, scene.depth_m, f, {9.0, 18.0, 14.0});
    ASSERT_EQ(std::count(s.begin(), s.end(), -1), 0);
    const bool bridges = std::set<int>(s.begin(), s.end()).size() > 1;
    const bool pole_and_gap = bridges && std::count(s.begin(), s.end(), 2) == 0;
    const bool gap_and_plate = bridges && std::count(s.begin(), s.end(), 0) == 0;
    int top_v = camera.height;
    for (const auto v : m.mesh.fv_range(f)) top_v = std::min(top_v, m.mesh.property(m.properties.pixel, v)[1]);
    const bool frame_row = top_v == 0 || top_v == camera.height - 2;
    EXPECT_EQ(truth[f.idx()] != 0, bridges) << "face " << f.idx();
    EXPECT_EQ(r.spurious[f.idx()] != 0, pole_and_gap || (gap_and_plate && frame_row)) << "face " << f.idx();
    EXPECT_EQ(old.spurious[f.idx()] != 0, (pole_and_gap || gap_and_plate) && frame_row) << "face " << f.idx();
    pole_gap += pole_and_gap;
    gap_plate += gap_and_plate;
    removed += r.spurious[f.idx()] != 0;
    old_kept_pole_gap += pole_and_gap && !old.spurious[f.idx()];
  }
  EXPECT_EQ(pole_gap, 2 * 11);
  EXPECT_EQ(gap_plate, 2 * 11);
  EXPECT_EQ(removed, 2 * 11 + 2 * 2);
  EXPECT_EQ(old_kept_pole_gap, 2 * 9);
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
    if (origin == solo::VertexOrigin::SolidBack) deepest_back = std::max(deepest_back, m.mesh.point(v)[2]);
    if (origin == solo::VertexOrigin::HoleFill) {
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
