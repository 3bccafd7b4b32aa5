#include <solo/render/render_upsample.h>

#include "test_support.h"

#include <opencv2/imgproc.hpp>

#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>

namespace {

constexpr int kLowWidth = 16, kLowHeight = 12, kFactor = 2;
const cv::Size kLowSize(kLowWidth, kLowHeight);
const cv::Size kSize(kLowWidth* kFactor, kLowHeight* kFactor);

// A full-size scene: per pixel its depth (0 = sky), reflectance (grey) and the irradiance that
// falls on it (grey).
struct FullTruth {
  cv::Mat depth_m, reflectance, irradiance;
};

FullTruth fullTruth(const std::function<float(int x, int y)>& depth, const std::function<float(int x, int y)>& albedo,
                    const std::function<float(int x, int y)>& irradiance) {
  FullTruth t;
  t.depth_m.create(kSize, CV_32F);
  t.reflectance.create(kSize, CV_32FC3);
  t.irradiance.create(kSize, CV_32F);
  for (int y = 0; y < kSize.height; ++y)
    for (int x = 0; x < kSize.width; ++x) {
      t.depth_m.at<float>(y, x) = depth(x, y);
      t.reflectance.at<cv::Vec3f>(y, x) = cv::Vec3f::all(albedo(x, y));
      t.irradiance.at<float>(y, x) = irradiance(x, y);
    }
  return t;
}

// The render of `t` at half size: each render pixel's first sample sees the full-size pixel at
// its top-left corner (albedo, depth), its samples the 2x2 full-size pixels it covers (radiance
// and mean albedo, the means of reflectance times irradiance and of reflectance).
solo::RenderOutput halfRender(const FullTruth& t) {
  solo::RenderOutput r;
  r.radiance.create(kLowSize, CV_32FC3);
  r.albedo.create(kLowSize, CV_32FC3);
  r.mean_albedo.create(kLowSize, CV_32FC3);
  r.normal = cv::Mat(kLowSize, CV_32FC3, cv::Scalar(0, 0, -1));
  r.depth_m.create(kLowSize, CV_32F);
  r.light_id = cv::Mat::zeros(kLowSize, CV_32S);
  r.emitter_coverage = cv::Mat::zeros(kLowSize, CV_32F);
  r.samples = cv::Mat(kLowSize, CV_32S, cv::Scalar(4));
  r.std_error = cv::Mat(kLowSize, CV_32F, cv::Scalar(0.01));
  for (int v = 0; v < kLowHeight; ++v)
    for (int u = 0; u < kLowWidth; ++u) {
      const int x = u * kFactor, y = v * kFactor;
      float albedo_mean = 0, radiance_mean = 0;
      for (int j = 0; j < kFactor; ++j)
        for (int i = 0; i < kFactor; ++i) {
          const float a = t.reflectance.at<cv::Vec3f>(y + j, x + i)[0];
          albedo_mean += a / (kFactor * kFactor);
          radiance_mean += a * t.irradiance.at<float>(y + j, x + i) / (kFactor * kFactor);
        }
      r.albedo.at<cv::Vec3f>(v, u) = t.reflectance.at<cv::Vec3f>(y, x);
      r.mean_albedo.at<cv::Vec3f>(v, u) = cv::Vec3f::all(albedo_mean);
      r.depth_m.at<float>(v, u) = t.depth_m.at<float>(y, x);
      r.radiance.at<cv::Vec3f>(v, u) = cv::Vec3f::all(radiance_mean);
    }
  return r;
}

cv::Mat bilinear(const cv::Mat& m) {
  cv::Mat out;
  cv::resize(m, out, kSize, 0, 0, cv::INTER_LINEAR);
  return out;
}

std::int64_t count(const solo::StageReport& report, const char* name) {
  const solo::MetricValue* value = report.find(name);
  return value ? std::get<std::int64_t>(*value) : -1;
}

solo::UpsampleGuides guides(const FullTruth& t, const cv::Mat& surface = cv::Mat(),
                            const cv::Mat& light_id = cv::Mat()) {
  return {t.reflectance, t.depth_m, surface, light_id};
}

float y(const cv::Mat& radiance, int x, int y_) { return radiance.at<cv::Vec3f>(y_, x)[1]; }

}  // namespace

