#include "solo/render/light_sampler.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <map>
#include <stdexcept>
#include <unordered_map>
#include <utility>

namespace solo {
namespace {

// Flux of a two-sided emitter of radiance L and area A per unit L: 2 sides * pi * A, times
// the profile's share: int g(mu) mu dmu / int mu dmu = (4 / pi^2) / (1 / 2) = 8 / pi^2 for the
// cosine lobe; for a beam toward the camera (one side), 2 pi / (k + 2) |n.a| over 2 pi, with
// |n.a| floored at kBeamMinFacing (a face seen edge-on still sends half its beam past its edge).
constexpr float kPi = 3.14159265358979f;
constexpr float kProfileFluxShare = 8.f / (kPi * kPi);
constexpr float kBeamMinFacing = 0.1f;

float profileFluxShare(const Emitter& emitter, const EmissiveTriangle& t) {
  switch (emitter.profile) {
    case EmitterProfile::CosineLobe: return kProfileFluxShare;
    case EmitterProfile::TowardCamera: {
      const Eigen::Vector3f centroid = (t.p0 + t.p1 + t.p2) / 3.f;
      const float distance = centroid.norm();
      const float facing = distance > 0.f ? std::abs(t.normal.dot(centroid)) / distance : 1.f;
      return std::max(facing, kBeamMinFacing) / (emitter.beam_exponent + 2.f);
    }
    case EmitterProfile::Uniform: break;
  }
  return 1.f;
}

class UniformSampler final : public LightSampler {
 public:
  explicit UniformSampler(std::size_t count) : count_(count) {}
  int pick(const Eigen::Vector3f&, const Eigen::Vector3f&, float u, float* pmf) const override {
    if (count_ == 0) return -1;
    *pmf = 1.f / static_cast<float>(count_);
    return std::min(static_cast<int>(u * static_cast<float>(count_)), static_cast<int>(count_) - 1);
  }
  float pmf(const Eigen::Vector3f&, const Eigen::Vector3f&, int) const override {
    return count_ ? 1.f / static_cast<float>(count_) : 0.f;
  }

 private:
  std::size_t count_;
};

// Picks in proportion to power in constant time with Walker's alias table (built by Vose's
// method): u selects a column, its fraction decides between the column's triangle and its alias.
// A binary search over a cumulative table of 200 000 triangles missed the cache at every step
// (5 % of a 1080p night render's time in a profile).
class PowerSampler final : public LightSampler {
 public:
  explicit PowerSampler(const std::vector<EmissiveTriangle>& triangles) {
    const std::size_t n = triangles.size();
    double total = 0;
    for (const auto& t : triangles) total += t.power;
    if (n == 0 || !(total > 0)) return;
    pmf_.reserve(n);
    for (const auto& t : triangles) pmf_.push_back(static_cast<float>(t.power / total));
    columns_.resize(n);
    std::vector<double> scaled(n);
    std::vector<std::uint32_t> small, large;
    for (std::size_t i = 0; i < n; ++i) {
      scaled[i] = triangles[i].power / total * static_cast<double>(n);
      (scaled[i] < 1.0 ? small : large).push_back(static_cast<std::uint32_t>(i));
    }
    while (!small.empty() && !large.empty()) {
      const std::uint32_t s = small.back(), l = large.back();
      small.pop_back();
      columns_[s] = {static_cast<float>(scaled[s]), l};
      scaled[l] -= 1.0 - scaled[s];
      if (scaled[l] < 1.0) {
        large.pop_back();
        small.push_back(l);
      }
    }
    for (const std::uint32_t i : large) columns_[i] = {1.f, i};  // rounding leftovers: full columns
    for (const std::uint32_t i : small) columns_[i] = {1.f, i};
    for (std::size_t i = 0; i < n; ++i) {  // both probabilities in the column: one cache line per pick
      columns_[i].own_pmf = pmf_[i];
      columns_[i].alias_pmf = pmf_[columns_[i].alias];
    }
  }
  void prefetch(float u) const override {
    if (!columns_.empty()) __builtin_prefetch(&columns_[columnOf(scaledOf(u))]);
  }
  int pick(const Eigen::Vector3f&, const Eigen::Vector3f&, float u, float* pmf) const override {
    if (columns_.empty()) return -1;
    const double scaled = scaledOf(u);
    const std::size_t column = columnOf(scaled);
    const Column& c = columns_[column];
    const bool own = scaled - static_cast<double>(column) < c.keep;
    *pmf = own ? c.own_pmf : c.alias_pmf;
    return static_cast<int>(own ? column : c.alias);
  }
  float pmf(const Eigen::Vector3f&, const Eigen::Vector3f&, int triangle) const override {
    return pmf_.empty() ? 0.f : pmf_[static_cast<std::size_t>(triangle)];
  }

