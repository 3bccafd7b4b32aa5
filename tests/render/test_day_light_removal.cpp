#include <solo/render/day_light_removal.h>
#include <solo/render/ray_caster.h>

#include "test_support.h"

#include <Eigen/Geometry>

#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <vector>

namespace {

constexpr int kWidth = 320, kHeight = 180;
constexpr float kAlbedo = 0.4f;
constexpr float kSunIrradiance = 2.0f;  // image units on a white surface facing the sun
constexpr float kSkyRadiance = 0.6f;    // image units, uniform
constexpr int kRoadInstance = 7, kCarInstance = 26001;

// A road plane 1.5 m below the camera (y = 1.5, the camera frame's y points down) from z = 2 to
// 60 m, and a 2 x 1.2 x 3 m box standing on it 10 m ahead: the box casts a shadow on the road.
struct PlaneAndBox {
  solo::DayLightGeometry geometry;
  std::vector<int> quad_instance;
};

void addQuad(PlaneAndBox& s, const std::array<Eigen::Vector3f, 4>& corners, int instance) {
  const auto first = static_cast<std::uint32_t>(s.geometry.vertices.size() / 3);
  for (const Eigen::Vector3f& c : corners)
    for (int k = 0; k < 3; ++k) s.geometry.vertices.push_back(c[k]);
  for (const std::uint32_t i : {0u, 1u, 2u, 0u, 2u, 3u}) s.geometry.triangles.push_back(first + i);
  s.geometry.triangle_instance.push_back(instance);
  s.geometry.triangle_instance.push_back(instance);
}

PlaneAndBox planeAndBox() {
  PlaneAndBox s;
  s.geometry.camera = solo::PinholeCamera{300, 300, (kWidth - 1) / 2.0, (kHeight - 1) / 2.0, kWidth, kHeight};
  const float y0 = 1.5f;
  addQuad(s, {{{-30, y0, 2}, {30, y0, 2}, {30, y0, 60}, {-30, y0, 60}}}, kRoadInstance);
  const float x0 = -1, x1 = 1, yt = y0 - 1.2f, z0 = 10, z1 = 13;
  const std::array<Eigen::Vector3f, 8> v = {{{x0, yt, z0}, {x1, yt, z0}, {x1, y0, z0}, {x0, y0, z0},
                                             {x0, yt, z1}, {x1, yt, z1}, {x1, y0, z1}, {x0, y0, z1}}};
  addQuad(s, {v[0], v[1], v[2], v[3]}, kCarInstance);  // front (faces the camera)
  addQuad(s, {v[4], v[5], v[1], v[0]}, kCarInstance);  // top
  addQuad(s, {v[1], v[5], v[6], v[2]}, kCarInstance);  // right
  addQuad(s, {v[4], v[0], v[3], v[7]}, kCarInstance);  // left
  addQuad(s, {v[5], v[4], v[7], v[6]}, kCarInstance);  // back
  return s;
}

Eigen::Vector3f sunDirection() { return Eigen::Vector3f(0.55f, -0.7f, -0.45f).normalized(); }

// Cosine-weighted direction j of `count` (a square grid of strata) about n.
Eigen::Vector3f cosineDirection(const Eigen::Vector3f& n, int j, int count) {
  const int side = static_cast<int>(std::lround(std::sqrt(count)));
  const Eigen::Vector3f t =
      n.cross(std::abs(n.x()) < 0.9f ? Eigen::Vector3f::UnitX() : Eigen::Vector3f::UnitY()).normalized();
  const Eigen::Vector3f b = n.cross(t);
  const int column = j % side, row = j / side;  // the stratum
  const float u = (static_cast<float>(column) + 0.5f) / side, v = (static_cast<float>(row) + 0.5f) / side;
  const float r = std::sqrt(u), phi = 6.2831853f * v;
  return (t * (r * std::cos(phi)) + b * (r * std::sin(phi)) + n * std::sqrt(1 - u)).normalized();
}

// Radiance of a surface point of constant albedo: sun and sky (uniform above the horizon),
// plus, with `bounce`, one bounce of that light from the surfaces its rays hit.
float radiance(const solo::RayCaster& caster, const Eigen::Vector3f& p, const Eigen::Vector3f& n,
               const Eigen::Vector3f& sun, float sun_irradiance, int rays, bool bounce) {
  const Eigen::Vector3f up(0, -1, 0);
  const float inf = std::numeric_limits<float>::infinity();
  float direct = 0;
  if (n.dot(sun) > 0 && !caster.occluded(p, sun, 0.f, inf)) direct = n.dot(sun);
  float ambient = 0;
  for (int j = 0; j < rays; ++j) {
    const Eigen::Vector3f d = cosineDirection(n, j, rays);
    const solo::RayHit hit = caster.intersect(p, d);
    if (!hit.hit) {
      ambient += d.dot(up) > 0 ? kSkyRadiance : 0.f;
    } else if (bounce) {
      Eigen::Vector3f m = hit.geometric_normal.normalized();
      if (m.dot(d) > 0) m = -m;
      ambient += radiance(caster, p + d * hit.distance + m * 1e-3f, m, sun, sun_irradiance, 9, false);
    }
  }
  return kAlbedo * (sun_irradiance * direct + ambient / static_cast<float>(rays));
}

// Calls visit(x, y, view, point, normal) for every pixel whose camera ray (through a fixed
// sub-pixel offset) hits the mesh: the unit view direction, the hit point lifted 1 mm off the
// surface and the surface normal facing the camera.
template <typename Visit>
void forEachSurfacePixel(const solo::DayLightGeometry& g, const solo::RayCaster& caster, Visit visit) {
  for (int y = 0; y < kHeight; ++y)
    for (int x = 0; x < kWidth; ++x) {
      const Eigen::Vector3f view = Eigen::Vector3f(static_cast<float>((x + 0.13 - g.camera.cx) / g.camera.fx),
                                                   static_cast<float>((y + 0.07 - g.camera.cy) / g.camera.fy), 1.f)
                                       .normalized();
      const solo::RayHit hit = caster.intersect(Eigen::Vector3f::Zero(), view);
      if (!hit.hit) continue;
      Eigen::Vector3f n = hit.geometric_normal.normalized();
      if (n.dot(view) > 0) n = -n;
      visit(x, y, view, Eigen::Vector3f(view * hit.distance + n * 1e-3f), n);
    }
}

// The day image of constant albedo under the sun and a uniform sky, with one bounce; sky pixels
// show the sky.
cv::Mat renderDay(const solo::DayLightGeometry& g, const Eigen::Vector3f& sun, float sun_irradiance) {
  const solo::RayCaster caster(g.vertices, g.triangles);
  cv::Mat day(kHeight, kWidth, CV_32FC3, cv::Scalar::all(kSkyRadiance));
  forEachSurfacePixel(g, caster, [&](int x, int y, const Eigen::Vector3f&, const Eigen::Vector3f& p,
                                     const Eigen::Vector3f& n) {
    day.at<cv::Vec3f>(y, x) = cv::Vec3f::all(radiance(caster, p, n, sun, sun_irradiance, 16, true));
  });
  return day;
}

// The spread of the albedo's green channel below the horizon (the road and the box): the
// ratio of its means over the pixels the sun lights and those in shadow (`lit`: the day image
// rendered with a sun and no sky), and its relative standard deviation.
struct Spread {
  double lit_over_shadow = 0, relative_std = 0;
};

Spread albedoSpread(const cv::Mat& albedo, const cv::Mat& lit) {
  double sum = 0, sum2 = 0, lit_sum = 0, shadow_sum = 0;
  int n = 0, n_lit = 0, n_shadow = 0;
  for (int y = kHeight / 2 + 5; y < kHeight; ++y)
    for (int x = 0; x < kWidth; ++x) {
      const double a = albedo.at<cv::Vec3f>(y, x)[1];
      if (lit.at<cv::Vec3f>(y, x)[1] < 0.f) continue;  // no surface
      const bool sunlit = lit.at<cv::Vec3f>(y, x)[1] > 0.05f;
      sum += a;
      sum2 += a * a;
      ++n;
      (sunlit ? lit_sum : shadow_sum) += a;
      ++(sunlit ? n_lit : n_shadow);
    }
  EXPECT_GT(n_shadow, 100);
  EXPECT_GT(n_lit, 100);
  const double mean = sum / n;
  return {(lit_sum / n_lit) / (shadow_sum / n_shadow), std::sqrt(std::max(0.0, sum2 / n - mean * mean)) / mean};
}

// Where the sun shines: the pixels' direct light alone.
cv::Mat sunlit(const solo::DayLightGeometry& g) {
  const solo::RayCaster caster(g.vertices, g.triangles);
  cv::Mat lit(kHeight, kWidth, CV_32FC3, cv::Scalar::all(-1));
  forEachSurfacePixel(g, caster, [&](int x, int y, const Eigen::Vector3f&, const Eigen::Vector3f& p,
                                     const Eigen::Vector3f& n) {
    lit.at<cv::Vec3f>(y, x) = cv::Vec3f::all(0);
    if (n.dot(sunDirection()) > 0 && !caster.occluded(p, sunDirection(), 0.f, std::numeric_limits<float>::infinity()))
      lit.at<cv::Vec3f>(y, x) = cv::Vec3f::all(n.dot(sunDirection()));
  });
  return lit;
}

double angleDeg(const Eigen::Vector3f& a, const Eigen::Vector3f& b) {
  return std::acos(std::clamp(static_cast<double>(a.normalized().dot(b.normalized())), -1.0, 1.0)) * 180 / 3.14159265;
}

}  // namespace

