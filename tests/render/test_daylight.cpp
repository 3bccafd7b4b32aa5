// Daytime mode of the path tracer against closed forms: a Lambertian plane under the sun
// alone (albedo / pi E cos zenith), under a uniform sky (albedo L) and a sky gradient, a point
// in a box's shadow (darker by exactly the sun term, with the sky the box hides), and the
// street day scene's sky pixels against the raster day image's.

#include <solo/synth/day_scene.h>
#include <solo/render/path_tracer.h>
#include <solo/synth/scene_raster.h>

#include "rectangle_irradiance.h"

#include <gtest/gtest.h>

#include <cmath>

namespace {

constexpr double kPi = 3.14159265358979323846;

void addQuad(solo::RenderScene& s, const Eigen::Vector3f& corner, const Eigen::Vector3f& u, const Eigen::Vector3f& v,
             float reflectance) {
  const auto base = static_cast<std::uint32_t>(s.vertices.size());
  s.vertices.insert(s.vertices.end(), {corner, corner + u, corner + u + v, corner + v});
  s.faces.push_back({base, base + 1, base + 2});
  s.faces.push_back({base, base + 2, base + 3});
  for (int k = 0; k < 2; ++k) s.face_reflectance.push_back(Eigen::Vector3f::Constant(reflectance));
}

// One narrow pixel looking along (x_over_z, y_over_z, 1): a pixel value is one point's radiance.
solo::PinholeCamera cameraLookingAt(double x_over_z, double y_over_z) {
  const double focal = 2000;
  return {focal, focal, -focal * x_over_z, -focal * y_over_z, 1, 1};
}

// A horizontal ground (y = 1, the camera 1 m above it, OpenCV y down) of reflectance a.
solo::RenderScene ground(float a) {
  solo::RenderScene s;
  addQuad(s, {-20, 1, 0.5f}, {40, 0, 0}, {0, 0, 40}, a);
  return s;
}

double renderY(solo::RenderScene s, double x, double z, int spp) {
  s.camera = cameraLookingAt(x / z, 1.0 / z);  // the ground point (x, 1, z)
  solo::PathTracerOptions o;
  o.diffuse = solo::DiffuseModel::Lambert;
  o.min_samples = o.max_samples = spp;
  o.progress = false;
  return solo::renderPathTraced(s, o).radiance.at<cv::Vec3f>(0, 0)[1];
}

using solo::test::rectangleIntegral;

}  // namespace

TEST(Daylight, PlaneUnderTheSunIsAlbedoOverPiTimesIlluminanceTimesCosine) {
  for (double zenith_deg : {0.0, 40.0, 75.0}) {
    const double zenith = zenith_deg * kPi / 180;
    solo::RenderScene s = ground(0.5f);
    s.sun.direction = Eigen::Vector3d(std::sin(zenith), -std::cos(zenith), 0).cast<float>();
    s.sun.illuminance = Eigen::Vector3f::Constant(10.f);
    const double expected = 0.5 / kPi * 10 * std::cos(zenith);
    EXPECT_NEAR(renderY(s, 0.3, 5, 64), expected, 0.005 * expected) << zenith_deg;
  }
}

TEST(Daylight, PlaneUnderAUniformSkyIsAlbedoTimesItsRadianceAndUnderTheGradientItsMean) {
  solo::RenderScene s = ground(0.5f);
  s.sky_radiance = Eigen::Vector3f::Constant(0.7f);
  EXPECT_NEAR(renderY(s, 0.0, 5, 256), 0.5 * 0.7, 0.002);
  // Gradient h + (z - h) sqrt(cos): irradiance / pi = h + (z - h) 2 int mu^1.5 dmu = h + 0.8 (z - h).
  s.sky_radiance = Eigen::Vector3f::Constant(0.4f);
  s.sky_zenith_radiance = Eigen::Vector3f::Constant(1.2f);
  EXPECT_NEAR(renderY(s, -1.0, 5, 4000), 0.5 * (0.4 + 0.8 * 0.8), 0.01 * 0.52);
}

