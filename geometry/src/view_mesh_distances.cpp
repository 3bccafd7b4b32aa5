// Mesh-to-truth distances of a depth mesh split by face origin and depth band, relative
// distances, and the coverage of the true visible surface (view_mesh_distances.h).

#include "solo/geometry/view_mesh_distances.h"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>
#include <stdexcept>

namespace solo {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using Triangle = Kernel::Triangle_3;
using Primitive = CGAL::AABB_triangle_primitive<Kernel, std::vector<Triangle>::const_iterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, Primitive>>;

/// Depth used for relative distances: a point at or behind the camera plane (none of a depth
/// mesh is) counts as 1 mm away rather than dividing by zero.
constexpr double kMinDepthM = 1e-3;

Point toPoint(const Eigen::Vector3d& p) { return {p.x(), p.y(), p.z()}; }

/// The non-degenerate faces as CGAL triangles, with the index of the face each came from.
std::vector<Triangle> triangles(const TriangleMesh& mesh, std::vector<std::size_t>* face_index) {
  std::vector<Triangle> out;
  out.reserve(mesh.faces.size());
  for (std::size_t i = 0; i < mesh.faces.size(); ++i) {
    const auto& f = mesh.faces[i];
    for (const std::uint32_t v : f)
      if (v >= mesh.vertices.size()) throw std::invalid_argument("measureViewMeshDistances: face index out of range");
    const Triangle t(toPoint(mesh.vertices[f[0]]), toPoint(mesh.vertices[f[1]]), toPoint(mesh.vertices[f[2]]));
    if (t.is_degenerate()) continue;
    out.push_back(t);
    if (face_index) face_index->push_back(i);
  }
  return out;
}

int bandOf(double z_m, const std::vector<double>& edges) {
  return static_cast<int>(std::upper_bound(edges.begin(), edges.end(), z_m) - edges.begin());
}

// Throws std::invalid_argument for options or inputs measureViewMeshDistances does not accept
// (before any triangle is made).
void checkInputs(const TriangleMesh& mesh, const std::vector<FaceOrigin>& face_origin, const cv::Mat& true_depth_m,
                 const ViewMeshDistanceOptions& options) {
  if (options.samples < 1) throw std::invalid_argument("measureViewMeshDistances: samples must be at least 1");
  if (!face_origin.empty() && face_origin.size() != mesh.faces.size())
    throw std::invalid_argument("measureViewMeshDistances: face_origin has " + std::to_string(face_origin.size()) +
                                " entries for " + std::to_string(mesh.faces.size()) + " faces");
  const std::vector<double>& edges = options.depth_band_edges_m;
  if (!std::is_sorted(edges.begin(), edges.end()) ||
      std::adjacent_find(edges.begin(), edges.end()) != edges.end())
    throw std::invalid_argument("measureViewMeshDistances: depth band edges must increase");
  if (!true_depth_m.empty() && true_depth_m.type() != CV_32F)
    throw std::invalid_argument("measureViewMeshDistances: the true depth must be CV_32F");
}

// Per mesh triangle: the part it counts in (its origin, and the depth band of its centroid: a
// face spans at most a pixel quad, so its band is that of its pixels), and the running sum of
// the areas (for sampling by area).
struct TriangleParts {
  std::vector<double> cumulative_area;
  std::vector<int> origin_of, band_of;
};

// The triangles' parts; their areas summed into `out` (whole, per origin and per band).
TriangleParts triangleParts(const std::vector<Triangle>& mesh_triangles, const std::vector<std::size_t>& mesh_face,
                            const std::vector<FaceOrigin>& face_origin, const std::vector<double>& edges,
                            ViewMeshDistances& out) {
  TriangleParts parts;
  parts.cumulative_area.resize(mesh_triangles.size());
  parts.origin_of.resize(mesh_triangles.size());
  parts.band_of.resize(mesh_triangles.size());
  double area_sum = 0;
  for (std::size_t i = 0; i < mesh_triangles.size(); ++i) {
    const double area = std::sqrt(CGAL::to_double(mesh_triangles[i].squared_area()));
    const Point c = CGAL::centroid(mesh_triangles[i]);
    parts.origin_of[i] = face_origin.empty() ? 0 : static_cast<int>(face_origin[mesh_face[i]]);
    parts.band_of[i] = bandOf(CGAL::to_double(c.z()), edges);
    out.by_origin[static_cast<std::size_t>(parts.origin_of[i])].area_m2 += area;
    out.by_depth[static_cast<std::size_t>(parts.band_of[i])].area_m2 += area;
    area_sum += area;
    parts.cumulative_area[i] = area_sum;
  }
  out.area_m2 = area_sum;
  return parts;
}

// The mesh -> truth distances: `samples` area-uniform random points on the mesh, their
// distance to the truth, whole and per part (out.area_m2 and the parts' areas already set).
void sampleMeshToTruth(const std::vector<Triangle>& mesh_triangles, const TriangleParts& parts,
                       const std::vector<Triangle>& truth_triangles, std::int64_t samples, std::mt19937_64& random,
                       ViewMeshDistances& out) {
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  Tree truth_tree(truth_triangles.begin(), truth_triangles.end());
  truth_tree.accelerate_distance_queries();
  const double area_sum = out.area_m2;
  double sum_m = 0, sum_relative = 0;
  for (std::int64_t s = 0; s < samples; ++s) {
    const double pick = uniform(random) * area_sum;
    const std::size_t i = std::min<std::size_t>(
        static_cast<std::size_t>(std::lower_bound(parts.cumulative_area.begin(), parts.cumulative_area.end(), pick) -
                                 parts.cumulative_area.begin()),
        mesh_triangles.size() - 1);
    const Triangle& t = mesh_triangles[i];
    // Uniform in the triangle: sqrt of the first variate (Osada et al.'s formula).
    const double r1 = std::sqrt(uniform(random)), r2 = uniform(random);
    const Point x = CGAL::ORIGIN + (1 - r1) * (t[0] - CGAL::ORIGIN) + r1 * (1 - r2) * (t[1] - CGAL::ORIGIN) +
                    r1 * r2 * (t[2] - CGAL::ORIGIN);
    const double d = std::sqrt(CGAL::to_double(truth_tree.squared_distance(x)));
    const double relative = d / std::max(CGAL::to_double(x.z()), kMinDepthM);
    sum_m += d;
    sum_relative += relative;
    for (DistancePart* part : {&out.by_origin[static_cast<std::size_t>(parts.origin_of[i])],
                               &out.by_depth[static_cast<std::size_t>(parts.band_of[i])]}) {
      ++part->samples;
      part->mean_m += d;  // sums until the division below
      part->mean_relative += relative;
    }
  }
  const double n = static_cast<double>(samples);
  out.samples = samples;
  out.mean_to_truth_m = sum_m / n;
  out.mean_relative_to_truth = sum_relative / n;
  auto finish = [&](DistancePart& part) {
    part.area_share = part.area_m2 / area_sum;
    part.contribution_m = part.mean_m / n;
    if (part.samples > 0) {
      part.mean_m /= static_cast<double>(part.samples);
      part.mean_relative /= static_cast<double>(part.samples);
    }
  };
  for (DistancePart& part : out.by_origin) finish(part);
  for (DistancePart& part : out.by_depth) finish(part);
}

// The true visible surface: pixel centres at their true depth (a seeded random subset of at
// most options.samples), their distance to the mesh relative to their depth, and how many the
// mesh covers.
void measureTruthCoverage(const std::vector<Triangle>& mesh_triangles, const cv::Mat& true_depth_m,
                          const PinholeCamera& camera, const ViewMeshDistanceOptions& options, std::mt19937_64& random,
                          ViewMeshDistances& out) {
  const PinholeCamera cam = camera.scaledTo(true_depth_m.cols, true_depth_m.rows);
  std::vector<std::pair<int, int>> pixels;
  for (int v = 0; v < true_depth_m.rows; ++v)
    for (int u = 0; u < true_depth_m.cols; ++u) {
      const float z = true_depth_m.at<float>(v, u);
      if (std::isfinite(z) && z > 0) pixels.emplace_back(u, v);
    }
  if (static_cast<std::int64_t>(pixels.size()) > options.samples) {
    std::shuffle(pixels.begin(), pixels.end(), random);
    pixels.resize(static_cast<std::size_t>(options.samples));
  }
  if (pixels.empty()) return;
  Tree mesh_tree(mesh_triangles.begin(), mesh_triangles.end());
  mesh_tree.accelerate_distance_queries();
  double truth_relative_sum = 0;
  std::int64_t covered = 0;
  std::vector<std::int64_t> covered_by_depth(out.truth_covered_by_depth.size(), 0);
  for (const auto& [u, v] : pixels) {
    const double z = true_depth_m.at<float>(v, u);
    const Eigen::Vector3d p = cam.backproject(u, v, z);
    const double relative = std::sqrt(CGAL::to_double(mesh_tree.squared_distance(toPoint(p)))) / z;
    const auto band = static_cast<std::size_t>(bandOf(z, options.depth_band_edges_m));
    truth_relative_sum += relative;
    ++out.truth_pixels_by_depth[band];
    if (relative < options.covered_relative) {
      ++covered;
      ++covered_by_depth[band];
    }
  }
  out.truth_pixels = static_cast<std::int64_t>(pixels.size());
  out.truth_mean_relative_to_mesh = truth_relative_sum / static_cast<double>(out.truth_pixels);
  out.truth_covered = static_cast<double>(covered) / static_cast<double>(out.truth_pixels);
  for (std::size_t b = 0; b < out.truth_covered_by_depth.size(); ++b)
    if (out.truth_pixels_by_depth[b] > 0)
      out.truth_covered_by_depth[b] =
          static_cast<double>(covered_by_depth[b]) / static_cast<double>(out.truth_pixels_by_depth[b]);
}

}  // namespace