TEST(DayLightRemoval, FindsTheSunAndFlattensTheShadowOfABox) {
  const PlaneAndBox scene = planeAndBox();
  const cv::Mat day = renderDay(scene.geometry, sunDirection(), kSunIrradiance);
  const Spread before = albedoSpread(day, sunlit(scene.geometry));
  const solo::DayLightRemoval out = solo::removeDayLight(day, scene.geometry);
  ASSERT_EQ(out.method, solo::DayLightMethod::SunAndSky);
  EXPECT_LT(angleDeg(out.sun_direction, sunDirection()), 3.0);
  const Spread after = albedoSpread(out.albedo, sunlit(scene.geometry));
  std::printf("lit / shadow: day image %.3f, albedo %.3f; relative std %.3f -> %.3f\n", before.lit_over_shadow,
              after.lit_over_shadow, before.relative_std, after.relative_std);
  EXPECT_GT(before.lit_over_shadow, 2.0);  // the day image: the shadow is dark
  // The box's side in the shadow is hidden from the camera: its radiance is guessed (the
  // surfaces' 25th percentile, here the lit road), so the shadow's ambient light is
  // overestimated and its albedo comes out about 25 % low.
  EXPECT_NEAR(after.lit_over_shadow, 1.0, 0.35);
  EXPECT_LT(after.relative_std, 0.5 * before.relative_std);
  EXPECT_GT(out.report.seconds, 0.0);
}