 private:
  // u in [0, 1) scaled to the columns: its integer part picks the column, its fraction decides.
  double scaledOf(float u) const { return static_cast<double>(u) * static_cast<double>(columns_.size()); }
  std::size_t columnOf(double scaled) const { return std::min(static_cast<std::size_t>(scaled), columns_.size() - 1); }
  struct Column {
    float keep = 1.f;         // probability of the column's own triangle
    std::uint32_t alias = 0;  // the other triangle
    float own_pmf = 0.f, alias_pmf = 0.f;  // their probabilities of being picked at all
  };
  std::vector<Column> columns_;
  std::vector<float> pmf_;
};

// What importance() reads of a cluster of emitting triangles, computed once: the bounding
// sphere of its box (a tree traversal evaluates two per level; this saves a square root and
// memory traffic each) and its power.
struct Sphere {
  Eigen::Vector3f centre;
  float radius, radius2, power;
};

// How much a cluster may light a shading point at p with normal n: power * (bound on the
// receiver's cosine over the sphere) / (squared distance to the centre, floored by the radius).
float importance(const Sphere& node, const Eigen::Vector3f& p, const Eigen::Vector3f& n) {
  const float radius = node.radius;
  const Eigen::Vector3f to_centre = node.centre - p;
  const float distance2 = to_centre.squaredNorm();
  float cosine_bound = 1.f;
  if (distance2 > node.radius2) {
    // cos(max(0, theta - theta_box)) without trigonometric calls: theta is the angle between
    // n and the direction to the centre, theta_box the box's angular radius.
    const float inv_distance = 1.f / std::sqrt(distance2);
    const float cos_theta = std::clamp(n.dot(to_centre) * inv_distance, -1.f, 1.f);
    const float sin_box = std::min(1.f, radius * inv_distance);
    const float cos_box = std::sqrt(std::max(0.f, 1.f - sin_box * sin_box));
    if (cos_theta < cos_box) {
      const float sin_theta = std::sqrt(std::max(0.f, 1.f - cos_theta * cos_theta));
      cosine_bound = std::max(0.f, cos_theta * cos_box + sin_theta * sin_box);
    }
  }
  return node.power * cosine_bound / std::max(distance2, std::max(node.radius2, 1e-8f));
}

// The entry of order[first, first + count) whose running share (cumulative, same positions,
// the last 1) first exceeds u in [0, 1): a pick in proportion to the shares.
int pickByRunningShare(const std::vector<float>& cumulative, const std::vector<int>& order, int first, int count,
                       float u) {
  const auto begin = cumulative.begin() + first, end = begin + count;
  const auto at = std::min(std::upper_bound(begin, end, u), end - 1);
  return order[static_cast<std::size_t>(at - cumulative.begin())];
}

// Leaves of the hierarchy: the triangles of one emitter within a bounding sphere of at most this
// radius, picked among themselves in proportion to power. Seen from farther than a few radii, a
// cluster's triangles differ little in distance and orientation; a tree down to single
// triangles spends most of its steps (17 on the 1080p street's 188 000) telling them apart.
constexpr float kLeafRadiusM = 0.25f;

// A binary hierarchy over clusters of emitting triangles. Each node stores its bounds and power;
// the branch probability at a shading point is proportional to power * (bound on the receiver's
// cosine) / (squared distance, floored by the node's size). In a leaf (one emitter's triangles
// within kLeafRadiusM) a triangle is picked in proportion to its power.
class HierarchySampler final : public LightSampler {
 public:
  explicit HierarchySampler(const std::vector<EmissiveTriangle>& triangles) {
    if (triangles.empty()) return;
    order_.resize(triangles.size());
    std::iota(order_.begin(), order_.end(), 0);
    leaf_of_triangle_.assign(triangles.size(), -1);
    share_.assign(triangles.size(), 0.f);
    cumulative_.assign(triangles.size(), 0.f);
    nodes_.reserve(2 * triangles.size());
    build(triangles, 0, static_cast<int>(order_.size()), -1);
    children_.resize(nodes_.size());
    const auto code = [this](int child) {
      const int leaf = nodes_[static_cast<std::size_t>(child)].leaf;
      return leaf >= 0 ? -leaf - 1 : child;
    };
    for (std::size_t i = 0; i < nodes_.size(); ++i) {
      const Node& node = nodes_[i];
      if (node.leaf >= 0) continue;
      children_[i] = {sphereOf(nodes_[static_cast<std::size_t>(node.left)]), sphereOf(nodes_[static_cast<std::size_t>(node.right)]),
                      code(node.left), code(node.right)};
    }
  }

