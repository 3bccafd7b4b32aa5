#include "solo/geometry/spurious_faces.h"

#include "solo/core/scene.h"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <opencv2/core/utility.hpp>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>

namespace solo {
namespace {

constexpr double kRadPerDeg = 3.14159265358979323846 / 180.0;

struct FacePixels {
  std::array<OpenMesh::Vec2i, 3> pixel;
  std::array<int, 3> vertex;
};

FacePixels facePixels(const DepthMesh& m, OpenMesh::FaceHandle f) {
  FacePixels out{};
  int k = 0;
  for (const auto v : m.mesh.fv_range(f)) {
    out.vertex[k] = v.idx();
    out.pixel[k] = m.mesh.property(m.properties.pixel, v);
    ++k;
  }
  return out;
}

class JumpTest {
 public:
  JumpTest(const DepthMesh& mesh, const cv::Mat& depth, const cv::Mat& normals, const SpuriousFaceOptions& options)
      : mesh_(mesh),
        depth_(depth),
        normals_(normals),
        options_(options),
        focal_px_(0.5 * (mesh.camera.fx + mesh.camera.fy)),
        normals_agree_cos_(std::cos(options.normal_plane_max_angle_deg * kRadPerDeg)) {}

  /// The footprint test alone: |za - zb| over `factor` pixel footprints at the nearer depth.
  bool exceedsFootprints(const OpenMesh::Vec2i& a, const OpenMesh::Vec2i& b, double factor) const {
    const double za = depth_.at<float>(a[1], a[0]), zb = depth_.at<float>(b[1], b[0]);
    const int du = b[0] - a[0], dv = b[1] - a[1];
    return std::abs(za - zb) > factor * std::min(za, zb) / focal_px_ * std::sqrt(double(du * du + dv * dv));
  }

  bool isJump(const OpenMesh::Vec2i& a, const OpenMesh::Vec2i& b) const { return classify(a, b, true) == Edge::Jump; }

 private:
  enum class Edge { Small, Continuous, ThinStep, Jump };

