// White-box tests of the path tracer's per-slot face data (render/src/slot_shading.h).
#include "slot_shading.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <cmath>
#include <random>
#include <vector>

namespace {

double angleBetween(const Eigen::Vector3f& a, const Eigen::Vector3f& b) {
  return std::atan2(a.cast<double>().cross(b.cast<double>()).norm(), a.cast<double>().dot(b.cast<double>()));
}

}  // namespace

// The octahedral pair gives back the unit vector within single precision everywhere: poles,
// the equator (z = 0, where the lower hemisphere's fold begins), the fold's edges and corners
// (x = 0 or y = 0 with z < 0), and random directions.
TEST(SlotShading, OctahedralRoundTripKeepsTheDirection) {
  std::vector<Eigen::Vector3f> directions = {
      {0, 0, 1},  {0, 0, -1}, {1, 0, 0},  {-1, 0, 0}, {0, 1, 0},
      {0, -1, 0}, Eigen::Vector3f(1, 1, 0).normalized(), Eigen::Vector3f(-1, 0, -1e-7f).normalized(),
      Eigen::Vector3f(0, -1, -1).normalized(), Eigen::Vector3f(1e-7f, 1e-7f, -1).normalized()};
  std::mt19937 rng(5);
  std::normal_distribution<float> g(0.f, 1.f);
  for (int i = 0; i < 100000; ++i) directions.push_back(Eigen::Vector3f(g(rng), g(rng), g(rng)).normalized());
  double worst = 0;
  for (const Eigen::Vector3f& d : directions) {
    const Eigen::Vector3f back = solo::decodeOctahedral(solo::encodeOctahedral(d));
    EXPECT_NEAR(back.norm(), 1.f, 1e-6f);
    worst = std::max(worst, angleBetween(back, d));
  }
  EXPECT_LT(worst, 1e-6);  // radians
  // The code itself: components in [-1, 1], the upper hemisphere inside |x| + |y| <= 1.
  const Eigen::Vector2f up = solo::encodeOctahedral(Eigen::Vector3f(0.6f, 0, 0.8f));
  EXPECT_NEAR(up.x(), 0.6f / 1.4f, 1e-7f);
  EXPECT_NEAR(up.y(), 0.f, 1e-7f);
  const Eigen::Vector2f down = solo::encodeOctahedral(Eigen::Vector3f(0.6f, 0, -0.8f));
  EXPECT_NEAR(down.x(), 1.f, 1e-7f);  // folded: (1 - |y|) sign(x), (1 - |x|) sign(y)
  EXPECT_NEAR(down.y(), 1.f - 0.6f / 1.4f, 1e-7f);
}

// Each slot carries its own triangle's reflectance, roughness, emitter, emissive index and
// normal, whichever half of a quad it is; a sliver whose cross product underflows in single
// precision still gets its true normal.
TEST(SlotShading, EachSlotCarriesItsTrianglesData) {
  solo::RenderScene scene;
  scene.vertices = {{0, 0, 5}, {1, 0, 5}, {1, 1, 6}, {0, 1, 5},  // a bent quad: two normals
                    {0, 0, 0}, {1, 0, 0}, {0.5f, 0, 1e-25f}};     // a sliver in the plane y = 0
  scene.faces = {{0, 1, 2}, {0, 2, 3}, {4, 5, 6}};
  scene.face_reflectance = {{0.1f, 0.2f, 0.3f}, {0.4f, 0.5f, 0.6f}, {0.7f, 0.8f, 0.9f}};
  scene.face_roughness = {0.25f, 0.75f, 1.f};
  scene.face_emitter = {-1, 0, -1};
  const std::vector<int> face_to_emissive = {-1, 3, -1};
  const std::vector<std::uint32_t> slot_triangles = {1, 0, 2, 2};  // the lone sliver in both halves
  const std::vector<solo::QuadShading> table = solo::buildSlotShading(scene, slot_triangles, face_to_emissive);
  ASSERT_EQ(table.size(), 2u);
  EXPECT_EQ(reinterpret_cast<std::uintptr_t>(table.data()) % 64, 0u) << "a quad's two slots share one cache line";
  for (std::uint32_t slot = 0; slot < 4; ++slot) {
    const std::uint32_t face = slot_triangles[slot];
    const solo::SlotShading& s = solo::slotShading(table, slot);
    EXPECT_EQ(s.reflectance, scene.face_reflectance[face]) << "slot " << slot;
    EXPECT_EQ(s.roughness, scene.face_roughness[face]);
    EXPECT_EQ(s.emitter, scene.face_emitter[face]);
    EXPECT_EQ(s.emissive, face_to_emissive[face]);
  }
  const auto normal = [&](std::uint32_t slot) { return solo::decodeOctahedral(solo::slotShading(table, slot).normal); };
  EXPECT_LT(angleBetween(normal(1), Eigen::Vector3f(0, -1, 1).normalized()), 1e-6);  // face 0: (1,0,0) x (1,1,1)
  EXPECT_LT(angleBetween(normal(0), Eigen::Vector3f(-1, 0, 1).normalized()), 1e-6);  // face 1: (1,1,1) x (0,1,0)
  EXPECT_LT(angleBetween(normal(2), Eigen::Vector3f(0, -1, 0)), 1e-6);
  EXPECT_LT(angleBetween(normal(3), Eigen::Vector3f(0, -1, 0)), 1e-6);

  // Without a roughness map every slot reads 0.5 (Burley's diffuse default); without emitters, -1.
  scene.face_roughness.clear();
  scene.face_emitter.clear();
  const std::vector<solo::QuadShading> plain = solo::buildSlotShading(scene, slot_triangles, {-1, -1, -1});
  for (std::uint32_t slot = 0; slot < 4; ++slot) {
    EXPECT_EQ(solo::slotShading(plain, slot).roughness, 0.5f);
    EXPECT_EQ(solo::slotShading(plain, slot).emitter, -1);
  }
  EXPECT_THROW(solo::buildSlotShading(scene, {0, 1, 5, 5}, {-1, -1, -1}), std::invalid_argument);
}

// A shading normal replaces the face's own normal in its slot; a zero or non-finite one, or a
// face beyond the list's end, keeps the face's.
TEST(SlotShading, AShadingNormalReplacesTheFacesOwn) {
  solo::RenderScene scene;
  scene.vertices = {{0, 0, 5}, {1, 0, 5}, {0, 1, 5}};  // normal (0, 0, 1)
  scene.faces = {{0, 1, 2}, {0, 1, 2}, {0, 1, 2}, {0, 1, 2}};
  scene.face_reflectance.assign(4, Eigen::Vector3f::Constant(0.5f));
  const Eigen::Vector3f tilted = Eigen::Vector3f(0.f, -0.6f, -0.8f);
  scene.face_shading_normal = {tilted * 2.f, Eigen::Vector3f::Zero(),
                               Eigen::Vector3f(std::nanf(""), 0.f, 1.f)};
  const std::vector<solo::QuadShading> table =
      solo::buildSlotShading(scene, {0, 1, 2, 3}, std::vector<int>(4, -1));
  EXPECT_LT(angleBetween(solo::decodeOctahedral(table[0].half[0].normal), tilted), 1e-6);
  for (const auto& s : {table[0].half[1], table[1].half[0], table[1].half[1]})
    EXPECT_LT(angleBetween(solo::decodeOctahedral(s.normal), Eigen::Vector3f::UnitZ()), 1e-6);
}