  int pick(const Eigen::Vector3f& p, const Eigen::Vector3f& n, float u, float* pmf) const override {
    if (nodes_.empty()) return -1;
    float probability = 1.f;
    int code = nodes_[0].leaf >= 0 ? -nodes_[0].leaf - 1 : 0;  // a node's index, or -(leaf + 1)
    while (code >= 0) {
      const Children& c = children_[static_cast<std::size_t>(code)];
      const float a = importance(c.left_sphere, p, n);
      const float b = importance(c.right_sphere, p, n);
      if (!(a + b > 0.f)) return -1;
      const float pa = a / (a + b);
      if (u < pa) {
        u = std::min(u / pa, 0.99999994f);
        probability *= pa;
        code = c.left;
      } else {
        u = std::min((u - pa) / (1.f - pa), 0.99999994f);
        probability *= 1.f - pa;
        code = c.right;
      }
    }
    const int triangle = pickInLeaf(leaves_[static_cast<std::size_t>(-code - 1)], u);
    *pmf = probability * share_[static_cast<std::size_t>(triangle)];
    return triangle;
  }

  float pmf(const Eigen::Vector3f& p, const Eigen::Vector3f& n, int triangle) const override {
    int node = leaves_[static_cast<std::size_t>(leaf_of_triangle_[static_cast<std::size_t>(triangle)])].node;
    float probability = share_[static_cast<std::size_t>(triangle)];
    while (nodes_[static_cast<std::size_t>(node)].parent >= 0) {
      const int parent = nodes_[static_cast<std::size_t>(node)].parent;
      const Node& up = nodes_[static_cast<std::size_t>(parent)];
      const Children& c = children_[static_cast<std::size_t>(parent)];
      const float a = importance(c.left_sphere, p, n);
      const float b = importance(c.right_sphere, p, n);
      if (!(a + b > 0.f)) return 0.f;
      probability *= (node == up.left ? a : b) / (a + b);
      node = parent;
    }
    return probability;
  }

 private:
  struct Node {
    Eigen::AlignedBox3f bounds;
    float power = 0;
    int left = -1, right = -1, parent = -1;
    int leaf = -1;  // a leaf's index into leaves_
  };
  // A leaf's triangles: order_[first, first + count), with their cumulative power shares.
  struct Leaf {
    int first = 0, count = 0, node = 0;
  };

  // Per interior node, what a traversal step reads, in one cache line: both children's spheres
  // and where to go next (a child's index, or -(leaf + 1)).
  struct alignas(64) Children {
    Sphere left_sphere, right_sphere;
    int left, right;
  };

  static Sphere sphereOf(const Node& node) {
    const float radius = 0.5f * node.bounds.diagonal().norm();
    return {node.bounds.center(), radius, radius * radius, node.power};
  }

  // The leaf's triangle whose cumulative share first exceeds u (u in [0, 1)).
  int pickInLeaf(const Leaf& leaf, float u) const {
    return pickByRunningShare(cumulative_, order_, leaf.first, leaf.count, u);
  }

  // Whether order_[begin, end) makes a leaf: one triangle, or one emitter's within kLeafRadiusM.
  bool isLeaf(const std::vector<EmissiveTriangle>& tris, int begin, int end, const Eigen::AlignedBox3f& bounds) const {
    if (end - begin == 1) return true;
    if (0.5f * bounds.diagonal().norm() > kLeafRadiusM) return false;
    const std::uint32_t emitter = tris[static_cast<std::size_t>(order_[static_cast<std::size_t>(begin)])].emitter;
    for (int i = begin + 1; i < end; ++i)
      if (tris[static_cast<std::size_t>(order_[static_cast<std::size_t>(i)])].emitter != emitter) return false;
    return true;
  }

  // Records order_[begin, end) as the leaf of node `index`: each triangle's share of the leaf's
  // power and the running sum of the shares.
  void makeLeaf(const std::vector<EmissiveTriangle>& tris, int begin, int end, int index, Node& node) {
    node.leaf = static_cast<int>(leaves_.size());
    leaves_.push_back({begin, end - begin, index});
    float running = 0.f;
    for (int i = begin; i < end; ++i) {
      const auto t = static_cast<std::size_t>(order_[static_cast<std::size_t>(i)]);
      share_[t] = tris[t].power / node.power;
      running += share_[t];
      cumulative_[static_cast<std::size_t>(i)] = running;
      leaf_of_triangle_[t] = node.leaf;
    }
    cumulative_[static_cast<std::size_t>(end - 1)] = 1.f;  // rounding: the last one takes the rest
  }