// A known sun (DayLightRemovalOptions::sun_direction) is used as given, with or without
// shadows_from_image: the box's shadow flattens as with the found sun, and a wrong sun (turned
// 90 degrees about the vertical) leaves it, so the given direction is what decides.
TEST(DayLightRemoval, AGivenSunIsUsedWithoutASearch) {
  const PlaneAndBox scene = planeAndBox();
  const cv::Mat day = renderDay(scene.geometry, sunDirection(), kSunIrradiance);
  const cv::Mat lit = sunlit(scene.geometry);
  const Spread before = albedoSpread(day, lit);
  for (const bool from_image : {false, true}) {
    SCOPED_TRACE(from_image ? "shadows_from_image" : "shadow rays");
    solo::DayLightRemovalOptions options;
    options.shadows_from_image = from_image;
    options.sun_direction = 3.f * sunDirection();  // any length
    const solo::DayLightRemoval out = solo::removeDayLight(day, scene.geometry, options);
    ASSERT_EQ(out.method, solo::DayLightMethod::SunAndSky);
    EXPECT_LT(angleDeg(out.sun_direction, sunDirection()), 1e-3);
    EXPECT_NEAR(out.sun_direction.norm(), 1.f, 1e-5f);
    EXPECT_NE(std::find(out.report.notes.begin(), out.report.notes.end(),
                        "sun direction given: its shadows traced through the mesh, no search"),
              out.report.notes.end());
    const Spread after = albedoSpread(out.albedo, lit);
    EXPECT_NEAR(after.lit_over_shadow, 1.0, 0.35);
    EXPECT_LT(after.relative_std, 0.5 * before.relative_std);
    EXPECT_GT(out.sun_gain, 0.15);
  }
  // Turned 90 degrees about the vertical (-y): the shadow is looked for where there is none.
  const Eigen::Vector3f s = sunDirection();
  solo::DayLightRemovalOptions wrong;
  wrong.sun_direction = Eigen::Vector3f(-s.z(), s.y(), s.x());
  const solo::DayLightRemoval out = solo::removeDayLight(day, scene.geometry, wrong);
  const double wrong_ratio = albedoSpread(out.albedo, lit).lit_over_shadow;
  std::printf("lit / shadow with the sun turned 90 degrees: %.3f\n", wrong_ratio);
  EXPECT_GT(wrong_ratio, 1.5);
  // Not finite: searched.
  solo::DayLightRemovalOptions nan_sun;
  nan_sun.sun_direction = Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN());
  const solo::DayLightRemoval searched = solo::removeDayLight(day, scene.geometry, nan_sun);
  ASSERT_EQ(searched.method, solo::DayLightMethod::SunAndSky);
  EXPECT_LT(angleDeg(searched.sun_direction, sunDirection()), 3.0);
}