  /// The jump test of one edge. with_planes = false leaves out the block planes of the step test
  /// (used on the blocks' own edges, so the test does not recurse).
  Edge classify(const OpenMesh::Vec2i& a, const OpenMesh::Vec2i& b, bool with_planes) const {
    const double factor = options_.depth_jump_factor;
    const double za = depth_.at<float>(a[1], a[0]), zb = depth_.at<float>(b[1], b[0]);
    const int du = b[0] - a[0], dv = b[1] - a[1];
    const double length_px = std::sqrt(double(du * du + dv * dv));
    const double footprint_m = std::min(za, zb) / focal_px_ * length_px;
    // A jump under the criterion but over small_jump_fraction of it is tested too; it must then
    // show a step of that many footprints as well (below).
    const double small_factor = options_.small_jump_fraction * factor;
    const bool small_jump = std::abs(za - zb) <= factor * footprint_m;
    if (small_jump && !(options_.small_jump_fraction > 0 && std::abs(za - zb) > small_factor * footprint_m))
      return Edge::Small;
    if (!options_.extrapolation_test) return small_jump ? Edge::Small : Edge::Jump;  // no step test either
    // The normal map measures the step directly (only for the edge itself: the edges of the
    // blocks behind it are tested on their depths, so that a block across a corner stays out).
    if (with_planes && !normals_.empty() &&
        distanceToNormalPlanes(a, b, point(a[0], a[1]), point(b[0], b[1])) < options_.min_step_m)
      return Edge::ThinStep;
    const double wa = 1.0 / za, wb = 1.0 / zb;
    // A side without a pixel behind it (image frame, sky) cannot be extrapolated: only jumps
    // larger than edge_of_data_factor times the criterion are cut there.
    if (!hasVertex(a[0] - du, a[1] - dv) || !hasVertex(b[0] + du, b[1] + dv))
      return std::abs(za - zb) > options_.edge_of_data_factor * factor * footprint_m ? Edge::Jump : Edge::Continuous;
    const double slope_a = wa - inverseDepth(a[0] - du, a[1] - dv);
    const double slope_b = inverseDepth(b[0] + du, b[1] + dv) - wb;
    // Side a: wa + t slope_a; side b: wb + (t - 1) slope_b; t = 0 at a, 1 at b.
    // The gap between the two sides, g(t) = g0 + t (g1 - g0), over t in [-slack, 1 + slack]:
    // continuous when it vanishes there or stays within the tolerance (in metres, about
    // dw / (wa wb)); an occlusion otherwise.
    const double g0 = wa - (wb - slope_b);
    const double g1 = (wa + slope_a) - wb;
    const double s = options_.crossing_slack_edges;
    const double lo = g0 - s * (g1 - g0), hi = g1 + s * (g1 - g0);
    if (lo == 0 || hi == 0 || (lo < 0) != (hi < 0)) return Edge::Continuous;
    const double smallest_gap_m = std::min(std::abs(lo), std::abs(hi)) / (wa * wb);
    if (smallest_gap_m <= options_.continuity_tolerance_footprints * footprint_m) return Edge::Continuous;
    // A thin step seen at a grazing angle (a window proud of a side facade) makes a large depth
    // jump between parallel surfaces only centimetres apart: measure how far each point lies
    // from the other side's surface line (through the point and the one behind it). A line
    // through pixels that themselves straddle a jump runs along the viewing rays and passes near
    // any point on the rays beside it (a car two pixels wide between a near person and a far
    // facade): such a line is no surface and does not count.
    const Eigen::Vector3d pa = point(a[0], a[1]), pb = point(b[0], b[1]);
    double apart_m = (pa - pb).norm();
    for (int step = 1; step <= 2; ++step) {  // two pixels back too: the first may be a one-pixel sliver
      const OpenMesh::Vec2i a_back(a[0] - step * du, a[1] - step * dv), b_back(b[0] + step * du, b[1] + step * dv);
      // The one-pixel line is dropped only when it crosses an occlusion (isOccludedLine): on
      // side facades whose pixels alternate between wall and window faces (inverse depth not
      // linear, 20-30 footprints a pixel) it still follows the facade within centimetres, and
      // checking its linearity alone cost more false positives than it saved (docs/mesh.md).
      if (step == 1 ? !isOccludedLine(a, -du, -dv) : isSurfaceLine(a, -step * du, -step * dv))
        apart_m = std::min(apart_m, distanceToLine(pb, pa, point(a_back[0], a_back[1])));
      if (step == 1 ? !isOccludedLine(b, du, dv) : isSurfaceLine(b, step * du, step * dv))
        apart_m = std::min(apart_m, distanceToLine(pa, pb, point(b_back[0], b_back[1])));
    }
    // A line only follows its surface along the edge: where a thin face stands on a surface
    // seen at a grazing angle (a tyre on the road, the window edges of a side facade) the other
    // point is centimetres from the surface's plane but metres from that line. So the planes of
    // the 2x2 pixel blocks behind each side count too.
    if (with_planes && options_.block_plane_tolerance_footprints > 0 && apart_m >= options_.min_step_m) {
      const int pu = -dv, pv = du;  // perpendicular to the edge in the image
      apart_m = std::min(apart_m, distanceToBlockPlanes(a, -du, -dv, pu, pv, pb));
      apart_m = std::min(apart_m, distanceToBlockPlanes(b, du, dv, pu, pv, pa));
    }
    const double min_step_m =
        small_jump ? std::max(options_.min_step_m, small_factor * footprint_m) : options_.min_step_m;
    return apart_m >= min_step_m ? Edge::Jump : Edge::ThinStep;
  }

  /// Whether the line through pixel s and s + (eu, ev) is no surface: no vertex there, or the
  /// two pixels are no surface line (isSurfaceLine) and jump by more than occluded_line_factor
  /// footprints (one of them lies far behind the other, on another surface).
  bool isOccludedLine(const OpenMesh::Vec2i& s, int eu, int ev) const {
    const OpenMesh::Vec2i t(s[0] + eu, s[1] + ev);
    if (!hasVertex(t[0], t[1])) return true;
    return options_.occluded_line_factor > 0 && exceedsFootprints(s, t, options_.occluded_line_factor) &&
           !isSurfaceLine(s, eu, ev);
  }

