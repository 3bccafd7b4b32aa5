// Solid-angle sampling of triangles against closed forms: the octant's solid angle, Lambert's
// polygon irradiance, and the share of samples in each quarter of a near, oblique triangle.

#include <solo/render/spherical_triangle.h>

#include "rectangle_irradiance.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <random>

namespace {

constexpr double kPi = 3.14159265358979323846;
using Eigen::Vector3d;

// Ray from `origin` along `direction` against triangle (a, b, c): barycentric (b, c) weights and
// distance, Moller-Trumbore; false when the ray misses by more than `slack` in barycentrics.
bool hitsTriangle(const Vector3d& origin, const Vector3d& direction, const Vector3d& a, const Vector3d& b,
                  const Vector3d& c, double slack) {
  const Vector3d e1 = b - a, e2 = c - a, p = direction.cross(e2);
  const double det = e1.dot(p);
  if (std::abs(det) < 1e-300) return false;
  const Vector3d s = origin - a;
  const double u = s.dot(p) / det;
  const Vector3d q = s.cross(e1);
  const double v = direction.dot(q) / det, t = e2.dot(q) / det;
  return t > 0 && u >= -slack && v >= -slack && u + v <= 1 + slack;
}

TEST(SphericalTriangle, OctantSubtendsAnEighthOfTheSphere) {
  const Vector3d o(0, 0, 0), a(1, 0, 0), b(0, 1, 0), c(0, 0, 1);
  EXPECT_NEAR(solo::triangleSolidAngle(o, a, b, c), kPi / 2, 1e-12);
  EXPECT_NEAR(solo::triangleSolidAngle(o, a, c, b), kPi / 2, 1e-12);  // either orientation
  EXPECT_NEAR(solo::triangleSolidAngle(o, 5 * a, 2 * b, 0.1 * c), kPi / 2, 1e-12);  // only directions count
}

TEST(SphericalTriangle, FarTriangleSubtendsAreaTimesCosineOverDistanceSquared) {
  // A 1 cm triangle 10 m away, tilted 60 degrees: area cos / d^2 to 1e-6 relative.
  const Vector3d p(0, 0, 0), centre(0, 0, 10);
  const Vector3d normal(std::sin(kPi / 3), 0, std::cos(kPi / 3));
  const Vector3d t = Vector3d::UnitY(), s = normal.cross(t);
  const Vector3d a = centre + 0.01 * s, b = centre + 0.01 * t, c = centre - 0.01 * s;
  const double area = 0.5 * (b - a).cross(c - a).norm();
  EXPECT_NEAR(solo::triangleSolidAngle(p, a, b, c), area * 0.5 / 100, 1e-6 * area * 0.5 / 100);
}

TEST(SphericalTriangle, PointInThePlaneSeesNothingAndSamplingRefuses) {
  const Vector3d a(0, 0, 0), b(1, 0, 0), c(0, 1, 0), p(2, 2, 0);
  EXPECT_EQ(solo::triangleSolidAngle(p, a, b, c), 0.0);
  Vector3d w(7, 7, 7);
  EXPECT_FALSE(solo::sampleSphericalTriangle(p, a, b, c, 0.3, 0.6, &w));
  EXPECT_EQ(w, Vector3d(7, 7, 7));
  EXPECT_FALSE(solo::sampleSphericalTriangle(p, a, a, c, 0.3, 0.6, &w));  // degenerate
}

// A triangle 2 cm above a point near its corner: the case that makes area sampling blow up.
struct NearTriangle {
  Vector3d p{0.01, 0.01, 0}, a{0, 0, 0.02}, b{1.5, 0, 0.3}, c{0, 0.8, 0.02};
};

TEST(SphericalTriangle, EverySampleHitsTheTriangle) {
  const NearTriangle t;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> uniform(0, 1);
  for (int i = 0; i < 20000; ++i) {
    Vector3d w;
    ASSERT_TRUE(solo::sampleSphericalTriangle(t.p, t.a, t.b, t.c, uniform(rng), uniform(rng), &w));
    ASSERT_NEAR(w.norm(), 1, 1e-12);
    ASSERT_TRUE(hitsTriangle(t.p, w, t.a, t.b, t.c, 1e-9)) << i;
  }
  // The corners of the unit square go to the triangle's corners and edges.
  Vector3d w;
  ASSERT_TRUE(solo::sampleSphericalTriangle(t.p, t.a, t.b, t.c, 0, 1, &w));
  EXPECT_NEAR(w.dot((t.a - t.p).normalized()), 1, 1e-9);  // u1 = 0: C' = A; u2 = 1: C'
  ASSERT_TRUE(solo::sampleSphericalTriangle(t.p, t.a, t.b, t.c, 1, 1, &w));
  EXPECT_NEAR(w.dot((t.c - t.p).normalized()), 1, 1e-9);  // u1 = 1: C' = C
  ASSERT_TRUE(solo::sampleSphericalTriangle(t.p, t.a, t.b, t.c, 0.7, 0, &w));
  EXPECT_NEAR(w.dot((t.b - t.p).normalized()), 1, 1e-9);  // u2 = 0: B
}

TEST(SphericalTriangle, SamplesAreUniformInSolidAngle) {
  // The four midpoint sub-triangles receive samples in proportion to their solid angles, which
  // here are far from their equal areas (so area sampling would fail this test).
  const NearTriangle t;
  const Vector3d mab = 0.5 * (t.a + t.b), mbc = 0.5 * (t.b + t.c), mca = 0.5 * (t.c + t.a);
  const std::array<std::array<Vector3d, 3>, 4> quarters = {{{t.a, mab, mca}, {mab, t.b, mbc}, {mca, mbc, t.c}, {mab, mbc, mca}}};
  const double total = solo::triangleSolidAngle(t.p, t.a, t.b, t.c);
  std::array<double, 4> expected{};
  double sum = 0;
  for (int k = 0; k < 4; ++k) {
    expected[k] = solo::triangleSolidAngle(t.p, quarters[k][0], quarters[k][1], quarters[k][2]) / total;
    sum += expected[k];
  }
  ASSERT_NEAR(sum, 1, 1e-9);
  ASSERT_GT(expected[0], 0.6);  // the corner above the point looks largest
  const int n = 100000;
  std::array<int, 4> counts{};
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> uniform(0, 1);
  for (int i = 0; i < n; ++i) {
    Vector3d w;
    ASSERT_TRUE(solo::sampleSphericalTriangle(t.p, t.a, t.b, t.c, uniform(rng), uniform(rng), &w));
    for (int k = 0; k < 4; ++k)
      if (hitsTriangle(t.p, w, quarters[k][0], quarters[k][1], quarters[k][2], 0)) {
        ++counts[k];
        break;
      }
  }
  for (int k = 0; k < 4; ++k) {
    const double sigma = std::sqrt(expected[k] * (1 - expected[k]) / n);
    EXPECT_NEAR(static_cast<double>(counts[k]) / n, expected[k], 4 * sigma) << "quarter " << k;
  }
}

TEST(SphericalTriangle, IrradianceMatchesLambertsFormula) {
  // Irradiance = int cos dw = E[cos] * solid angle with uniform directions.
  const NearTriangle t;
  const Vector3d n = Vector3d(0.2, -0.1, 1).normalized();
  const double omega = solo::triangleSolidAngle(t.p, t.a, t.b, t.c);
  const int rows = 256;  // a stratified grid: the estimate converges fast
  double sum = 0;
  for (int i = 0; i < rows; ++i)
    for (int j = 0; j < rows; ++j) {
      Vector3d w;
      ASSERT_TRUE(solo::sampleSphericalTriangle(t.p, t.a, t.b, t.c, (i + 0.5) / rows, (j + 0.5) / rows, &w));
      sum += std::max(0.0, n.dot(w));
    }
  const double estimate = sum / (rows * rows) * omega;
  EXPECT_NEAR(estimate, solo::test::polygonIrradiance(t.p, n, {t.a, t.b, t.c}), 1e-3 * estimate);
}

TEST(SphericalTriangle, InversionRecoversTheUnitSquarePoint) {
  const NearTriangle t;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> uniform(0.001, 0.999);
  for (int i = 0; i < 2000; ++i) {
    const double u1 = uniform(rng), u2 = uniform(rng);
    Vector3d w;
    ASSERT_TRUE(solo::sampleSphericalTriangle(t.p, t.a, t.b, t.c, u1, u2, &w));
    double v1 = -1, v2 = -1;
    ASSERT_TRUE(solo::invertSphericalTriangleSample(t.p, t.a, t.b, t.c, w, &v1, &v2));
    ASSERT_NEAR(v1, u1, 1e-8);
    ASSERT_NEAR(v2, u2, 1e-8);
  }
}

TEST(SphericalTriangle, CosineWarpedDensityIsConsistentAndNormalised) {
  const NearTriangle t;
  const Vector3d n = Vector3d(0.2, -0.1, 1).normalized();
  const double omega = solo::triangleSolidAngle(t.p, t.a, t.b, t.c);
  // The density the sampler reports is the one the pdf function gives for the same direction.
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> uniform(0, 1);
  for (int i = 0; i < 2000; ++i) {
    Vector3d w;
    double pdf = 0;
    ASSERT_TRUE(solo::sampleSphericalTriangleCosine(t.p, n, t.a, t.b, t.c, uniform(rng), uniform(rng), &w, &pdf));
    ASSERT_TRUE(hitsTriangle(t.p, w, t.a, t.b, t.c, 1e-9));
    ASSERT_NEAR(solo::sphericalTriangleCosinePdf(t.p, n, t.a, t.b, t.c, w), pdf, 1e-6 * pdf);
  }
  // It integrates to 1 over the triangle: the mean over uniform directions times the solid angle.
  const int rows = 200;
  double sum = 0;
  for (int i = 0; i < rows; ++i)
    for (int j = 0; j < rows; ++j) {
      Vector3d w;
      ASSERT_TRUE(solo::sampleSphericalTriangle(t.p, t.a, t.b, t.c, (i + 0.5) / rows, (j + 0.5) / rows, &w));
      sum += solo::sphericalTriangleCosinePdf(t.p, n, t.a, t.b, t.c, w);
    }
  EXPECT_NEAR(sum / (rows * rows) * omega, 1.0, 1e-3);
}

TEST(SphericalTriangle, CosineWarpLowersTheVarianceOfIrradiance) {
  // The receiver sees the triangle from near grazing to near its normal: cos / pdf varies less
  // with the warp. Both estimates match Lambert's formula.
  const NearTriangle t;
  const Vector3d n(0, 0, 1);
  const double omega = solo::triangleSolidAngle(t.p, t.a, t.b, t.c);
  const double expected = solo::test::polygonIrradiance(t.p, n, {t.a, t.b, t.c});
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> uniform(0, 1);
  const int samples = 200000;
  double mean[2] = {0, 0}, square[2] = {0, 0};
  for (int i = 0; i < samples; ++i) {
    const double u1 = uniform(rng), u2 = uniform(rng);
    Vector3d w;
    ASSERT_TRUE(solo::sampleSphericalTriangle(t.p, t.a, t.b, t.c, u1, u2, &w));
    const double plain = std::max(0.0, n.dot(w)) * omega;
    double pdf = 0;
    ASSERT_TRUE(solo::sampleSphericalTriangleCosine(t.p, n, t.a, t.b, t.c, u1, u2, &w, &pdf));
    const double warped = std::max(0.0, n.dot(w)) / pdf;
    mean[0] += plain / samples;
    square[0] += plain * plain / samples;
    mean[1] += warped / samples;
    square[1] += warped * warped / samples;
  }
  const double variance[2] = {square[0] - mean[0] * mean[0], square[1] - mean[1] * mean[1]};
  for (int k = 0; k < 2; ++k) EXPECT_NEAR(mean[k], expected, 4 * std::sqrt(variance[k] / samples)) << k;
  std::printf("per-sample variance of the irradiance estimate: uniform %.4g, cosine-warped %.4g\n", variance[0], variance[1]);
  EXPECT_LT(variance[1], 0.5 * variance[0]);
}

TEST(SphericalTriangle, TinyAndFarTrianglesStayFinite) {
  // A 1 mm triangle at 1 km and a sliver: the sampler either refuses or returns a hit.
  const Vector3d p(0, 0, 0);
  const std::array<std::array<Vector3d, 3>, 2> cases = {
      {{Vector3d(0, 0, 1000), Vector3d(0.001, 0, 1000), Vector3d(0, 0.001, 1000)},
       {Vector3d(-1, 0, 1), Vector3d(1, 0, 1), Vector3d(0, 1e-7, 1)}}};
  for (const auto& c : cases) {
    const double omega = solo::triangleSolidAngle(p, c[0], c[1], c[2]);
    EXPECT_TRUE(std::isfinite(omega));
    EXPECT_GE(omega, 0);
    Vector3d w;
    if (solo::sampleSphericalTriangle(p, c[0], c[1], c[2], 0.37, 0.81, &w)) {
      EXPECT_TRUE(w.allFinite());
      EXPECT_TRUE(hitsTriangle(p, w, c[0], c[1], c[2], 1e-3));
    }
  }
}

}  // namespace