TEST(DayLightRemoval, WithoutSunOnlyTheAmbientLightIsDividedOut) {
  const PlaneAndBox scene = planeAndBox();
  const cv::Mat day = renderDay(scene.geometry, sunDirection(), 0.f);  // overcast
  const solo::DayLightRemoval out = solo::removeDayLight(day, scene.geometry);
  EXPECT_EQ(out.method, solo::DayLightMethod::SkyOnly);
  EXPECT_TRUE(out.sun_direction.isZero());
  ASSERT_FALSE(out.report.notes.empty());
  EXPECT_NE(out.report.notes.front().find("no clear sun"), std::string::npos);
  EXPECT_LT(albedoSpread(out.albedo, sunlit(scene.geometry)).relative_std, 0.1);
}

TEST(DayLightRemoval, DegenerateInputsFallBackFinite) {
  const cv::Mat day(kHeight, kWidth, CV_32FC3, cv::Scalar::all(0.5));
  const auto all_finite = [](const cv::Mat& m) {
    return cv::checkRange(m, true, nullptr, 0.0, 1.0 + 1e-6);
  };
  // No mesh at all.
  solo::DayLightGeometry empty;
  empty.camera = planeAndBox().geometry.camera;
  const solo::DayLightRemoval none = solo::removeDayLight(day, empty);
  EXPECT_EQ(none.method, solo::DayLightMethod::DayImage);
  EXPECT_TRUE(all_finite(none.albedo));
  EXPECT_NE(none.report.notes.front().find("no mesh"), std::string::npos);

  // All sky: a mesh behind the camera.
  solo::DayLightGeometry behind = empty;
  behind.vertices = {-1, -1, -5, 1, -1, -5, 0, 1, -5};
  behind.triangles = {0, 1, 2};
  behind.triangle_instance = {kRoadInstance};
  const solo::DayLightRemoval sky = solo::removeDayLight(day, behind);
  EXPECT_EQ(sky.method, solo::DayLightMethod::DayImage);
  EXPECT_TRUE(all_finite(sky.albedo));

  // NaN normals and NaN or negative pixels: the faces' own normals, a finite albedo.
  PlaneAndBox scene = planeAndBox();
  scene.geometry.normals = cv::Mat(kHeight, kWidth, CV_32FC3, cv::Scalar::all(std::numeric_limits<float>::quiet_NaN()));
  cv::Mat noisy = renderDay(scene.geometry, sunDirection(), kSunIrradiance);
  noisy.at<cv::Vec3f>(150, 100) = cv::Vec3f(std::numeric_limits<float>::quiet_NaN(), -1.f, 0.f);
  const solo::DayLightRemoval nan = solo::removeDayLight(noisy, scene.geometry);
  EXPECT_TRUE(all_finite(nan.albedo));
}