// A plane at one depth under one irradiance whose reflectance alternates 0.2 / 0.8 at every
// full-size pixel: the render cannot see the texture (each of its pixels averages 0.5), the
// upsampling gives it back exactly; bilinear leaves a flat grey.
TEST(RenderUpsample, GivesAPlaneItsTextureBackExactly) {
  const FullTruth t = fullTruth([](int, int) { return 10.f; }, [](int x, int y_) { return (x + y_) % 2 ? 0.8f : 0.2f; },
                                [](int, int) { return 3.f; });
  const solo::RenderOutput low = halfRender(t);
  solo::StageReport report;
  const solo::RenderOutput up = solo::upsampleRender(low, kSize, guides(t), {}, &report);
  ASSERT_EQ(up.radiance.size(), kSize);
  for (int y_ = 0; y_ < kSize.height; ++y_)
    for (int x = 0; x < kSize.width; ++x)
      ASSERT_NEAR(y(up.radiance, x, y_), 3.f * t.reflectance.at<cv::Vec3f>(y_, x)[0], 1e-5f) << x << "," << y_;
  EXPECT_NEAR(y(bilinear(low.radiance), 5, 5), 1.5f, 1e-5f);  // what the bilinear upsampling shows
  EXPECT_EQ(count(report, "upsampled_textured_pixels"), kSize.area());
  EXPECT_EQ(count(report, "upsampled_bilinear_pixels"), 0);
  // The AOVs: depth and light ids nearest, of the render's size.
  EXPECT_EQ(up.depth_m.size(), kSize);
  EXPECT_FLOAT_EQ(up.depth_m.at<float>(7, 9), 10.f);
  EXPECT_EQ(up.light_id.size(), kSize);
}

// Irradiance that varies smoothly (linearly across the image) on a checkered plane: the
// upsampled radiance is the reflectance times the bilinear irradiance, exact for a linear
// function away from the border rows and columns (each render pixel's albedo-weighted
// irradiance is the one at its centre: a checker's two bright pixels sit on a diagonal).
TEST(RenderUpsample, SmoothLightIsInterpolatedAndTheTextureKept) {
  const FullTruth t = fullTruth([](int, int) { return 8.f; }, [](int x, int y_) { return (x + y_) % 2 ? 0.7f : 0.3f; },
                                [](int x, int y_) { return 1.f + 0.1f * x + 0.05f * y_; });
  const solo::RenderOutput low = halfRender(t);
  const solo::RenderOutput up = solo::upsampleRender(low, kSize, guides(t));
  for (int y_ = 1; y_ < kSize.height - 1; ++y_)
    for (int x = 1; x < kSize.width - 1; ++x) {
      const float truth = t.reflectance.at<cv::Vec3f>(y_, x)[0] * t.irradiance.at<float>(y_, x);
      ASSERT_NEAR(y(up.radiance, x, y_), truth, 1e-4f * truth) << x << "," << y_;
    }
}

// A near plane (5 m, lit at 4) beside a far one (20 m, lit at 0.5), the edge inside a render
// pixel's bilinear reach: the full-size pixels on either side take only their own surface's
// light. Bilinear would mix them.
TEST(RenderUpsample, KeepsEachSideOfADepthEdgeOnItsOwnLight) {
  const auto near = [](int x) { return x < 12; };
  // The same edge at 0.5 / 2 m, 5 / 20 m and 1 / 4 km: the depth weight is relative.
  for (const float scale : {0.1f, 1.f, 200.f}) {
    const FullTruth t = fullTruth([&](int x, int) { return scale * (near(x) ? 5.f : 20.f); },
                                  [](int, int) { return 0.5f; }, [&](int x, int) { return near(x) ? 4.f : 0.5f; });
    const solo::RenderOutput low = halfRender(t);
    const solo::RenderOutput up = solo::upsampleRender(low, kSize, guides(t));
    const cv::Mat mixed = bilinear(low.radiance);
    for (int x = 9; x <= 14; ++x) {
      const float truth = 0.5f * (near(x) ? 4.f : 0.5f);
      EXPECT_NEAR(y(up.radiance, x, 10), truth, 1e-5f) << x << " at scale " << scale;
    }
    EXPECT_GT(std::abs(y(mixed, 11, 10) - 2.f), 0.2f);  // bilinear's mix at the edge
    EXPECT_GT(std::abs(y(mixed, 12, 10) - 0.25f), 0.2f);
  }
}