  /// Whether pixels s and s + (eu, ev) sample one surface: their depths are within the
  /// footprint criterion, or the inverse depth of s, s + e and s + 2e is linear (as on a plane,
  /// however grazing: second difference 0) to surface_line_linearity times the step between
  /// the first two (a jump onto a flat surface gives 1).
  bool isSurfaceLine(const OpenMesh::Vec2i& s, int eu, int ev) const {
    if (!hasVertex(s[0] + eu, s[1] + ev)) return false;
    const double z0 = depth_.at<float>(s[1], s[0]), z1 = depth_.at<float>(s[1] + ev, s[0] + eu);
    const double length_px = std::sqrt(double(eu * eu + ev * ev));
    if (std::abs(z0 - z1) <= options_.depth_jump_factor * std::min(z0, z1) / focal_px_ * length_px) return true;
    if (!hasVertex(s[0] + 2 * eu, s[1] + 2 * ev)) return false;
    const double w0 = 1.0 / z0, w1 = 1.0 / z1, w2 = inverseDepth(s[0] + 2 * eu, s[1] + 2 * ev);
    return std::abs(w0 - 2 * w1 + w2) <= options_.surface_line_linearity * std::abs(w0 - w1);
  }

  /// Distance of `other` from the planes of the blocks s, s + e, s + q, s + e + q (q = +-p) behind
  /// pixel s: a block counts when it is planar (its fourth point within
  /// block_plane_tolerance_footprints of the plane of the other three) and none of its four
  /// edges is a jump. Without the second condition a block across a straight occlusion edge
  /// (two near and two far pixels: coplanar) would explain every jump at an occluder's corner.
  double distanceToBlockPlanes(const OpenMesh::Vec2i& s, int eu, int ev, int pu, int pv,
                               const Eigen::Vector3d& other) const {
    double best = std::numeric_limits<double>::infinity();
    const OpenMesh::Vec2i s1(s[0] + eu, s[1] + ev);
    if (!hasVertex(s1[0], s1[1])) return best;
    const Eigen::Vector3d p0 = point(s[0], s[1]), p1 = point(s1[0], s1[1]);
    for (const int sign : {-1, 1}) {
      const OpenMesh::Vec2i s2(s[0] + sign * pu, s[1] + sign * pv), s3(s2[0] + eu, s2[1] + ev);
      if (!hasVertex(s2[0], s2[1]) || !hasVertex(s3[0], s3[1])) continue;
      const Eigen::Vector3d p2 = point(s2[0], s2[1]), p3 = point(s3[0], s3[1]);
      Eigen::Vector3d normal = (p1 - p0).cross(p2 - p0);
      const double length = normal.norm();
      if (!(length > 0)) continue;
      normal /= length;
      const double footprint_m = p0.z() / focal_px_;
      if (std::abs(normal.dot(p3 - p0)) > options_.block_plane_tolerance_footprints * footprint_m) continue;
      if (classify(s, s2, false) == Edge::Jump || classify(s1, s3, false) == Edge::Jump ||
          classify(s, s1, false) == Edge::Jump || classify(s2, s3, false) == Edge::Jump)
        continue;
      best = std::min(best, std::abs(normal.dot(other - p0)));
    }
    return best;
  }

  /// Each point's distance from the plane through the other with the other's normal (the normal
  /// map), the smaller one; infinite unless both normals are valid and agree within
  /// normal_plane_max_angle_deg (a window proud of its facade: both carry the facade's normal,
  /// and the step is the window's depth; near an occluder's outline a blurred normal belongs to
  /// neither surface).
  double distanceToNormalPlanes(const OpenMesh::Vec2i& a, const OpenMesh::Vec2i& b, const Eigen::Vector3d& pa,
                                const Eigen::Vector3d& pb) const {
    const cv::Vec3f ca = normals_.at<cv::Vec3f>(a[1], a[0]), cb = normals_.at<cv::Vec3f>(b[1], b[0]);
    const Eigen::Vector3d na(ca[0], ca[1], ca[2]), nb(cb[0], cb[1], cb[2]);
    const double la = na.norm(), lb = nb.norm();
    if (!(la > 0.5 && lb > 0.5) || !std::isfinite(la) || !std::isfinite(lb)) return std::numeric_limits<double>::infinity();
    if (std::abs(na.dot(nb)) < normals_agree_cos_ * la * lb) return std::numeric_limits<double>::infinity();
    return std::min(std::abs(na.dot(pb - pa)) / la, std::abs(nb.dot(pa - pb)) / lb);
  }