namespace {

// The image-based removal's test scene: the PlaneAndBox road alone, the left half of the
// image road and the right half sidewalk (two materials on one plane), and its day image
// I_c = A_c (V S_c + L_c): L the sky radiance the sky pixels show (a uniform sky lights a
// plane with radiance A L), S the sun's term, V = 0 inside one rectangle on each half (cast
// shadows whose casters are not in the mesh). Lit / shadowed = (S + L) / L per channel:
// 5.0, 4.0 and 2.9.
constexpr int kSidewalkInstance = 8;
const cv::Vec3f kRoadAlbedo(0.30f, 0.30f, 0.32f), kSidewalkAlbedo(0.55f, 0.50f, 0.45f);
const cv::Vec3f kSkyRgb(0.25f, 0.32f, 0.45f), kSunRgb(1.00f, 0.95f, 0.85f);
const cv::Rect kRoadShadow(40, 120, 70, 40), kSidewalkShadow(200, 110, 80, 40);

struct TwoMaterialPlane {
  solo::DayLightGeometry geometry;
  cv::Mat day, truth;  // truth: the albedo, -1 where no surface
};

// The sun's visibility at (x, y) of twoMaterialPlane: 0 inside the shadow rectangles; with a
// penumbra the road shadow's right edge (x = 110) rises from 0 to 1 over `penumbra_px` as the
// share of the sun's disc a straight edge uncovers: with u from -1 to 1 across the penumbra,
// 1/2 + (u sqrt(1 - u^2) + asin u) / pi.
float sunVisibility(int x, int y, bool sidewalk, int penumbra_px) {
  const cv::Rect& shadow = sidewalk ? kSidewalkShadow : kRoadShadow;
  if (y < shadow.y || y >= shadow.y + shadow.height || x < shadow.x) return 1.f;
  if (sidewalk || penumbra_px == 0) return shadow.contains(cv::Point(x, y)) ? 0.f : 1.f;
  const double edge = kRoadShadow.x + kRoadShadow.width;
  const double u = std::clamp(2.0 * (x + 0.5 - edge) / penumbra_px, -1.0, 1.0);
  return static_cast<float>(0.5 + (u * std::sqrt(1 - u * u) + std::asin(u)) / 3.14159265358979323846);
}

// With shadow_ambient < 1 a shadowed pixel gets that share of the sky's light (its caster hides
// the rest), a penumbra pixel V of the way to all of it.
TwoMaterialPlane twoMaterialPlane(bool shadows, int penumbra_px = 0, float shadow_ambient = 1.f) {
  TwoMaterialPlane s;
  PlaneAndBox road;
  road.geometry.camera = planeAndBox().geometry.camera;
  addQuad(road, {{{-30, 1.5f, 2}, {30, 1.5f, 2}, {30, 1.5f, 60}, {-30, 1.5f, 60}}}, kRoadInstance);
  s.geometry = road.geometry;
  s.geometry.instances = cv::Mat(kHeight, kWidth, CV_32S, cv::Scalar(kRoadInstance));
  s.geometry.instances.colRange(kWidth / 2, kWidth).setTo(kSidewalkInstance);
  s.day = cv::Mat(kHeight, kWidth, CV_32FC3, kSkyRgb);
  s.truth = cv::Mat(kHeight, kWidth, CV_32FC3, cv::Scalar::all(-1));
  const solo::RayCaster caster(s.geometry.vertices, s.geometry.triangles);
  forEachSurfacePixel(s.geometry, caster, [&](int x, int y, const Eigen::Vector3f&, const Eigen::Vector3f&,
                                              const Eigen::Vector3f&) {
    const bool sidewalk = x >= kWidth / 2;
    const cv::Vec3f a = sidewalk ? kSidewalkAlbedo : kRoadAlbedo;
    const float v = shadows ? sunVisibility(x, y, sidewalk, penumbra_px) : 1.f;
    const float ambient = shadow_ambient + v * (1.f - shadow_ambient);
    for (int c = 0; c < 3; ++c) s.day.at<cv::Vec3f>(y, x)[c] = a[c] * (v * kSunRgb[c] + ambient * kSkyRgb[c]);
    s.truth.at<cv::Vec3f>(y, x) = a;
  });
  return s;
}

solo::DayLightRemovalOptions imageShadows() {
  solo::DayLightRemovalOptions o;
  o.shadows_from_image = true;
  return o;
}

// Whether (x, y) lies within `margin` px of a shadow rectangle's border or beyond row 106
// (z = 27 m): the plane ends at row 97 (z = 60 m), and up to 9 rows from there the ambient
// light's smoothing and the day image's mix the plane with the sky.
bool nearShadowEdge(int x, int y, int margin) {
  if (y < 106) return true;
  for (const cv::Rect& r : {kRoadShadow, kSidewalkShadow}) {
    const cv::Rect outer(r.x - margin, r.y - margin, r.width + 2 * margin, r.height + 2 * margin);
    const cv::Rect inner(r.x + margin, r.y + margin, r.width - 2 * margin, r.height - 2 * margin);
    if (outer.contains(cv::Point(x, y)) && !inner.contains(cv::Point(x, y))) return true;
  }
  return false;
}

// The largest relative error of `albedo` against the truth over the surface pixels away from
// the shadow edges, after each channel's least-squares gain (white balance and scale are free).
double largestRelativeError(const cv::Mat& albedo, const cv::Mat& truth) {
  std::array<double, 3> ee{}, et{};
  for (int y = 0; y < kHeight; ++y)
    for (int x = 0; x < kWidth; ++x)
      if (truth.at<cv::Vec3f>(y, x)[0] >= 0.f && !nearShadowEdge(x, y, 4))
        for (int c = 0; c < 3; ++c) {
          ee[static_cast<std::size_t>(c)] += double(albedo.at<cv::Vec3f>(y, x)[c]) * albedo.at<cv::Vec3f>(y, x)[c];
          et[static_cast<std::size_t>(c)] += double(albedo.at<cv::Vec3f>(y, x)[c]) * truth.at<cv::Vec3f>(y, x)[c];
        }
  double worst = 0;
  for (int y = 0; y < kHeight; ++y)
    for (int x = 0; x < kWidth; ++x)
      if (truth.at<cv::Vec3f>(y, x)[0] >= 0.f && !nearShadowEdge(x, y, 4))
        for (int c = 0; c < 3; ++c) {
          const double gain = et[static_cast<std::size_t>(c)] / ee[static_cast<std::size_t>(c)];
          const double t = truth.at<cv::Vec3f>(y, x)[c];
          worst = std::max(worst, std::abs(gain * albedo.at<cv::Vec3f>(y, x)[c] - t) / t);
        }
  return worst;
}

}  // namespace