// Pixels beside a render pixel that sees a lamp keep the bilinear radiance (the lamp keeps its
// shape, its light is not multiplied by the texture); sky pixels (no depth, or not a surface in
// the surface mask) too; a render pixel of a black surface or a non-finite radiance is not used.
TEST(RenderUpsample, LampsSkyBlackSurfacesAndNonFiniteRendersStayBilinearOrAreLeftOut) {
  const FullTruth t = fullTruth([](int, int y_) { return y_ < 4 ? 0.f : 10.f; },
                                [](int x, int) { return x % 2 ? 0.9f : 0.1f; }, [](int, int) { return 2.f; });
  solo::RenderOutput low = halfRender(t);
  low.emitter_coverage.at<float>(6, 3) = 0.5f;
  low.radiance.at<cv::Vec3f>(6, 3) = cv::Vec3f::all(5000.f);
  low.mean_albedo.at<cv::Vec3f>(8, 10) = cv::Vec3f::all(0.f);  // black: not used
  low.radiance.at<cv::Vec3f>(8, 12) = cv::Vec3f::all(std::numeric_limits<float>::quiet_NaN());
  cv::Mat surface(kSize, CV_8U, cv::Scalar(1));
  surface.at<std::uint8_t>(20, 30) = 0;
  solo::StageReport report;
  const solo::RenderOutput up = solo::upsampleRender(low, kSize, guides(t, surface), {}, &report);
  const cv::Mat plain = bilinear(low.radiance);
  // Around the lamp: render pixel (3, 6) is a bilinear neighbour of full-size pixels 5..8 x 11..14.
  for (int y_ = 11; y_ <= 14; ++y_)
    for (int x = 5; x <= 8; ++x) EXPECT_FLOAT_EQ(y(up.radiance, x, y_), y(plain, x, y_)) << x << "," << y_;
  // Sky rows and the masked pixel.
  for (int x = 0; x < kSize.width; ++x) EXPECT_FLOAT_EQ(y(up.radiance, x, 1), y(plain, x, 1));
  EXPECT_FLOAT_EQ(y(up.radiance, 30, 20), y(plain, 30, 20));
  // Beside the black render pixel (8, 10) and the NaN one (8, 12): the others' light.
  for (const int x : {19, 20, 21, 23, 24, 25}) {
    const float truth = 2.f * t.reflectance.at<cv::Vec3f>(17, x)[0];
    EXPECT_NEAR(y(up.radiance, x, 17), truth, 1e-5f) << x;
  }
  for (int y_ = 0; y_ < kSize.height; ++y_)
    for (int x = 0; x < kSize.width; ++x) ASSERT_TRUE(std::isfinite(y(up.radiance, x, y_))) << x << "," << y_;
  EXPECT_GT(count(report, "upsampled_bilinear_pixels"), kSize.width * 4);
}