const char* faceOriginName(FaceOrigin origin) {
  switch (origin) {
    case FaceOrigin::DepthSurface: return "depth_surface";
    case FaceOrigin::HoleFill: return "hole_fill";
    case FaceOrigin::Solid: return "solid";
  }
  return "unknown";
}

std::vector<FaceOrigin> faceOrigins(const SurfaceMesh& mesh) {
  const std::optional<ImageVertexProperties> properties = ImageVertexProperties::find(mesh);
  std::vector<FaceOrigin> out;
  out.reserve(mesh.n_faces());
  for (const auto f : mesh.faces()) {
    if (mesh.status(f).deleted()) continue;
    FaceOrigin origin = FaceOrigin::DepthSurface;
    if (properties)
      for (const auto v : mesh.fv_range(f)) {
        const auto o = static_cast<VertexOrigin>(mesh.property(properties->origin, v));
        if (o == VertexOrigin::SolidBack) origin = FaceOrigin::Solid;
        else if (o == VertexOrigin::HoleFill && origin != FaceOrigin::Solid) origin = FaceOrigin::HoleFill;
      }
    out.push_back(origin);
  }
  return out;
}

ViewMeshDistances measureViewMeshDistances(const TriangleMesh& mesh, const std::vector<FaceOrigin>& face_origin,
                                           const TriangleMesh& truth, const cv::Mat& true_depth_m,
                                           const PinholeCamera& camera, const ViewMeshDistanceOptions& options) {
  checkInputs(mesh, face_origin, true_depth_m, options);
  std::vector<std::size_t> mesh_face;
  const std::vector<Triangle> mesh_triangles = triangles(mesh, &mesh_face);
  const std::vector<Triangle> truth_triangles = triangles(truth, nullptr);
  if (mesh_triangles.empty()) throw std::invalid_argument("measureViewMeshDistances: the mesh has no area");
  if (truth_triangles.empty()) throw std::invalid_argument("measureViewMeshDistances: the truth has no area");

  const std::size_t bands = options.depth_band_edges_m.size() + 1;
  ViewMeshDistances out;
  out.by_depth.assign(bands, DistancePart{});
  out.truth_covered_by_depth.assign(bands, 0.0);
  out.truth_pixels_by_depth.assign(bands, 0);
  const TriangleParts parts = triangleParts(mesh_triangles, mesh_face, face_origin, options.depth_band_edges_m, out);
  std::mt19937_64 random(options.seed);
  sampleMeshToTruth(mesh_triangles, parts, truth_triangles, options.samples, random, out);
  if (!true_depth_m.empty()) measureTruthCoverage(mesh_triangles, true_depth_m, camera, options, random, out);
  return out;
}

}  // namespace solo