TEST(DayLightRemoval, ImageShadowsOfUnseenCastersAreRelitOnTwoMaterials) {
  const TwoMaterialPlane scene = twoMaterialPlane(true);
  const double day_error = largestRelativeError(scene.day, scene.truth);
  const solo::DayLightRemoval out = solo::removeDayLight(scene.day, scene.geometry, imageShadows());
  ASSERT_EQ(out.method, solo::DayLightMethod::SunAndSky);
  const double error = largestRelativeError(out.albedo, scene.truth);
  std::printf("largest relative albedo error: day image %.3f, removed %.4f\n", day_error, error);
  EXPECT_GT(day_error, 0.5);  // the shadows keep a fifth to a third of the lit radiance
  EXPECT_LT(error, 0.01);
  // The sun's term on the plane, n.w_c = n.s / q_c, is S_c in units of the measured ambient
  // light: its colour is the sun's, 1 : 0.95 : 0.85.
  const Eigen::Vector3f sun_term = out.ambient_scale.cwiseInverse() * out.sun_direction.dot(Eigen::Vector3f(0, -1, 0));
  EXPECT_NEAR(sun_term[0] / sun_term[1], kSunRgb[0] / kSunRgb[1], 0.03);
  EXPECT_NEAR(sun_term[2] / sun_term[1], kSunRgb[2] / kSunRgb[1], 0.03);
}