// A lit window whose outline falls inside render pixels (full-size columns 9-16, render
// columns 4 and 8 half covered): with the image's light ids, the window's pixels take the
// window's radiance and the wall's pixels beside it the wall's, each to the full-size pixel.
TEST(RenderUpsample, AWindowKeepsItsOutlineWithTheImagesLightIds) {
  constexpr int kLight = 7;
  constexpr float kWindow = 1000.f;
  const auto in_window = [](int x, int y_) { return x >= 9 && x < 17 && y_ >= 8 && y_ < 16; };
  const FullTruth t = fullTruth([](int, int) { return 10.f; }, [](int x, int y_) { return (x + y_) % 2 ? 0.6f : 0.4f; },
                                [](int, int) { return 2.f; });
  solo::RenderOutput low = halfRender(t);
  cv::Mat light_id = cv::Mat::zeros(kSize, CV_32S);
  for (int y_ = 0; y_ < kSize.height; ++y_)
    for (int x = 0; x < kSize.width; ++x)
      if (in_window(x, y_)) light_id.at<std::int32_t>(y_, x) = kLight;
  for (int v = 4; v <= 7; ++v)
    for (int u = 4; u <= 8; ++u) {
      const float coverage = (u == 4 || u == 8) ? 0.5f : 1.f;
      const cv::Vec3f wall = low.radiance.at<cv::Vec3f>(v, u);
      low.emitter_coverage.at<float>(v, u) = coverage;
      low.light_id.at<std::int32_t>(v, u) = kLight;
      low.radiance.at<cv::Vec3f>(v, u) = coverage * cv::Vec3f::all(kWindow) + (1.f - coverage) * wall;
      low.mean_albedo.at<cv::Vec3f>(v, u) *= 1.f - coverage;  // an emitting face reflects nothing
    }
  solo::StageReport report;
  const solo::RenderOutput up = solo::upsampleRender(low, kSize, guides(t, cv::Mat(), light_id), {}, &report);
  for (int x = 6; x <= 19; ++x) {
    const float truth = in_window(x, 11) ? kWindow : 2.f * t.reflectance.at<cv::Vec3f>(11, x)[0];
    EXPECT_NEAR(y(up.radiance, x, 11), truth, 1e-3f * truth) << x;
  }
  EXPECT_EQ(count(report, "upsampled_lamp_pixels"), 8 * 8);
  // Without the light ids, the pixels beside the window keep the bilinear mix.
  const solo::RenderOutput plain = solo::upsampleRender(low, kSize, guides(t));
  EXPECT_FLOAT_EQ(y(plain.radiance, 8, 11), y(bilinear(low.radiance), 8, 11));
  EXPECT_GT(y(plain.radiance, 8, 11), 100.f);
}

TEST(RenderUpsample, WithoutAReflectanceOrSwitchedOffIsBilinearAndRefusesMapsOfAnotherSize) {
  const FullTruth t = fullTruth([](int, int) { return 10.f; }, [](int x, int) { return x % 2 ? 0.9f : 0.1f; },
                                [](int, int) { return 2.f; });
  const solo::RenderOutput low = halfRender(t);
  const solo::RenderOutput up = solo::upsampleRender(low, kSize, {cv::Mat(), t.depth_m, cv::Mat(), cv::Mat()});
  const cv::Mat plain = bilinear(low.radiance);
  EXPECT_EQ(cv::norm(up.radiance, plain, cv::NORM_INF), 0.0);
  solo::RenderUpsampleOptions no_texture;
  no_texture.texture = false;
  EXPECT_EQ(cv::norm(solo::upsampleRender(low, kSize, guides(t), no_texture).radiance, plain, cv::NORM_INF), 0.0);
  EXPECT_THROW(solo::upsampleRender(low, kSize, {t.reflectance, cv::Mat(kLowSize, CV_32F, cv::Scalar(1)), {}, {}}),
               std::invalid_argument);
  EXPECT_THROW(solo::upsampleRender(low, kSize, {cv::Mat(kSize, CV_32F, cv::Scalar(1)), t.depth_m, {}, {}}),
               std::invalid_argument);
  EXPECT_THROW(solo::upsampleRender(low, kSize, guides(t, cv::Mat(), cv::Mat(kSize, CV_32F, cv::Scalar(0)))),
               std::invalid_argument);
  solo::RenderUpsampleOptions bad;
  bad.depth_tolerance = 0;
  EXPECT_THROW(solo::upsampleRender(low, kSize, guides(t), bad), std::invalid_argument);
}