  int build(const std::vector<EmissiveTriangle>& tris, int begin, int end, int parent) {
    const int index = static_cast<int>(nodes_.size());
    nodes_.push_back({});
    Node node;
    node.parent = parent;
    Eigen::AlignedBox3f centroids;
    for (int i = begin; i < end; ++i) {
      const EmissiveTriangle& t = tris[static_cast<std::size_t>(order_[static_cast<std::size_t>(i)])];
      node.bounds.extend(t.p0);
      node.bounds.extend(t.p1);
      node.bounds.extend(t.p2);
      centroids.extend((t.p0 + t.p1 + t.p2) / 3.f);
      node.power += t.power;
    }
    if (isLeaf(tris, begin, end, node.bounds)) {
      makeLeaf(tris, begin, end, index, node);
      nodes_[static_cast<std::size_t>(index)] = node;
      return index;
    }
    int axis = 0;
    centroids.diagonal().maxCoeff(&axis);
    const int middle = (begin + end) / 2;
    std::nth_element(order_.begin() + begin, order_.begin() + middle, order_.begin() + end, [&](int a, int b) {
      const auto& ta = tris[static_cast<std::size_t>(a)];
      const auto& tb = tris[static_cast<std::size_t>(b)];
      return (ta.p0 + ta.p1 + ta.p2)[axis] < (tb.p0 + tb.p1 + tb.p2)[axis];
    });
    nodes_[static_cast<std::size_t>(index)] = node;
    const int left = build(tris, begin, middle, index);
    const int right = build(tris, middle, end, index);
    nodes_[static_cast<std::size_t>(index)].left = left;
    nodes_[static_cast<std::size_t>(index)].right = right;
    return index;
  }

  std::vector<Node> nodes_;
  std::vector<Children> children_;  // per node (unused for leaves), see Children
  std::vector<Leaf> leaves_;
  std::vector<int> order_;            // triangle indices, each leaf's contiguous
  std::vector<float> cumulative_;     // per position in order_: running share within its leaf
  std::vector<float> share_;          // per triangle: its share of its leaf's power
  std::vector<int> leaf_of_triangle_;
};

// Near-field selection, over any sampler. A light sampler's estimate of what a cluster gives a
// shading point floors the squared distance by the cluster's squared radius (the hierarchy) or
// ignores distance (power): right for power spread through a wide node, wrong for a point a few
// centimetres from one small lamp. There the hierarchy gave a car light 0.36 m from a bounce
// vertex a probability of 8e-6 (street-s2-wide-sky), and the rare bounce that found the light
// carried 9 000 times its pixel's value. So a shading point with emitter clusters within
// kNearRadiusM weighs each by importance() times a bound on the emitter's cosine toward it,
// picks among them with probability kNearShare x T / (T + K) (T their summed weight, K the
// scene's total power over its squared radius), then a triangle in the cluster by power;
// otherwise it asks the base sampler. Its pmf is the mixture's, so the estimate stays unbiased.
// The clusters near a point are the ones listed for its cell of a grid of kNearCellM, built
// with every cluster whose sphere comes within kNearRadiusM of the cell.
constexpr float kNearRadiusM = 0.5f;
constexpr float kNearCellM = 0.5f;
constexpr float kNearShare = 0.5f;  // the largest probability of the near-field strategy
// Clusters: one emitter's triangles whose centroids share a cell of this size.
constexpr float kNearClusterCellM = 0.35f;
// Triangles wider than this are left to the base sampler: they would fill many cells, and a
// floor by their own radius already makes them important nearby.
constexpr float kNearMaxRadiusM = 2.f;
// At most this many clusters per cell (the most powerful), so that a shading point weighs few.
constexpr int kMaxNearClusters = 16;

// The directions a cluster's faces point in, up to sign: an axis and the cosine and sine of the
// largest angle between it and a face's normal (cos_spread 0: any direction).
struct Cone {
  Eigen::Vector3f axis = Eigen::Vector3f::UnitZ();
  float cos_spread = 0.f, sin_spread = 1.f;
};

class NearFieldSampler final : public LightSampler {
 public:
  NearFieldSampler(std::unique_ptr<LightSampler> base, const std::vector<EmissiveTriangle>& triangles)
      : base_(std::move(base)) {
    buildClusters(triangles);
    buildGrid();
    Eigen::AlignedBox3f all;
    double power = 0;
    for (const EmissiveTriangle& t : triangles) {
      all.extend(t.p0);
      all.extend(t.p1);
      all.extend(t.p2);
      power += t.power;
    }
    const double radius2 = std::max(0.25 * all.diagonal().squaredNorm(), 1e-4);
    if (!triangles.empty()) scale_ = static_cast<float>(power / radius2);
  }

