#include <solo/core/srgb.h>

#include <gtest/gtest.h>

#include <cmath>

namespace {

using solo::linearToSrgb;
using solo::linearToSrgbSlope;
using solo::srgbToLinear;

// Reference values worked by hand from the IEC 61966-2-1 formulas:
// 1.055 * 0.5^(1/2.4) - 0.055 = 1.055 * 0.749154 - 0.055 = 0.735357,
// ((0.5 + 0.055) / 1.055)^2.4 = 0.526066^2.4 = 0.214041,
// 1.055 * 0.18^(1/2.4) - 0.055 = 0.461356 (18 % grey).
TEST(Srgb, EncodesAndDecodesKnownValues) {
  EXPECT_NEAR(linearToSrgb(0.5), 0.735357, 1e-6);
  EXPECT_NEAR(linearToSrgb(0.18), 0.461356, 1e-6);
  EXPECT_NEAR(srgbToLinear(0.5), 0.214041, 1e-6);
  EXPECT_NEAR(srgbToLinear(0.735357), 0.5, 1e-6);
  EXPECT_NEAR(linearToSrgb(0.5f), 0.735357f, 1e-6f);
  EXPECT_NEAR(srgbToLinear(0.5f), 0.214041f, 1e-6f);
}

TEST(Srgb, EndsAtBlackAndWhite) {
  EXPECT_EQ(linearToSrgb(0.0), 0.0);
  EXPECT_EQ(srgbToLinear(0.0), 0.0);
  EXPECT_NEAR(linearToSrgb(1.0), 1.0, 1e-12);
  EXPECT_NEAR(srgbToLinear(1.0), 1.0, 1e-12);
  EXPECT_NEAR(linearToSrgb(1.f), 1.f, 1e-6f);
  EXPECT_NEAR(srgbToLinear(1.f), 1.f, 1e-6f);
}

// The linear segment meets the power segment at linear 0.0031308 <-> encoded 0.04045:
// 12.92 * 0.0031308 = 0.0404499 and 0.04045 / 12.92 = 0.0031308.
TEST(Srgb, PiecesMeetAtTheBreakpoints) {
  EXPECT_NEAR(linearToSrgb(0.0031308), 0.04045, 1e-7);
  EXPECT_NEAR(srgbToLinear(0.04045), 0.0031308, 1e-8);
  EXPECT_DOUBLE_EQ(linearToSrgb(0.002), 12.92 * 0.002);  // the linear segment
  EXPECT_DOUBLE_EQ(srgbToLinear(0.02), 0.02 / 12.92);
  // Just above the breakpoint the power segment continues without a jump.
  EXPECT_NEAR(linearToSrgb(0.0031309), 0.04045, 2e-6);
  EXPECT_NEAR(srgbToLinear(0.04046), 0.0031308, 2e-6);
}

TEST(Srgb, RoundTripsWithinAMillionth) {
  for (int i = 0; i <= 1000; ++i) {
    const double v = i / 1000.0;
    EXPECT_NEAR(srgbToLinear(linearToSrgb(v)), v, 1e-6) << v;
    EXPECT_NEAR(linearToSrgb(srgbToLinear(v)), v, 1e-6) << v;
    const float f = static_cast<float>(v);
    EXPECT_NEAR(srgbToLinear(linearToSrgb(f)), f, 2e-6f) << v;
  }
}

TEST(Srgb, FloatAndDoubleAgree) {
  for (int i = 0; i <= 100; ++i) {
    const double v = i / 100.0;
    EXPECT_NEAR(linearToSrgb(static_cast<float>(v)), linearToSrgb(v), 1e-6) << v;
    EXPECT_NEAR(srgbToLinear(static_cast<float>(v)), srgbToLinear(v), 1e-6) << v;
  }
}

TEST(Srgb, SlopeMatchesAFiniteDifference) {
  EXPECT_EQ(linearToSrgbSlope(0.001), 12.92);
  // 1.055 / 2.4 * 0.5^(1/2.4 - 1) = 0.439583 * 1.498307 = 0.658631
  EXPECT_NEAR(linearToSrgbSlope(0.5), 0.658631, 1e-6);
  for (const double v : {0.001, 0.002, 0.01, 0.05, 0.18, 0.5, 0.9}) {
    const double h = 1e-7;
    const double central = (linearToSrgb(v + h) - linearToSrgb(v - h)) / (2 * h);
    EXPECT_NEAR(linearToSrgbSlope(v), central, 1e-5 * linearToSrgbSlope(v)) << v;
  }
}

}  // namespace