// A penumbra 24 px wide (a caster tens of metres from the road) and shadows that get
// 60 % of the sky's light: across the penumbra and inside the shadows the albedo comes back
// within 5 % (3.6 % at the penumbra's foot, where the 3 px smoothing the visibility is solved
// from bends it; 85 % with each mode's visibility and the traced ambient alone).
TEST(DayLightRemoval, ImageShadowsRelitAcrossAWidePenumbraAndWithTheSkyTheCasterHides) {
  const TwoMaterialPlane scene = twoMaterialPlane(true, 24, 0.6f);
  const solo::DayLightRemoval out = solo::removeDayLight(scene.day, scene.geometry, imageShadows());
  ASSERT_EQ(out.method, solo::DayLightMethod::SunAndSky);
  // Each channel's least-squares gain over the plane's near part, then the largest error there
  // and along the penumbra's rows; only the shadows' hard edges (4 px) are left out.
  const auto hard_edge = [](int x, int y) {
    const cv::Rect& road = kRoadShadow;  // its right edge is the penumbra, 12 px either side of x = 110
    if (x >= road.x - 4 && x < road.x + road.width + 16 && y >= road.y - 4 && y < road.y + road.height + 4 &&
        (std::abs(y - road.y) < 4 || std::abs(y - (road.y + road.height)) < 4 || std::abs(x - road.x) < 4))
      return true;
    const cv::Rect& walk = kSidewalkShadow;
    const cv::Rect outer(walk.x - 4, walk.y - 4, walk.width + 8, walk.height + 8);
    const cv::Rect inner(walk.x + 4, walk.y + 4, walk.width - 8, walk.height - 8);
    return outer.contains(cv::Point(x, y)) && !inner.contains(cv::Point(x, y));
  };
  std::array<double, 3> ee{}, et{};
  for (int y = 106; y < kHeight; ++y)
    for (int x = 0; x < kWidth; ++x)
      if (scene.truth.at<cv::Vec3f>(y, x)[0] >= 0.f && !hard_edge(x, y))
        for (int c = 0; c < 3; ++c) {
          ee[static_cast<std::size_t>(c)] += double(out.albedo.at<cv::Vec3f>(y, x)[c]) * out.albedo.at<cv::Vec3f>(y, x)[c];
          et[static_cast<std::size_t>(c)] += double(out.albedo.at<cv::Vec3f>(y, x)[c]) * scene.truth.at<cv::Vec3f>(y, x)[c];
        }
  double worst = 0, worst_penumbra = 0;
  for (int y = 106; y < kHeight; ++y)
    for (int x = 0; x < kWidth; ++x)
      if (scene.truth.at<cv::Vec3f>(y, x)[0] >= 0.f && !hard_edge(x, y))
        for (int c = 0; c < 3; ++c) {
          const double t = scene.truth.at<cv::Vec3f>(y, x)[c];
          const double e = std::abs(et[static_cast<std::size_t>(c)] / ee[static_cast<std::size_t>(c)] *
                                        out.albedo.at<cv::Vec3f>(y, x)[c] - t) / t;
          worst = std::max(worst, e);
          const float v = sunVisibility(x, y, x >= kWidth / 2, 24);
          if (v > 0.f && v < 1.f) worst_penumbra = std::max(worst_penumbra, e);
        }
  std::printf("largest relative albedo error: %.4f, in the penumbra %.4f\n", worst, worst_penumbra);
  EXPECT_GT(worst_penumbra, 0.0) << "the penumbra is measured";
  EXPECT_LT(worst, 0.05);
}