  int pick(const Eigen::Vector3f& p, const Eigen::Vector3f& n, float u, float* pmf) const override {
    const Near near = nearClusters(p, n);
    if (!(near.chance > 0.f)) return base_->pick(p, n, u, pmf);
    int triangle = -1;
    float base_pmf = 0.f;
    if (u < near.chance) {
      u = std::min(u / near.chance, kOneMinus);
      const int cluster = near.pick(&u);
      triangle = pickInCluster(cluster, u);
      base_pmf = base_->pmf(p, n, triangle);
    } else {
      triangle = base_->pick(p, n, std::min((u - near.chance) / (1.f - near.chance), kOneMinus), &base_pmf);
      if (triangle < 0) return -1;
    }
    *pmf = near.chance * nearPmf(near, triangle) + (1.f - near.chance) * base_pmf;
    return triangle;
  }

  float pmf(const Eigen::Vector3f& p, const Eigen::Vector3f& n, int triangle) const override {
    const Near near = nearClusters(p, n);
    if (!(near.chance > 0.f)) return base_->pmf(p, n, triangle);
    return near.chance * nearPmf(near, triangle) + (1.f - near.chance) * base_->pmf(p, n, triangle);
  }

 private:
  static constexpr float kOneMinus = 0.99999994f;

  // The clusters listed for a shading point's cell, with their importance there.
  struct Near {
    const int* clusters = nullptr;
    int count = 0;
    float importance[kMaxNearClusters];
    float total = 0.f;
    float chance = 0.f;  // the probability of picking among them: kNearShare x total / (total + scale_)

    // The listed cluster u selects in proportion to importance; u is rescaled for reuse.
    int pick(float* u) const {
      const float target = *u * total;
      float running = 0.f;
      int chosen = -1;
      for (int k = 0; k < count; ++k) {
        if (!(importance[k] > 0.f)) continue;
        chosen = k;
        if (target < running + importance[k]) break;
        running += importance[k];
      }
      *u = std::clamp((target - running) / importance[chosen], 0.f, kOneMinus);
      return clusters[chosen];
    }
    float share(int cluster) const {
      for (int k = 0; k < count; ++k)
        if (clusters[k] == cluster) return importance[k] / total;
      return 0.f;
    }
  };

  Near nearClusters(const Eigen::Vector3f& p, const Eigen::Vector3f& n) const {
    Near near;
    if (cells_.empty() || !occupancy_.mayHold(p)) return near;
    const auto found = cells_.find(cellKey(p));
    if (found == cells_.end()) return near;
    near.clusters = cell_clusters_.data() + found->second.first;
    near.count = found->second.second;
    for (int k = 0; k < near.count; ++k) {
      const auto c = static_cast<std::size_t>(near.clusters[k]);
      near.importance[k] = importance(spheres_[c], p, n) * emitterCosineBound(cones_[c], spheres_[c], p);
      near.total += near.importance[k];
    }
    if (near.total > 0.f && std::isfinite(near.total)) near.chance = kNearShare * near.total / (near.total + scale_);
    return near;
  }

  // A bound on |cos| between a cluster's faces and the direction to p (two-sided emitters):
  // cos(max(0, theta - spread - theta_box)), theta the angle between the cluster's mean normal
  // and the direction from its centre, folded to [0, pi/2]. A window seen edge-on from its own
  // wall gets about radius / distance.
  static float emitterCosineBound(const Cone& cone, const Sphere& sphere, const Eigen::Vector3f& p) {
    const Eigen::Vector3f to_p = p - sphere.centre;
    const float distance2 = to_p.squaredNorm();
    if (!(distance2 > sphere.radius2)) return 1.f;
    const float inv_distance = 1.f / std::sqrt(distance2);
    const float cos_theta = std::min(1.f, std::abs(cone.axis.dot(to_p)) * inv_distance);
    const float sin_box = std::min(1.f, sphere.radius * inv_distance);
    const float cos_box = std::sqrt(std::max(0.f, 1.f - sin_box * sin_box));
    // cos and sin of spread + theta_box
    const float cos_open = cone.cos_spread * cos_box - cone.sin_spread * sin_box;
    const float sin_open = cone.sin_spread * cos_box + cone.cos_spread * sin_box;
    if (cos_theta >= cos_open || sin_open >= 1.f) return 1.f;
    const float sin_theta = std::sqrt(std::max(0.f, 1.f - cos_theta * cos_theta));
    return std::clamp(cos_theta * cos_open + sin_theta * sin_open, 0.f, 1.f);
  }