  bool hasVertex(int u, int v) const { return mesh_.vertexAt(u, v) >= 0; }
  double inverseDepth(int u, int v) const { return 1.0 / depth_.at<float>(v, u); }
  Eigen::Vector3d point(int u, int v) const { return mesh_.camera.backproject(u, v, depth_.at<float>(v, u)); }
  static double distanceToLine(const Eigen::Vector3d& p, const Eigen::Vector3d& on_line, const Eigen::Vector3d& other) {
    const Eigen::Vector3d direction = on_line - other;
    const double length = direction.norm();
    return length > 0 ? direction.cross(p - on_line).norm() / length : (p - on_line).norm();
  }

  const DepthMesh& mesh_;
  const cv::Mat& depth_;
  const cv::Mat& normals_;
  const SpuriousFaceOptions& options_;
  double focal_px_;
  double normals_agree_cos_;
};

}  // namespace

bool isForegroundThingClass(int class_id) {
  switch (class_id) {
    case 17: case 19: case 20: case 24: case 25: case 26: case 27: case 28: case 31: case 32: case 33:
      return true;
    default:
      return false;
  }
}

SpuriousFaceResult findSpuriousFaces(const DepthMesh& m, const cv::Mat& depth_m, const cv::Mat& instances,
                                     const cv::Mat& uncertain, const SpuriousFaceOptions& options,
                                     const cv::Mat& normals) {
  if (!normals.empty() && (normals.type() != CV_32FC3 || normals.size() != depth_m.size()))
    throw std::invalid_argument("findSpuriousFaces: the normal map must be CV_32FC3 of the depth map's size");
  SpuriousFaceResult result;
  const SurfaceMesh& mesh = m.mesh;
  result.spurious.assign(mesh.n_faces(), 0);
  result.criteria.assign(mesh.n_faces(), 0);
  const bool use_instances = options.cut_instance_boundaries && !instances.empty();
  const bool use_uncertain = options.use_uncertain_mask && !uncertain.empty();
  const bool use_grazing = options.grazing_angle_deg < 90.0;
  const double grazing_cos = std::cos(options.grazing_angle_deg * kRadPerDeg);
  const cv::Mat no_normals;
  const JumpTest jumps(m, depth_m, options.use_normals ? normals : no_normals, options);
  std::atomic<std::int64_t> checked{0}, removed{0}, jump{0}, grazing{0}, uncertain_count{0}, instance{0};

  cv::parallel_for_(cv::Range(0, static_cast<int>(mesh.n_faces())), [&](const cv::Range& range) {
    std::int64_t n_checked = 0, n_removed = 0, n_jump = 0, n_grazing = 0, n_uncertain = 0, n_instance = 0;
    for (int fi = range.start; fi < range.end; ++fi) {
      const OpenMesh::FaceHandle f(fi);
      if (mesh.status(f).deleted()) continue;
      ++n_checked;
      const FacePixels fp = facePixels(m, f);
      bool is_jump = false;
      for (int k = 0; k < 3 && !is_jump; ++k) is_jump = jumps.isJump(fp.pixel[k], fp.pixel[(k + 1) % 3]);

      bool is_grazing = false;
      if (use_grazing) {
        const auto& p0 = mesh.point(OpenMesh::VertexHandle(fp.vertex[0]));
        const auto& p1 = mesh.point(OpenMesh::VertexHandle(fp.vertex[1]));
        const auto& p2 = mesh.point(OpenMesh::VertexHandle(fp.vertex[2]));
        const auto normal = (p1 - p0) % (p2 - p0);
        const auto centroid = (p0 + p1 + p2) / 3.0;
        const double denominator = normal.norm() * centroid.norm();
        is_grazing = denominator > 0 && std::abs(normal | centroid) < grazing_cos * denominator;
      }

      std::array<int, 3> ids{0, 0, 0};
      if (!instances.empty())
        for (int k = 0; k < 3; ++k) ids[k] = instances.at<int>(fp.pixel[k][1], fp.pixel[k][0]);
      const bool one_instance = ids[0] == ids[1] && ids[1] == ids[2];

      bool is_uncertain = false;
      if (use_uncertain) {
        bool any = false;
        for (int k = 0; k < 3; ++k) any = any || uncertain.at<std::uint8_t>(fp.pixel[k][1], fp.pixel[k][0]) != 0;
        if (any) {
          double zmin = 1e300, zmax = 0;
          for (int k = 0; k < 3; ++k) {
            const double z = depth_m.at<float>(fp.pixel[k][1], fp.pixel[k][0]);
            zmin = std::min(zmin, z);
            zmax = std::max(zmax, z);
          }
          const bool inside_one_thing = !instances.empty() && one_instance &&
                                        isForegroundThingClass(cityscapesClassOfInstance(ids[0])) &&
                                        zmax - zmin <= options.uncertain_same_object_span_m;
          // The mask marks where the depth is unreliable, not where surfaces part: a face in it
          // goes only when one of its edges also jumps (the footprint test alone, since the
          // extrapolation and step tests need the reliable depth the mask says is missing).
          for (int k = 0; k < 3 && !inside_one_thing && !is_uncertain; ++k) {
            const bool between_classes = instances.empty() || options.uncertain_within_class ||
                                         cityscapesClassOfInstance(ids[k]) != cityscapesClassOfInstance(ids[(k + 1) % 3]);
            is_uncertain = between_classes &&
                           jumps.exceedsFootprints(fp.pixel[k], fp.pixel[(k + 1) % 3], options.uncertain_jump_factor);
          }
        }
      }

      bool is_instance_boundary = false;
      if (use_instances && !one_instance)
        for (int k = 0; k < 3; ++k)
          is_instance_boundary = is_instance_boundary || isForegroundThingClass(cityscapesClassOfInstance(ids[k]));

      n_jump += is_jump;
      n_grazing += is_grazing;
      n_uncertain += is_uncertain;
      n_instance += is_instance_boundary;
      result.criteria[fi] = static_cast<std::uint8_t>((is_jump ? kDepthJump : 0) | (is_grazing ? kGrazing : 0) |
                                                      (is_uncertain ? kUncertain : 0) |
                                                      (is_instance_boundary ? kInstanceBoundary : 0));
      if (result.criteria[fi]) {
        result.spurious[fi] = 1;
        ++n_removed;
      }
    }
    checked += n_checked;
    removed += n_removed;
    jump += n_jump;
    grazing += n_grazing;
    uncertain_count += n_uncertain;
    instance += n_instance;
  });
  result.faces_checked = checked;
  result.removed = removed;
  result.by_depth_jump = jump;
  result.by_grazing = grazing;
  result.by_uncertain = uncertain_count;
  result.by_instance_boundary = instance;
  return result;
}

std::vector<std::uint8_t> spuriousFacesFromGroundTruth(const DepthMesh& m, const cv::Mat& true_depth_m,
                                                       const cv::Mat& true_normals, double min_gap_m) {
  const SurfaceMesh& mesh = m.mesh;
  std::vector<std::uint8_t> truth(mesh.n_faces(), 0);
  const PinholeCamera& cam = m.camera;
  const auto ray = [&](const OpenMesh::Vec2i& p) {
    return Eigen::Vector3d((p[0] - cam.cx) / cam.fx, (p[1] - cam.cy) / cam.fy, 1.0);
  };
  const auto normal = [&](const OpenMesh::Vec2i& p) {
    const cv::Vec3f n = true_normals.at<cv::Vec3f>(p[1], p[0]);
    return Eigen::Vector3d(n[0], n[1], n[2]);
  };
  const auto true_point = [&](int u, int v) -> std::optional<Eigen::Vector3d> {
    if (u < 0 || v < 0 || u >= true_depth_m.cols || v >= true_depth_m.rows) return std::nullopt;
    const double z = true_depth_m.at<float>(v, u);
    if (!(z > 0)) return std::nullopt;
    return Eigen::Vector3d(z * (u - cam.cx) / cam.fx, z * (v - cam.cy) / cam.fy, z);
  };
  // The sub-pixel-detail exception (header): the points of a - d, a, b, b + d evenly spaced
  // along one line within min_gap_m / 2.
  const auto onePixelRowLine = [&](const OpenMesh::Vec2i& a, const OpenMesh::Vec2i& b) {
    const int du = b[0] - a[0], dv = b[1] - a[1];
    const auto q0 = true_point(a[0] - du, a[1] - dv), q1 = true_point(a[0], a[1]), q2 = true_point(b[0], b[1]),
               q3 = true_point(b[0] + du, b[1] + dv);
    if (!q0 || !q1 || !q2 || !q3) return false;
    const std::array<Eigen::Vector3d, 4> q{*q0, *q1, *q2, *q3};
    const std::array<double, 3> steps{(q[1] - q[0]).norm(), (q[2] - q[1]).norm(), (q[3] - q[2]).norm()};
    if (*std::max_element(steps.begin(), steps.end()) > 2.0 * *std::min_element(steps.begin(), steps.end()))
      return false;  // a jump among smaller steps: two clusters lie on any line through them
    const Eigen::Vector3d centre = (q[0] + q[1] + q[2] + q[3]) / 4.0;
    Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
    for (const auto& x : q) scatter += (x - centre) * (x - centre).transpose();
    const Eigen::Vector3d direction = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(scatter).eigenvectors().col(2);
    for (const auto& x : q) {
      const Eigen::Vector3d r = x - centre;
      if ((r - r.dot(direction) * direction).norm() > 0.5 * min_gap_m) return false;
    }
    return true;
  };
  cv::parallel_for_(cv::Range(0, static_cast<int>(mesh.n_faces())), [&](const cv::Range& range) {
    for (int fi = range.start; fi < range.end; ++fi) {
      const OpenMesh::FaceHandle f(fi);
      if (mesh.status(f).deleted()) continue;
      const FacePixels fp = facePixels(m, f);
      for (int k = 0; k < 3 && !truth[fi]; ++k) {
        const OpenMesh::Vec2i a = fp.pixel[k], b = fp.pixel[(k + 1) % 3];
        const double za = true_depth_m.at<float>(a[1], a[0]), zb = true_depth_m.at<float>(b[1], b[0]);
        if (!(za > 0) || !(zb > 0)) continue;
        const Eigen::Vector3d na = normal(a), nb = normal(b), ra = ray(a), rb = ray(b);
        const double ca = na.dot(za * ra), cb = nb.dot(zb * rb);
        if (std::abs(ca) < 1e-12 || std::abs(cb) < 1e-12) continue;
        // Inverse depth of plane A and of plane B at pixels a and b.
        const double wa_at_a = 1.0 / za, wa_at_b = na.dot(rb) / ca;
        const double wb_at_a = nb.dot(ra) / cb, wb_at_b = 1.0 / zb;
        const double g0 = wa_at_a - wb_at_a, g1 = wa_at_b - wb_at_b;
        const double tolerance = 1e-3 * std::max(wa_at_a, wb_at_b);
        if (std::abs(g0) <= tolerance || std::abs(g1) <= tolerance) continue;
        if ((g0 < 0) != (g1 < 0)) continue;
        // How far apart the two surfaces are: each point's distance from the other's plane.
        const Eigen::Vector3d pa = za * ra, pb = zb * rb;
        const double apart_m = std::min(std::abs(na.dot(pb - pa)) / na.norm(), std::abs(nb.dot(pa - pb)) / nb.norm());
        if (apart_m < min_gap_m) continue;
        if (!onePixelRowLine(a, b)) truth[fi] = 1;
      }
    }
  });
  return truth;
}

DetectionScore scoreDetection(const std::vector<std::uint8_t>& flagged, const std::vector<std::uint8_t>& truth) {
  DetectionScore s;
  const std::size_t n = std::min(flagged.size(), truth.size());
  for (std::size_t i = 0; i < n; ++i) {
    if (flagged[i] && truth[i]) ++s.true_positives;
    else if (flagged[i]) ++s.false_positives;
    else if (truth[i]) ++s.false_negatives;
  }
  if (s.true_positives + s.false_positives > 0)
    s.precision = double(s.true_positives) / double(s.true_positives + s.false_positives);
  if (s.true_positives + s.false_negatives > 0)
    s.recall = double(s.true_positives) / double(s.true_positives + s.false_negatives);
  return s;
}

}  // namespace solo
