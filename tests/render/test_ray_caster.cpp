#include <solo/render/ray_caster.h>

#include "test_support.h"

#include <Eigen/Geometry>

#include <array>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

namespace {
// Unit square in the plane z = 5, x and y in [-1, 1], two triangles.
solo::RayCaster squareAtZ5() {
  return solo::RayCaster({-1, -1, 5, 1, -1, 5, 1, 1, 5, -1, 1, 5}, {0, 1, 2, 0, 2, 3});
}
}  // namespace

TEST(RayCaster, HitDistanceMatchesThePlaneEquation) {
  const solo::RayCaster caster = squareAtZ5();
  EXPECT_EQ(caster.triangleCount(), 2u);
  const solo::RayHit straight = caster.intersect({0.2f, 0.1f, 0}, {0, 0, 1});
  ASSERT_TRUE(straight.hit);
  EXPECT_FLOAT_EQ(straight.distance, 5.f);
  // The geometric normal of the counter-clockwise square points along +z.
  EXPECT_GT(straight.geometric_normal.z(), 0.f);
  EXPECT_FLOAT_EQ(straight.geometric_normal.x(), 0.f);

  // Oblique unit direction: t = 5 / cos(theta).
  const Eigen::Vector3f d = Eigen::Vector3f(0.1f, 0.1f, 1.f).normalized();
  const solo::RayHit oblique = caster.intersect({0, 0, 0}, d);
  ASSERT_TRUE(oblique.hit);
  EXPECT_NEAR(oblique.distance, 5.f / d.z(), 1e-5);
}

TEST(RayCaster, MissesAndRangeLimits) {
  const solo::RayCaster caster = squareAtZ5();
  EXPECT_FALSE(caster.intersect({3, 0, 0}, {0, 0, 1}).hit) << "outside the square";
  EXPECT_FALSE(caster.intersect({0, 0, 0}, {0, 0, -1}).hit) << "behind the origin";
  EXPECT_FALSE(caster.intersect({0, 0, 0}, {0, 0, 1}, 0.f, 4.9f).hit) << "beyond t_far";
  EXPECT_TRUE(caster.occluded({0, 0, 0}, {0, 0, 1}, 0.f, 5.1f));
  EXPECT_FALSE(caster.occluded({0, 0, 0}, {0, 0, 1}, 0.f, 4.9f));
}

TEST(RayCaster, RejectsOutOfRangeIndices) {
  EXPECT_THROW(solo::RayCaster({0, 0, 0, 1, 0, 0, 0, 1, 0}, {0, 1, 3}), std::invalid_argument);
  EXPECT_THROW(solo::RayCaster({0, 0}, {}), std::invalid_argument);
}

TEST(RayCaster, EmptySceneNeverHits) {
  const solo::RayCaster caster({}, {});
  EXPECT_FALSE(caster.intersect({0, 0, 0}, {0, 0, 1}).hit);
}

namespace {
// Closest hit by brute force (Moeller-Trumbore, double precision): triangle index, t, and the
// barycentrics of its vertices 1 and 2; triangle -1 when nothing is hit.
struct BruteHit {
  int triangle = -1;
  double t = 0, u = 0, v = 0;
};
BruteHit bruteForce(const std::vector<float>& p, const std::vector<std::uint32_t>& tri, const Eigen::Vector3d& o,
                    const Eigen::Vector3d& d) {
  BruteHit best;
  best.t = std::numeric_limits<double>::infinity();
  const auto vertex = [&](std::uint32_t i) { return Eigen::Vector3d(p[3 * i], p[3 * i + 1], p[3 * i + 2]); };
  for (std::size_t f = 0; f < tri.size() / 3; ++f) {
    const Eigen::Vector3d a = vertex(tri[3 * f]), e1 = vertex(tri[3 * f + 1]) - a, e2 = vertex(tri[3 * f + 2]) - a;
    const Eigen::Vector3d q = d.cross(e2);
    const double det = e1.dot(q);
    if (std::abs(det) < 1e-12) continue;
    const Eigen::Vector3d s = o - a;
    const double u = s.dot(q) / det, v = d.dot(s.cross(e1)) / det, t = e2.dot(s.cross(e1)) / det;
    if (u < 0 || v < 0 || u + v > 1 || t <= 0 || t >= best.t) continue;
    best = {static_cast<int>(f), t, u, v};
  }
  return best;
}
}  // namespace