  // The probability that the near-field strategy picks `triangle`.
  float nearPmf(const Near& near, int triangle) const {
    const int cluster = cluster_of_[static_cast<std::size_t>(triangle)];
    return cluster < 0 ? 0.f : near.share(cluster) * share_[static_cast<std::size_t>(triangle)];
  }

  int pickInCluster(int cluster, float u) const {
    const auto [first, count] = ranges_[static_cast<std::size_t>(cluster)];
    return pickByRunningShare(cumulative_, order_, first, count, u);
  }

  static std::int64_t cellKey(const Eigen::Vector3f& p) { return cellKey(p, kNearCellM); }
  static std::int64_t cellKey(const Eigen::Vector3f& p, float cell_m) {
    const auto cell = [cell_m](float x) {
      const float c = std::floor(x / cell_m);  // written so that NaN lands on the lowest cell
      return static_cast<std::int64_t>(c > 1048575.f ? 1048575.f : (c > -1048575.f ? c : -1048575.f)) + 1048576;
    };
    return (cell(p.x()) << 42) | (cell(p.y()) << 21) | cell(p.z());
  }

  // Groups the triangles of radius at most kNearMaxRadiusM into clusters (one emitter, one cell
  // of kNearClusterCellM) with their bounding spheres and each triangle's share of its
  // cluster's power.
  void buildClusters(const std::vector<EmissiveTriangle>& tris) {
    std::map<std::pair<std::uint32_t, std::int64_t>, std::vector<int>> groups;
    for (std::size_t i = 0; i < tris.size(); ++i) {
      const EmissiveTriangle& t = tris[i];
      const Eigen::Vector3f centroid = (t.p0 + t.p1 + t.p2) / 3.f;
      const float radius2 = std::max({(t.p0 - centroid).squaredNorm(), (t.p1 - centroid).squaredNorm(),
                                      (t.p2 - centroid).squaredNorm()});
      if (!(radius2 <= kNearMaxRadiusM * kNearMaxRadiusM)) continue;
      groups[{t.emitter, cellKey(centroid, kNearClusterCellM)}].push_back(static_cast<int>(i));
    }
    cluster_of_.assign(tris.size(), -1);
    share_.assign(tris.size(), 0.f);
    for (const auto& [key, members] : groups) {
      Eigen::AlignedBox3f box;
      float power = 0.f;
      for (const int i : members) {
        const EmissiveTriangle& t = tris[static_cast<std::size_t>(i)];
        box.extend(t.p0);
        box.extend(t.p1);
        box.extend(t.p2);
        power += t.power;
      }
      if (!(power > 0.f)) continue;
      const int cluster = static_cast<int>(spheres_.size());
      const float radius = 0.5f * box.diagonal().norm();
      spheres_.push_back({box.center(), radius, radius * radius, power});
      cones_.push_back(coneOf(tris, members));
      ranges_.emplace_back(static_cast<int>(order_.size()), static_cast<int>(members.size()));
      float running = 0.f;
      for (const int i : members) {
        share_[static_cast<std::size_t>(i)] = tris[static_cast<std::size_t>(i)].power / power;
        running += share_[static_cast<std::size_t>(i)];
        cluster_of_[static_cast<std::size_t>(i)] = cluster;
        order_.push_back(i);
        cumulative_.push_back(running);
      }
      cumulative_.back() = 1.f;  // rounding: the last one takes the rest
    }
  }