TEST(Daylight, ABoxShadowRemovesExactlyTheSunTerm) {
  const double zenith = 40 * kPi / 180, height = 0.5, half = 0.25, a = 0.5, sky = 0.6, sun = 8;
  solo::RenderScene s = ground(static_cast<float>(a));
  s.sun.direction = Eigen::Vector3d(std::sin(zenith), -std::cos(zenith), 0).cast<float>();
  s.sun.illuminance = Eigen::Vector3f::Constant(static_cast<float>(sun));
  // A black square 0.5 m above the ground, placed to shadow the point (0, 1, 5).
  const double shift = height * std::tan(zenith);
  addQuad(s, Eigen::Vector3d(shift - half, 1 - height, 5 - half).cast<float>(), {static_cast<float>(2 * half), 0, 0},
          {0, 0, static_cast<float>(2 * half)}, 0.f);
  // Sun only: the shadowed point is black, the lit one the closed form.
  const double sun_term = a / kPi * sun * std::cos(zenith);
  EXPECT_NEAR(renderY(s, 0, 5, 64), 0.0, 1e-6);
  EXPECT_NEAR(renderY(s, -1, 5, 64), sun_term, 0.005 * sun_term);
  // With a uniform sky both lose the sky the square hides from them.
  s.sky_radiance = Eigen::Vector3f::Constant(static_cast<float>(sky));
  const double hidden0 = rectangleIntegral(shift - half, shift + half, -half, half, height) / kPi;
  const double hidden1 = rectangleIntegral(1 + shift - half, 1 + shift + half, -half, half, height) / kPi;
  const double shadowed = a * sky * (1 - hidden0), lit = a * sky * (1 - hidden1) + sun_term;
  EXPECT_NEAR(renderY(s, 0, 5, 8000), shadowed, 0.015 * shadowed);
  EXPECT_NEAR(renderY(s, -1, 5, 8000), lit, 0.015 * lit);
}

TEST(Daylight, StreetSkyPixelsShowTheRasterDayImagesSkyGradient) {
  solo::StreetSceneOptions options;
  options.width = 96;
  options.height = 54;
  options.variant = solo::StreetVariant::WideSky;
  const solo::StreetScene street = solo::buildStreetScene(options);
  const solo::GroundTruthMaps truth = solo::rasterizeGroundTruth(street);
  solo::StreetSceneOptions fine_options = options;
  fine_options.width *= 8;
  fine_options.height *= 8;
  const solo::GroundTruthMaps fine = solo::rasterizeGroundTruth(solo::buildStreetScene(fine_options));
  const cv::Mat raster = solo::renderDaylight(street, truth);
  solo::DayRenderOptions day;
  day.min_samples = day.max_samples = 64;
  const solo::DaylightRender traced = solo::renderDaylightPathTraced(street, day);
  ASSERT_EQ(traced.linear_rgb.size(), raster.size());
  const solo::PinholeCamera& cam = street.camera;
  const Eigen::Vector3f up(0, -1, 0);
  int compared = 0;
  for (int y = 1; y + 1 < raster.rows; ++y)
    for (int x = 1; x + 1 < raster.cols; ++x) {
      // Sky over the pixel's whole footprint, thin poles included: checked on the ground
      // truth at 8 times the resolution (the same layout; coarse pixel centre x is fine
      // 8x + 3.5), over 0.75 coarse pixels around the centre.
      bool all_sky = true;
      for (int fy = 8 * y - 2; fy <= 8 * y + 9; ++fy)
        for (int fx = 8 * x - 2; fx <= 8 * x + 9; ++fx) all_sky = all_sky && fine.depth_m.at<float>(fy, fx) <= 0.f;
      if (!all_sky) continue;
      ++compared;
      // The gradient averaged over the pixel's area (at its centre it is the raster's value;
      // near the horizon the sqrt makes the two differ).
      Eigen::Vector3d expected = Eigen::Vector3d::Zero();
      const int n = 32;
      for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
          const Eigen::Vector3f d = Eigen::Vector3d((x - 0.5 + (i + 0.5) / n - cam.cx) / cam.fx,
                                                    (y - 0.5 + (j + 0.5) / n - cam.cy) / cam.fy, 1.0)
                                        .normalized()
                                        .cast<float>();
          const float elevation = std::max(0.f, d.dot(up));
          expected +=
              (day.sky_horizon_rgb + (day.sky_zenith_rgb - day.sky_horizon_rgb) * std::sqrt(elevation)).cast<double>();
        }
      expected /= n * n;
      const cv::Vec3f at_centre = raster.at<cv::Vec3f>(y, x);
      for (int k = 0; k < 3; ++k) {
        EXPECT_NEAR(traced.linear_rgb.at<cv::Vec3f>(y, x)[k], expected[k], 0.01) << x << "," << y;
        if (y < cam.cy - 5) {  // well above the horizon the gradient is nearly linear over a pixel
          EXPECT_NEAR(traced.linear_rgb.at<cv::Vec3f>(y, x)[k], at_centre[k], 0.02) << x << "," << y;
        }
      }
    }
  EXPECT_GT(compared, 100);
  EXPECT_NE(traced.report.find("sun_illuminance_y"), nullptr);
}
