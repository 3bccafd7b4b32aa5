#include <solo/render/ray_caster.h>

#include "test_support.h"

#include <cmath>

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