  // The members' area-weighted mean normal, each normal's sign taken to agree with the first,
  // and the largest angle between a member's normal and that axis.
  static Cone coneOf(const std::vector<EmissiveTriangle>& tris, const std::vector<int>& members) {
    const Eigen::Vector3f first = tris[static_cast<std::size_t>(members.front())].normal;
    Eigen::Vector3f sum = Eigen::Vector3f::Zero();
    for (const int i : members) {
      const EmissiveTriangle& t = tris[static_cast<std::size_t>(i)];
      sum += (t.normal.dot(first) < 0.f ? -t.area : t.area) * t.normal;
    }
    Cone cone;
    if (!(sum.norm() > 0.f)) return cone;  // no axis: every direction allowed
    cone.axis = sum.normalized();
    float cos_spread = 1.f;
    for (const int i : members) cos_spread = std::min(cos_spread, std::abs(cone.axis.dot(tris[static_cast<std::size_t>(i)].normal)));
    cone.cos_spread = cos_spread;
    cone.sin_spread = std::sqrt(std::max(0.f, 1.f - cos_spread * cos_spread));
    return cone;
  }

  // Lists each cluster for the cells its sphere comes within kNearRadiusM of; a cell keeps its
  // kMaxNearClusters most powerful clusters.
  void buildGrid() {
    std::unordered_map<std::int64_t, std::vector<int>> cells;
    const Eigen::Vector3f half_cell = Eigen::Vector3f::Constant(0.5f * kNearCellM);
    for (std::size_t c = 0; c < spheres_.size(); ++c) {
      const Sphere& s = spheres_[c];
      const float reach = s.radius + kNearRadiusM;
      const Eigen::Vector3f lo = s.centre - Eigen::Vector3f::Constant(reach);
      const Eigen::Vector3f first = (lo / kNearCellM).array().floor().matrix() * kNearCellM;
      for (float x = first.x(); x <= s.centre.x() + reach; x += kNearCellM)
        for (float y = first.y(); y <= s.centre.y() + reach; y += kNearCellM)
          for (float z = first.z(); z <= s.centre.z() + reach; z += kNearCellM) {
            const Eigen::Vector3f cell_centre = Eigen::Vector3f(x, y, z) + half_cell;
            const float gap = ((s.centre - cell_centre).cwiseAbs() - half_cell).cwiseMax(0.f).norm();
            if (gap <= reach) {
              std::vector<int>& list = cells[cellKey(cell_centre)];
              if (list.empty()) occupancy_.centres.push_back(cell_centre);
              list.push_back(static_cast<int>(c));
            }
          }
    }
    occupancy_.build();
    cells_.reserve(cells.size());
    for (auto& [key, list] : cells) {
      if (static_cast<int>(list.size()) > kMaxNearClusters) {
        std::partial_sort(list.begin(), list.begin() + kMaxNearClusters, list.end(), [this](int a, int b) {
          return spheres_[static_cast<std::size_t>(a)].power > spheres_[static_cast<std::size_t>(b)].power;
        });
        list.resize(kMaxNearClusters);
      }
      cells_.emplace(key, std::make_pair(static_cast<int>(cell_clusters_.size()), static_cast<int>(list.size())));
      cell_clusters_.insert(cell_clusters_.end(), list.begin(), list.end());
    }
  }

  // Which cells list clusters, as bits over the box of those cells at a coarser cell
  // (kNearCellM x 2^level, at most 2^24 bits): most shading points are far from every emitter
  // and leave after one bit test instead of a hash lookup that misses the cache.
  struct Occupancy {
    std::vector<Eigen::Vector3f> centres;  // the listed cells' centres, while building
    Eigen::Vector3f origin = Eigen::Vector3f::Zero();
    Eigen::Vector3i dims = Eigen::Vector3i::Zero();
    float cell_m = kNearCellM;
    std::vector<std::uint64_t> bits;

    // Sets the bits of the cells whose centres were gathered in `centres`, then drops them.
    void build() {
      if (centres.empty()) return;
      Eigen::AlignedBox3f box;
      for (const Eigen::Vector3f& c : centres) box.extend(c);
      origin = box.min() - Eigen::Vector3f::Constant(0.5f * kNearCellM);
      const Eigen::Vector3f extent = box.max() - box.min() + Eigen::Vector3f::Constant(kNearCellM);
      for (cell_m = kNearCellM;; cell_m *= 2.f) {
        dims = (extent / cell_m).array().ceil().cast<int>().max(1).matrix();
        if (static_cast<double>(dims.x()) * dims.y() * dims.z() <= double(1 << 24)) break;
      }
      bits.assign((static_cast<std::size_t>(dims.x()) * dims.y() * dims.z() + 63) / 64, 0);
      for (const Eigen::Vector3f& c : centres) {
        const std::size_t i = index(c);
        bits[i / 64] |= std::uint64_t{1} << (i % 64);
      }
      centres.clear();
      centres.shrink_to_fit();
    }
    std::size_t index(const Eigen::Vector3f& p) const {
      const Eigen::Vector3i c = ((p - origin) / cell_m).array().floor().cast<int>().matrix();
      return (static_cast<std::size_t>(c.z()) * dims.y() + c.y()) * dims.x() + c.x();
    }
    bool mayHold(const Eigen::Vector3f& p) const {
      const Eigen::Vector3f q = (p - origin) / cell_m;  // NaN fails every comparison below
      if (!(q.x() >= 0.f && q.y() >= 0.f && q.z() >= 0.f && q.x() < dims.x() && q.y() < dims.y() && q.z() < dims.z()))
        return false;
      const std::size_t i = index(p);
      return (bits[i / 64] >> (i % 64)) & 1u;
    }
  };