// The caster hands edge-sharing triangle pairs to Embree as quads. Whatever the pairing (a
// pixel-quad pair in either diagonal and vertex order, a lone triangle, a pair with flipped
// orientation that must not be merged), a hit reports the input triangle, its barycentrics and
// its own geometric normal, as brute force finds them.
TEST(RayCaster, TrianglePairsGivenAsQuadsReportTheInputTriangle) {
  // A bumpy 6x4 height field, z = 5 + 0.3 sin(x) cos(y): pixel quads split along alternating
  // diagonals, the vertex order of each triangle rotated, every fifth pair's second triangle
  // flipped, and a lone triangle at the end.
  std::vector<float> p;
  const int nx = 7, ny = 5;
  for (int y = 0; y < ny; ++y)
    for (int x = 0; x < nx; ++x)
      p.insert(p.end(), {x - 3.f, y - 2.f, 5.f + 0.3f * std::sin(1.3f * x) * std::cos(0.9f * y)});
  std::vector<std::uint32_t> tri;
  int pair = 0;
  const auto push = [&](std::array<std::uint32_t, 3> t, int rotation) {
    for (int k = 0; k < 3; ++k) tri.push_back(t[static_cast<std::size_t>((k + rotation) % 3)]);
  };
  for (int y = 0; y + 1 < ny; ++y)
    for (int x = 0; x + 1 < nx; ++x, ++pair) {
      const auto id = [&](int i, int j) { return static_cast<std::uint32_t>(j * nx + i); };
      std::array<std::uint32_t, 3> first, second;
      if (pair % 2 == 0) {
        first = {id(x, y), id(x + 1, y), id(x + 1, y + 1)};
        second = {id(x, y), id(x + 1, y + 1), id(x, y + 1)};
      } else {
        first = {id(x, y), id(x + 1, y), id(x, y + 1)};
        second = {id(x + 1, y), id(x + 1, y + 1), id(x, y + 1)};
      }
      if (pair % 5 == 4) std::swap(second[1], second[2]);
      push(first, pair % 3);
      push(second, (pair + 1) % 3);
    }
  p.insert(p.end(), {-3.f, -2.f, 3.f, -2.f, -2.f, 3.f, -3.f, -1.f, 3.f});  // the lone triangle, nearer
  const auto lone = static_cast<std::uint32_t>(nx * ny);
  tri.insert(tri.end(), {lone, lone + 1, lone + 2});

  const solo::RayCaster caster(p, tri);
  EXPECT_EQ(caster.triangleCount(), tri.size() / 3);
  // 24 pixel quads: 20 pairs become quads; the 4 flipped pairs and the lone triangle stay
  // single (a flipped triangle's edges run the same way as its neighbours').
  EXPECT_EQ(caster.primitiveCount(), 20u + 4u * 2u + 1u);
  // Slots: both halves of each quad; a single triangle fills both halves of its own.
  const std::vector<std::uint32_t> slots = caster.slotTriangles();
  ASSERT_EQ(slots.size(), caster.slotCount());
  ASSERT_EQ(slots.size(), 2 * caster.primitiveCount());
  std::vector<int> seen(tri.size() / 3, 0);
  for (std::size_t k = 0; k < slots.size(); k += 2) {
    ++seen[slots[k]];
    if (slots[k + 1] != slots[k]) ++seen[slots[k + 1]];
  }
  for (std::size_t t = 0; t < seen.size(); ++t) EXPECT_EQ(seen[t], 1) << "triangle " << t << " in one quad";
  EXPECT_EQ(slots[slots.size() - 1], tri.size() / 3 - 1);  // the lone triangle, in both halves
  EXPECT_EQ(slots[slots.size() - 2], tri.size() / 3 - 1);
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> spread(-3.2f, 3.2f), height(-2.2f, 2.2f);
  int hits = 0, second_halves = 0;
  for (int i = 0; i < 4000; ++i) {
    const Eigen::Vector3f target(spread(rng), height(rng), 5.f);
    const Eigen::Vector3f origin(0.1f * spread(rng), 0.1f * height(rng), -1.f);
    const Eigen::Vector3f d = (target - origin).normalized();
    const solo::RayHit hit = caster.intersect(origin, d);
    const BruteHit truth = bruteForce(p, tri, origin.cast<double>(), d.cast<double>());
    ASSERT_EQ(hit.hit, truth.triangle >= 0) << "ray " << i;
    const solo::SlotHit slot_hit = caster.intersectSlot(origin, d);
    ASSERT_EQ(slot_hit.hit, hit.hit) << "ray " << i;
    if (!hit.hit) continue;
    ++hits;
    EXPECT_EQ(slot_hit.distance, hit.distance) << "ray " << i;
    ASSERT_LT(slot_hit.slot, slots.size());
    EXPECT_EQ(slots[slot_hit.slot], hit.triangle) << "ray " << i;  // the slot's triangle, even on an edge
    if (std::abs(truth.u + truth.v - 1) < 1e-4 || truth.u < 1e-4 || truth.v < 1e-4) continue;  // on an edge
    ASSERT_EQ(static_cast<int>(hit.triangle), truth.triangle) << "ray " << i;
    second_halves += hit.triangle % 2 == 1 && hit.triangle + 1 != tri.size() / 3;
    EXPECT_NEAR(hit.distance, truth.t, 1e-4);
    EXPECT_NEAR(hit.u, truth.u, 1e-4);
    EXPECT_NEAR(hit.v, truth.v, 1e-4);
    const auto vertex = [&](std::uint32_t k) { return Eigen::Vector3f(p[3 * k], p[3 * k + 1], p[3 * k + 2]); };
    const std::uint32_t* f = &tri[3 * hit.triangle];
    const Eigen::Vector3f normal = (vertex(f[1]) - vertex(f[0])).cross(vertex(f[2]) - vertex(f[0]));
    EXPECT_GT(hit.geometric_normal.normalized().dot(normal.normalized()), 0.9999f) << "ray " << i;
  }
  EXPECT_GT(hits, 3000);
  EXPECT_GT(second_halves, 1000);
}