TEST(DayLightRemoval, ImageShadowsLeaveAShadowlessSceneAsItIsUpToTheWhiteBalance) {
  const TwoMaterialPlane scene = twoMaterialPlane(false);
  const solo::DayLightRemoval out = solo::removeDayLight(scene.day, scene.geometry, imageShadows());
  EXPECT_EQ(out.method, solo::DayLightMethod::SkyOnly);
  EXPECT_NE(out.report.notes.front().find("no clear sun"), std::string::npos);
  std::array<double, 3> lo{1e9, 1e9, 1e9}, hi{0, 0, 0};
  for (int y = 0; y < kHeight; ++y)
    for (int x = 0; x < kWidth; ++x)
      if (scene.truth.at<cv::Vec3f>(y, x)[0] >= 0.f)
        for (int c = 0; c < 3; ++c) {
          const double ratio = out.albedo.at<cv::Vec3f>(y, x)[c] / scene.day.at<cv::Vec3f>(y, x)[c];
          lo[static_cast<std::size_t>(c)] = std::min(lo[static_cast<std::size_t>(c)], ratio);
          hi[static_cast<std::size_t>(c)] = std::max(hi[static_cast<std::size_t>(c)], ratio);
        }
  for (int c = 0; c < 3; ++c) EXPECT_LT(hi[static_cast<std::size_t>(c)] / lo[static_cast<std::size_t>(c)], 1.01) << c;
}

TEST(DayLightRemoval, ImageShadowsFallBackFiniteOnDegenerateInputs) {
  const cv::Mat day(kHeight, kWidth, CV_32FC3, cv::Scalar::all(0.5));
  solo::DayLightGeometry empty;
  empty.camera = planeAndBox().geometry.camera;
  EXPECT_EQ(solo::removeDayLight(day, empty, imageShadows()).method, solo::DayLightMethod::DayImage);
  PlaneAndBox scene = planeAndBox();
  scene.geometry.normals = cv::Mat(kHeight, kWidth, CV_32FC3, cv::Scalar::all(std::numeric_limits<float>::quiet_NaN()));
  cv::Mat noisy = renderDay(scene.geometry, sunDirection(), kSunIrradiance);
  noisy.at<cv::Vec3f>(150, 100) = cv::Vec3f(std::numeric_limits<float>::quiet_NaN(), -1.f, 0.f);
  EXPECT_TRUE(cv::checkRange(solo::removeDayLight(noisy, scene.geometry, imageShadows()).albedo, true, nullptr, 0.0,
                             1.0 + 1e-6));
}