  std::unique_ptr<LightSampler> base_;
  Occupancy occupancy_;
  // The scale a near cluster's importance is weighed against: the importance of all the
  // scene's emitters from a point inside their bounding sphere, total power / radius^2.
  float scale_ = 0.f;
  std::vector<Sphere> spheres_;                // per cluster
  std::vector<Cone> cones_;                    // per cluster
  std::vector<std::pair<int, int>> ranges_;    // per cluster: its range of order_
  std::vector<int> order_;                     // triangle indices, each cluster's contiguous
  std::vector<float> cumulative_;              // per position in order_: running share in its cluster
  std::vector<float> share_;                   // per triangle: its share of its cluster's power
  std::vector<int> cluster_of_;                // per triangle: its cluster, or -1
  // Per cell key: the range of cell_clusters_ that lists its clusters.
  std::unordered_map<std::int64_t, std::pair<int, int>> cells_;
  std::vector<int> cell_clusters_;
};

}  // namespace

const char* lightSamplerName(LightSamplerKind kind) {
  switch (kind) {
    case LightSamplerKind::Uniform: return "uniform";
    case LightSamplerKind::Power: return "power";
    case LightSamplerKind::Hierarchy: return "hierarchy";
  }
  return "hierarchy";
}

LightSamplerKind lightSamplerFromName(const std::string& name) {
  for (LightSamplerKind k : {LightSamplerKind::Uniform, LightSamplerKind::Power, LightSamplerKind::Hierarchy})
    if (name == lightSamplerName(k)) return k;
  throw std::invalid_argument("unknown light sampler \"" + name + "\" (uniform, power, hierarchy)");
}

std::vector<EmissiveTriangle> collectEmissiveTriangles(const RenderScene& scene) {
  std::vector<EmissiveTriangle> out;
  if (scene.face_emitter.empty()) return out;
  for (std::size_t f = 0; f < scene.faces.size(); ++f) {
    const int e = scene.face_emitter[f];
    if (e < 0) continue;
    const Emitter& emitter = scene.emitters[static_cast<std::size_t>(e)];
    const float luminance = emitter.radiance.y();
    if (!(emitter.radiance.maxCoeff() > 0.f) || !std::isfinite(emitter.radiance.sum())) continue;
    EmissiveTriangle t;
    t.face = static_cast<std::uint32_t>(f);
    t.emitter = static_cast<std::uint32_t>(e);
    t.p0 = scene.vertices[scene.faces[f][0]];
    t.p1 = scene.vertices[scene.faces[f][1]];
    t.p2 = scene.vertices[scene.faces[f][2]];
    const Eigen::Vector3f cross = (t.p1 - t.p0).cross(t.p2 - t.p0);
    t.area = 0.5f * cross.norm();
    if (!(t.area > 0.f) || !std::isfinite(t.area)) continue;
    t.normal = cross.normalized();
    t.power = std::max(luminance, 1e-3f * emitter.radiance.maxCoeff()) * t.area * 2.f * kPi *
              profileFluxShare(emitter, t);
    out.push_back(t);
  }
  return out;
}

std::unique_ptr<LightSampler> makeLightSampler(LightSamplerKind kind, const std::vector<EmissiveTriangle>& triangles,
                                               bool near_field) {
  std::unique_ptr<LightSampler> base;
  switch (kind) {
    case LightSamplerKind::Uniform: base = std::make_unique<UniformSampler>(triangles.size()); break;
    case LightSamplerKind::Power: base = std::make_unique<PowerSampler>(triangles); break;
    case LightSamplerKind::Hierarchy: base = std::make_unique<HierarchySampler>(triangles); break;
  }
  if (!near_field || !base) return base;
  return std::make_unique<NearFieldSampler>(std::move(base), triangles);
}

}  // namespace solo
