#include "solo/render/day_light_removal.h"

#include "solo/render/ray_caster.h"
#include "solo/render/sampler.h"

#include <solo/geometry/depth_mesh.h>

#include <Eigen/Geometry>
#include <opencv2/imgproc.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

namespace solo {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr float kAmbientFloor = 0.1f;      // of the surfaces' median: what no ray found bright
constexpr int kLabels = 34;                // Cityscapes labelIds 0..33
constexpr float kClassCostClip = 0.7f;     // the class cost's clip: albedos of one class vary more
constexpr int kAmbientRadiusPx = 4;        // smoothing of the traced ambient irradiance
// The least drop of the class cost per point (squared log units) that a sun must bring: a
// model the ambient light already explains has no shadows to find.
constexpr double kMinCostDrop = 0.003;
constexpr int kMinPairs = 200;             // pixel pairs below which no sun is searched
constexpr float kLogCostClip = 0.35f;      // robust cost: a log difference counts at most this much
constexpr float kClippedValue = 0.98f;     // a channel at or above it is clipped by the camera
constexpr float kDarkLuminance = 0.004f;   // below it a pixel's log is noise
constexpr float kContrastLog = 0.15f;      // a pair this far apart in log luminance has contrast
constexpr int kSmoothingPx = 3;            // box filter of the day image the pairs read (noise)
constexpr int kRoadLabel = 7, kSidewalkLabel = 8;
// Camera rays pass this far from the pixel centre: a depth mesh has a vertex at every pixel
// centre, and a ray through a vertex shared by six triangles may slip between them.
constexpr double kRayOffsetX = 0.13, kRayOffsetY = 0.07;

float luminance(const cv::Vec3f& c) { return 0.2126f * c[0] + 0.7152f * c[1] + 0.0722f * c[2]; }

int labelOfInstance(int instance) { return instance >= 1000 ? instance / 1000 : instance; }

// What the camera ray of every pixel hits: a point, a normal facing the camera, an instance.
struct SurfaceMap {
  int width = 0, height = 0;
  std::vector<Eigen::Vector3f> point, normal;
  std::vector<int> instance;
  std::vector<std::uint8_t> valid;
  std::int64_t valid_count = 0;
};

// A shadow or sky ray's start off the surface: depth noise folds the mesh by about 1 % of the
// distance, so the ray leaves along the normal and ignores the first 1 % of the depth.
struct RayStart {
  Eigen::Vector3f origin;
  float t_near;
};

RayStart rayStart(const Eigen::Vector3f& point, const Eigen::Vector3f& normal) {
  const float depth_m = point.z();
  return {point + normal * (0.002f * depth_m + 0.005f), 0.01f * depth_m};
}

// The normal map's normal at (x, y) when it is finite, unit and faces the camera; else `fallback`.
Eigen::Vector3f pixelNormal(const cv::Mat& normals, int x, int y, const Eigen::Vector3f& view,
                            const Eigen::Vector3f& fallback) {
  if (normals.empty()) return fallback;
  const cv::Vec3f v = normals.at<cv::Vec3f>(y, x);
  const Eigen::Vector3f n(v[0], v[1], v[2]);
  const float length = n.norm();
  if (!std::isfinite(length) || std::abs(length - 1.f) > 0.1f || n.dot(view) >= 0.f) return fallback;
  return n / length;
}

SurfaceMap castCameraRays(const DayLightGeometry& geometry, const RayCaster& caster) {
  SurfaceMap map;
  map.width = geometry.camera.width;
  map.height = geometry.camera.height;
  const std::size_t pixels = static_cast<std::size_t>(map.width) * static_cast<std::size_t>(map.height);
  map.point.assign(pixels, Eigen::Vector3f::Zero());
  map.normal.assign(pixels, Eigen::Vector3f::Zero());
  map.instance.assign(pixels, 0);
  map.valid.assign(pixels, 0);
  const bool use_normals = !geometry.normals.empty() && geometry.normals.type() == CV_32FC3 &&
                           geometry.normals.cols == map.width && geometry.normals.rows == map.height;
  const bool use_instances = !geometry.instances.empty() && geometry.instances.type() == CV_32S &&
                             geometry.instances.cols == map.width && geometry.instances.rows == map.height;
  const PinholeCamera& cam = geometry.camera;
  tbb::parallel_for(0, map.height, [&](int y) {
    for (int x = 0; x < map.width; ++x) {
      const Eigen::Vector3f view = Eigen::Vector3f(static_cast<float>((x + kRayOffsetX - cam.cx) / cam.fx),
                                                   static_cast<float>((y + kRayOffsetY - cam.cy) / cam.fy), 1.f)
                                       .normalized();
      const RayHit hit = caster.intersect(Eigen::Vector3f::Zero(), view);
      const float g_length = hit.geometric_normal.norm();
      if (!hit.hit || !std::isfinite(hit.distance) || !(g_length > 0.f)) continue;
      Eigen::Vector3f g = hit.geometric_normal / g_length;
      if (g.dot(view) > 0.f) g = -g;
      const std::size_t i = static_cast<std::size_t>(y) * map.width + x;
      map.point[i] = view * hit.distance;
      map.normal[i] = use_normals ? pixelNormal(geometry.normals, x, y, view, g) : g;
      map.instance[i] = use_instances ? geometry.instances.at<int>(y, x)
                        : hit.triangle < geometry.triangle_instance.size() ? geometry.triangle_instance[hit.triangle]
                                                                            : 0;
      map.valid[i] = map.point[i].z() > 0.f ? 1 : 0;
    }
  });
  for (const std::uint8_t v : map.valid) map.valid_count += v;
  return map;
}

// Up: the mean normal of the road and sidewalk when they cover 1 % of the pixels and lean
// upward (-y), else -y (a level camera).
Eigen::Vector3f upDirection(const SurfaceMap& map) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  std::int64_t count = 0;
  for (std::size_t i = 0; i < map.valid.size(); ++i) {
    const int label = labelOfInstance(map.instance[i]);
    if (!map.valid[i] || (label != kRoadLabel && label != kSidewalkLabel)) continue;
    sum += map.normal[i].cast<double>();
    ++count;
  }
  const Eigen::Vector3f level(0.f, -1.f, 0.f);
  if (count < static_cast<std::int64_t>(map.valid.size() / 100) || !(sum.norm() > 0)) return level;
  const Eigen::Vector3f up = sum.normalized().cast<float>();
  return up.dot(level) > 0.9f ? up : level;
}

// Two unit vectors completing n to an orthonormal frame.
std::pair<Eigen::Vector3f, Eigen::Vector3f> tangentFrame(const Eigen::Vector3f& n) {
  const Eigen::Vector3f a = std::abs(n.x()) < 0.9f ? Eigen::Vector3f::UnitX() : Eigen::Vector3f::UnitY();
  const Eigen::Vector3f t = n.cross(a).normalized();
  return {t, n.cross(t)};
}

// The sky's radiance by elevation above the horizon, read from the pixels that show no surface
// (the sky) in kSkyBins bins; a bin without pixels takes the nearest filled one. Without sky
// pixels the sky is grey at the 95th percentile of the surfaces' luminance.
struct SkyRadiance {
  static constexpr int kSkyBins = 9;
  std::array<Eigen::Vector3f, kSkyBins> bins;
  bool measured = false;
  Eigen::Vector3f at(const Eigen::Vector3f& dir, const Eigen::Vector3f& up) const {
    const float elevation = std::asin(std::clamp(dir.dot(up), 0.f, 1.f));
    return bins[static_cast<std::size_t>(std::min(kSkyBins - 1, static_cast<int>(elevation / (kPi / 2) * kSkyBins)))];
  }
};

SkyRadiance skyRadiance(const cv::Mat& day, const SurfaceMap& map, const PinholeCamera& cam, const Eigen::Vector3f& up) {
  std::array<Eigen::Vector3d, SkyRadiance::kSkyBins> sum;
  std::array<std::int64_t, SkyRadiance::kSkyBins> count{};
  sum.fill(Eigen::Vector3d::Zero());
  std::vector<float> surface_luminance;
  for (int y = 0; y < map.height; ++y)
    for (int x = 0; x < map.width; ++x) {
      const cv::Vec3f c = day.at<cv::Vec3f>(y, x);
      if (map.valid[static_cast<std::size_t>(y) * map.width + x]) {
        surface_luminance.push_back(luminance(c));
        continue;
      }
      const Eigen::Vector3f view =
          Eigen::Vector3f(static_cast<float>((x - cam.cx) / cam.fx), static_cast<float>((y - cam.cy) / cam.fy), 1.f)
              .normalized();
      const float elevation = std::asin(std::clamp(view.dot(up), -1.f, 1.f));
      if (elevation <= 0.f || !std::isfinite(c[0] + c[1] + c[2])) continue;
      const int bin = std::min(SkyRadiance::kSkyBins - 1, static_cast<int>(elevation / (kPi / 2) * SkyRadiance::kSkyBins));
      sum[static_cast<std::size_t>(bin)] += Eigen::Vector3d(c[0], c[1], c[2]);
      ++count[static_cast<std::size_t>(bin)];
    }
  SkyRadiance sky;
  float grey = 1.f;
  if (!surface_luminance.empty()) {
    const auto p95 = surface_luminance.begin() + static_cast<std::ptrdiff_t>(surface_luminance.size() * 95 / 100);
    std::nth_element(surface_luminance.begin(), p95, surface_luminance.end());
    grey = std::max(*p95, 1e-3f);
  }
  sky.bins.fill(Eigen::Vector3f::Constant(grey));
  for (int b = 0; b < SkyRadiance::kSkyBins; ++b) {
    int nearest = -1;
    for (int d = 0; d < SkyRadiance::kSkyBins && nearest < 0; ++d)
      for (const int c : {b - d, b + d})
        if (c >= 0 && c < SkyRadiance::kSkyBins && count[static_cast<std::size_t>(c)] >= 20 && nearest < 0) nearest = c;
    if (nearest < 0) continue;
    sky.measured = true;
    sky.bins[static_cast<std::size_t>(b)] =
        (sum[static_cast<std::size_t>(nearest)] / static_cast<double>(count[static_cast<std::size_t>(nearest)])).cast<float>();
  }
  return sky;
}

// What the ambient rays read: the day image (smoothed), the sky, the camera, the radiance of
// the ground beyond the mesh (the surfaces' median) and of the surfaces the camera does not see
// (their 25th percentile: mostly the sides of things turned away from the camera and the sun).
struct AmbientSources {
  const cv::Mat& day;
  const SkyRadiance& sky;
  const PinholeCamera& camera;
  Eigen::Vector3f ground, unseen;
  Eigen::Vector3f up;
};

// The radiance arriving along a ray from `start`: the sky above the horizon where it escapes,
// the day image's pixel where it hits a surface the camera sees there, else `unseen`.
Eigen::Vector3f incomingRadiance(const SurfaceMap& map, const RayCaster& caster, const AmbientSources& src,
                                 const RayStart& start, const Eigen::Vector3f& dir) {
  const RayHit hit = caster.intersect(start.origin, dir, start.t_near);
  if (!hit.hit) return dir.dot(src.up) > 0.f ? src.sky.at(dir, src.up) : src.ground;
  const Eigen::Vector3f h = start.origin + dir * hit.distance;
  if (!(h.z() > 0.f)) return src.unseen;
  const Eigen::Vector2d pixel = src.camera.project(h.cast<double>());
  const int u = static_cast<int>(std::lround(pixel.x())), v = static_cast<int>(std::lround(pixel.y()));
  if (u < 0 || v < 0 || u >= map.width || v >= map.height) return src.unseen;
  const std::size_t j = static_cast<std::size_t>(v) * map.width + u;
  if (!map.valid[j] || std::abs(map.point[j].z() - h.z()) > 0.05f * h.z()) return src.unseen;
  const cv::Vec3f c = src.day.at<cv::Vec3f>(v, u);
  return {c[0], c[1], c[2]};
}

// The ambient irradiance at pixel i in image units: the mean radiance over `rays` stratified
// cosine-weighted directions about its normal, rotated per pixel.
Eigen::Vector3f ambientAt(const SurfaceMap& map, std::size_t i, const RayCaster& caster, const AmbientSources& src,
                          int rays) {
  const Eigen::Vector3f& n = map.normal[i];
  const auto [t, b] = tangentFrame(n);
  const RayStart start = rayStart(map.point[i], n);
  Pcg32 rng(0x5eed, i);
  const float rotate_u = rng.uniform(), rotate_v = rng.uniform();
  const int columns = std::max(1, static_cast<int>(std::lround(std::sqrt(static_cast<double>(rays)))));
  Eigen::Vector3f sum = Eigen::Vector3f::Zero();
  for (int j = 0; j < rays; ++j) {
    const float u = std::fmod((static_cast<float>(j % columns) + 0.5f) / columns + rotate_u, 1.f);
    const float v = std::fmod((static_cast<float>(j) + 0.5f) / rays + rotate_v, 1.f);
    const float radius = std::sqrt(u), phi = static_cast<float>(2 * kPi) * v;
    const Eigen::Vector3f dir =
        (t * (radius * std::cos(phi)) + b * (radius * std::sin(phi)) + n * std::sqrt(std::max(0.f, 1.f - u)))
            .normalized();
    sum += incomingRadiance(map, caster, src, start, dir);
  }
  return sum / static_cast<float>(rays);
}

// The mean of the traced values within `radius` px of pixel i that lie on its instance with a
// normal within 25 degrees (else of all traced values there; else `fallback`).
Eigen::Vector3f neighbourMean(const SurfaceMap& map, const std::vector<Eigen::Vector3f>& traced, int x, int y,
                              int radius, const Eigen::Vector3f& fallback) {
  const int w = map.width, h = map.height;
  const std::size_t i = static_cast<std::size_t>(y) * w + x;
  Eigen::Vector3f sum = Eigen::Vector3f::Zero(), any_sum = Eigen::Vector3f::Zero();
  int count = 0, any_count = 0;
  for (int yy = std::max(0, y - radius); yy <= std::min(h - 1, y + radius); ++yy)
    for (int xx = std::max(0, x - radius); xx <= std::min(w - 1, x + radius); ++xx) {
      const std::size_t j = static_cast<std::size_t>(yy) * w + xx;
      if (traced[j].x() < 0.f) continue;
      any_sum += traced[j];
      ++any_count;
      if (map.instance[j] == map.instance[i] && map.normal[j].dot(map.normal[i]) > 0.9f) {
        sum += traced[j];
        ++count;
      }
    }
  if (count > 0) return sum / static_cast<float>(count);
  return any_count > 0 ? any_sum / static_cast<float>(any_count) : fallback;
}

// Ambient irradiance per pixel: traced at every second pixel in x and y, smoothed over the
// traced pixels within kAmbientRadiusPx on one surface (the ambient light varies slowly; a
// few rays per pixel do not), then each pixel takes the mean of the smoothed ones within 2 px.
std::vector<Eigen::Vector3f> ambientIrradiance(const SurfaceMap& map, const RayCaster& caster,
                                               const AmbientSources& src, int rays) {
  const int w = map.width, h = map.height;
  std::vector<Eigen::Vector3f> traced(map.valid.size(), Eigen::Vector3f::Constant(-1.f));
  tbb::parallel_for(0, (h + 1) / 2, [&](int row) {
    const int y = 2 * row;
    for (int x = 0; x < w; x += 2) {
      const std::size_t i = static_cast<std::size_t>(y) * w + x;
      if (map.valid[i]) traced[i] = ambientAt(map, i, caster, src, rays);
    }
  });
  std::vector<Eigen::Vector3f> smoothed(map.valid.size(), Eigen::Vector3f::Constant(-1.f));
  tbb::parallel_for(0, (h + 1) / 2, [&](int row) {
    const int y = 2 * row;
    for (int x = 0; x < w; x += 2)
      if (map.valid[static_cast<std::size_t>(y) * w + x])
        smoothed[static_cast<std::size_t>(y) * w + x] = neighbourMean(map, traced, x, y, kAmbientRadiusPx, src.ground);
  });
  std::vector<Eigen::Vector3f> ambient(map.valid.size(), src.ground);
  tbb::parallel_for(0, h, [&](int y) {
    for (int x = 0; x < w; ++x)
      if (map.valid[static_cast<std::size_t>(y) * w + x])
        ambient[static_cast<std::size_t>(y) * w + x] = neighbourMean(map, smoothed, x, y, 2, src.ground);
  });
  return ambient;
}

// The surfaces' radiance per channel at `percent` (of the pixels that show a surface).
Eigen::Vector3f surfacePercentile(const cv::Mat& day, const SurfaceMap& map, int percent) {
  std::array<std::vector<float>, 3> values;
  for (std::size_t i = 0; i < map.valid.size(); ++i) {
    if (!map.valid[i]) continue;
    const cv::Vec3f c = day.at<cv::Vec3f>(static_cast<int>(i / map.width), static_cast<int>(i % map.width));
    for (int k = 0; k < 3; ++k) values[k].push_back(c[k]);
  }
  Eigen::Vector3f out = Eigen::Vector3f::Constant(0.1f);
  for (int k = 0; k < 3; ++k) {
    if (values[k].empty()) continue;
    auto at = values[k].begin() + static_cast<std::ptrdiff_t>(values[k].size() * static_cast<std::size_t>(percent) / 100);
    std::nth_element(values[k].begin(), at, values[k].end());
    out[k] = std::max(*at, 1e-3f);
  }
  return out;
}

// A pixel that scores sun candidates: where its shadow ray starts, its normal, ambient
// irradiance and log intensity (per channel and luminance).
struct SamplePoint {
  RayStart start;
  Eigen::Vector3f normal;
  std::array<float, 4> ambient;    // r, g, b, luminance
  std::array<float, 4> log_value;  // r, g, b, luminance
  int label;                       // Cityscapes labelId, index into the class sums
};

struct PairSet {
  std::vector<SamplePoint> points;
  std::vector<std::pair<int, int>> pairs;  // indices into points
};

// Whether pixel i can score: valid, neither clipped nor dark in the day image.
bool usablePixel(const SurfaceMap& map, const cv::Mat& day, std::size_t i) {
  if (!map.valid[i]) return false;
  const cv::Vec3f c = day.at<cv::Vec3f>(static_cast<int>(i / map.width), static_cast<int>(i % map.width));
  if (!(c[0] < kClippedValue && c[1] < kClippedValue && c[2] < kClippedValue)) return false;
  return luminance(c) > kDarkLuminance && c[0] > 0.f && c[1] > 0.f && c[2] > 0.f;
}

SamplePoint samplePoint(const SurfaceMap& map, const cv::Mat& day, const std::vector<Eigen::Vector3f>& ambient,
                        std::size_t i) {
  const cv::Vec3f c = day.at<cv::Vec3f>(static_cast<int>(i / map.width), static_cast<int>(i % map.width));
  const Eigen::Vector3f& e = ambient[i];
  return {rayStart(map.point[i], map.normal[i]),
          map.normal[i],
          {e[0], e[1], e[2], luminance(cv::Vec3f(e[0], e[1], e[2]))},
          {std::log(c[0]), std::log(c[1]), std::log(c[2]), std::log(luminance(c))},
          std::clamp(labelOfInstance(map.instance[i]), 0, kLabels - 1)};
}

// `count` pairs of usable pixels 3 to 32 px apart on one instance: where the albedo is most
// likely the same, so that their intensity ratio is the ratio of their shading. Half of them
// differ by more than kContrastLog in log luminance (a shadow edge, two faces of a box: what
// tells sun directions apart), half are drawn as they come. `day` is the smoothed day image.
PairSet samplePairs(const SurfaceMap& map, const cv::Mat& day, const std::vector<Eigen::Vector3f>& ambient, int count,
                    std::uint64_t seed) {
  PairSet set;
  Pcg32 rng(seed, 17);
  const int w = map.width, h = map.height;
  const std::int64_t max_tries = 200 * static_cast<std::int64_t>(count);
  int plain = 0, contrast = 0;
  for (std::int64_t attempt = 0; attempt < max_tries && plain + contrast < count; ++attempt) {
    const int xa = static_cast<int>(rng.uniform() * w), ya = static_cast<int>(rng.uniform() * h);
    const float radius = 3.f + 29.f * rng.uniform(), angle = static_cast<float>(2 * kPi) * rng.uniform();
    const int xb = xa + static_cast<int>(std::lround(radius * std::cos(angle)));
    const int yb = ya + static_cast<int>(std::lround(radius * std::sin(angle)));
    if (xb < 0 || yb < 0 || xb >= w || yb >= h) continue;
    const std::size_t a = static_cast<std::size_t>(ya) * w + xa, b = static_cast<std::size_t>(yb) * w + xb;
    if (!usablePixel(map, day, a) || !usablePixel(map, day, b) || map.instance[a] != map.instance[b]) continue;
    const SamplePoint pa = samplePoint(map, day, ambient, a), pb = samplePoint(map, day, ambient, b);
    const bool differ = std::abs(pa.log_value[3] - pb.log_value[3]) > kContrastLog;
    if (differ ? 2 * contrast >= count : 2 * plain >= count) continue;
    ++(differ ? contrast : plain);
    set.points.push_back(pa);
    set.points.push_back(pb);
    const int first = static_cast<int>(set.points.size()) - 2;
    set.pairs.emplace_back(first, first + 1);
  }
  return set;
}

// Direct sun shading V * max(0, n.s) of every point.
std::vector<float> directShading(const PairSet& set, const RayCaster& caster, const Eigen::Vector3f& sun) {
  std::vector<float> direct(set.points.size(), 0.f);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, set.points.size(), 256),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      for (std::size_t i = range.begin(); i < range.end(); ++i) {
                        const SamplePoint& p = set.points[i];
                        const float cosine = p.normal.dot(sun);
                        if (cosine <= 0.f) continue;
                        if (!caster.occluded(p.start.origin, sun, p.start.t_near,
                                             std::numeric_limits<float>::infinity()))
                          direct[i] = cosine;
                      }
                    });
  return direct;
}

// The robust spread of de-lit log intensities within each class: the sum over points of the
// clipped squared difference to their class's mean.
double classCost(const PairSet& set, const std::vector<float>& direct, float q, int channel) {
  std::array<double, kLabels> sum{};
  std::array<int, kLabels> count{};
  std::vector<float> delit(set.points.size());
  for (std::size_t i = 0; i < set.points.size(); ++i) {
    const SamplePoint& p = set.points[i];
    delit[i] = p.log_value[channel] - std::log(direct[i] + q * p.ambient[channel]);
    sum[static_cast<std::size_t>(p.label)] += delit[i];
    ++count[static_cast<std::size_t>(p.label)];
  }
  double cost = 0;
  const float clip = kClassCostClip * kClassCostClip;
  for (std::size_t i = 0; i < set.points.size(); ++i) {
    const auto label = static_cast<std::size_t>(set.points[i].label);
    const float d = delit[i] - static_cast<float>(sum[label] / count[label]);
    cost += std::min(d * d, clip);
  }
  return cost;
}

// The ambient scales q a candidate tries: log-spaced from 0.02 to 20 (sun irradiance per unit
// of the image's radiance; about 1 for a camera that exposes a white surface in the sun to 1).
std::vector<float> ambientScaleGrid(int count) {
  std::vector<float> grid;
  for (int i = 0; i < count; ++i)
    grid.push_back(static_cast<float>(0.02 * std::pow(1000.0, static_cast<double>(i) / (count - 1))));
  return grid;
}

struct CandidateScore {
  double elevation_rad = 0, azimuth_rad = 0;
  double cost = std::numeric_limits<double>::infinity();
  float ambient_scale = 0;
};

// Directions about `up`: elevation above the horizon and azimuth from the camera's x axis.
struct HemisphereFrame {
  Eigen::Vector3f up, east, north;
  explicit HemisphereFrame(const Eigen::Vector3f& up_) : up(up_) {
    east = (Eigen::Vector3f::UnitX() - up * up.x()).normalized();
    north = up.cross(east);
  }
  Eigen::Vector3f direction(double elevation_rad, double azimuth_rad) const {
    const float ce = static_cast<float>(std::cos(elevation_rad));
    return (east * (ce * static_cast<float>(std::cos(azimuth_rad))) +
            north * (ce * static_cast<float>(std::sin(azimuth_rad))) + up * static_cast<float>(std::sin(elevation_rad)))
        .normalized();
  }
};

CandidateScore scoreCandidate(const PairSet& set, const RayCaster& caster, const HemisphereFrame& frame,
                              double elevation_rad, double azimuth_rad, const std::vector<float>& scales) {
  CandidateScore score;
  score.elevation_rad = elevation_rad;
  score.azimuth_rad = azimuth_rad;
  const std::vector<float> direct = directShading(set, caster, frame.direction(elevation_rad, azimuth_rad));
  for (const float q : scales) {
    const double cost = classCost(set, direct, q, 3);
    if (cost < score.cost) {
      score.cost = cost;
      score.ambient_scale = q;
    }
  }
  return score;
}

// The candidate grid's best few, by cost.
std::vector<CandidateScore> coarseSearch(const PairSet& set, const RayCaster& caster, const HemisphereFrame& frame,
                                         const DayLightRemovalOptions& o, std::size_t keep) {
  const double step = o.coarse_step_deg * kPi / 180;
  const std::vector<float> scales = ambientScaleGrid(10);
  std::vector<std::pair<double, double>> directions;
  for (double elevation = o.min_elevation_deg * kPi / 180; elevation < kPi / 2; elevation += step) {
    const double azimuth_step = step / std::max(0.25, std::cos(elevation));  // about even on the sphere
    for (double azimuth = 0; azimuth < 2 * kPi - 1e-9; azimuth += azimuth_step) directions.emplace_back(elevation, azimuth);
  }
  std::vector<CandidateScore> scores(directions.size());
  for (std::size_t d = 0; d < directions.size(); ++d)
    scores[d] = scoreCandidate(set, caster, frame, directions[d].first, directions[d].second, scales);
  std::sort(scores.begin(), scores.end(),
            [](const CandidateScore& a, const CandidateScore& b) { return a.cost < b.cost; });
  if (scores.size() > keep) scores.resize(keep);
  return scores;
}

// Pattern search from `start`: the best of the 8 neighbours at the current step, halving the
// step when none is better, down to o.final_step_deg.
CandidateScore refineCandidate(const PairSet& set, const RayCaster& caster, const HemisphereFrame& frame,
                               const CandidateScore& start, const DayLightRemovalOptions& o) {
  const std::vector<float> scales = ambientScaleGrid(16);
  const double min_elevation = o.min_elevation_deg * kPi / 180;
  CandidateScore best = scoreCandidate(set, caster, frame, start.elevation_rad, start.azimuth_rad, scales);
  for (double step = 0.5 * o.coarse_step_deg * kPi / 180; step >= o.final_step_deg * kPi / 180 - 1e-12;) {
    CandidateScore next = best;
    for (int de = -1; de <= 1; ++de)
      for (int da = -1; da <= 1; ++da) {
        if (de == 0 && da == 0) continue;
        const double elevation = std::clamp(best.elevation_rad + de * step, min_elevation, kPi / 2 - 1e-3);
        const double azimuth = best.azimuth_rad + da * step / std::max(0.2, std::cos(best.elevation_rad));
        const CandidateScore s = scoreCandidate(set, caster, frame, elevation, azimuth, scales);
        if (s.cost < next.cost) next = s;
      }
    if (next.cost < best.cost)
      best = next;
    else
      step *= 0.5;
  }
  return best;
}

// The ambient scale of each channel for the found sun: the finer grid's best.
Eigen::Vector3f channelAmbientScales(const PairSet& set, const std::vector<float>& direct) {
  const std::vector<float> scales = ambientScaleGrid(64);
  Eigen::Vector3f out = Eigen::Vector3f::Ones();
  for (int c = 0; c < 3; ++c) {
    double best = std::numeric_limits<double>::infinity();
    for (const float q : scales) {
      const double cost = classCost(set, direct, q, c);
      if (cost < best) {
        best = cost;
        out[c] = q;
      }
    }
  }
  return out;
}

// The albedo I / (V max(0, n.s) + q E) at every pixel, E the ambient irradiance floored at a
// share of the surfaces' median; sky pixels keep the day image.
cv::Mat divideShading(const cv::Mat& day, const SurfaceMap& map, const std::vector<Eigen::Vector3f>& ambient,
                      const Eigen::Vector3f& floor, const RayCaster& caster, const Eigen::Vector3f& sun, bool with_sun,
                      const Eigen::Vector3f& q) {
  cv::Mat albedo = day.clone();
  tbb::parallel_for(0, map.height, [&](int y) {
    for (int x = 0; x < map.width; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * map.width + x;
      if (!map.valid[i]) continue;
      float direct = 0.f;
      const float cosine = map.normal[i].dot(sun);
      if (with_sun && cosine > 0.f) {
        const RayStart start = rayStart(map.point[i], map.normal[i]);
        if (!caster.occluded(start.origin, sun, start.t_near, std::numeric_limits<float>::infinity())) direct = cosine;
      }
      cv::Vec3f& a = albedo.at<cv::Vec3f>(y, x);
      for (int c = 0; c < 3; ++c) a[c] = std::max(a[c], 0.f) / (direct + q[c] * std::max(ambient[i][c], floor[c]));
    }
  });
  return albedo;
}

// Per-channel gains that make the road and sidewalk grey (their median per channel), or, with
// less than 0.5 % of the pixels on them, the mean of the non-sky pixels grey; then a scale that
// puts the non-sky median luminance at `median_reflectance`. Applied in place, clamped to [0, 1].
Eigen::Vector3f whiteBalance(cv::Mat& albedo, const SurfaceMap& map, double median_reflectance, StageReport& report) {
  std::array<std::vector<float>, 3> road, all;
  for (std::size_t i = 0; i < map.valid.size(); ++i) {
    if (!map.valid[i]) continue;
    const cv::Vec3f a = albedo.at<cv::Vec3f>(static_cast<int>(i / map.width), static_cast<int>(i % map.width));
    if (!std::isfinite(a[0] + a[1] + a[2])) continue;
    const int label = labelOfInstance(map.instance[i]);
    for (int c = 0; c < 3; ++c) {
      all[c].push_back(a[c]);
      if (label == kRoadLabel || label == kSidewalkLabel) road[c].push_back(a[c]);
    }
  }
  const auto median = [](std::vector<float> v) {
    if (v.empty()) return 0.f;
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
    return v[v.size() / 2];
  };
  const auto mean = [](const std::vector<float>& v) {
    double s = 0;
    for (const float x : v) s += x;
    return v.empty() ? 0.f : static_cast<float>(s / static_cast<double>(v.size()));
  };
  const bool use_road = road[0].size() >= all[0].size() / 200 && !road[0].empty();
  Eigen::Vector3f reference;
  for (int c = 0; c < 3; ++c) reference[c] = use_road ? median(road[c]) : mean(all[c]);
  report.notes.push_back(use_road ? "white balance: the road and sidewalk are grey"
                                  : "white balance: grey world (too little road and sidewalk)");
  Eigen::Vector3f gains = Eigen::Vector3f::Ones();
  if (reference.minCoeff() > 0.f) gains = Eigen::Vector3f::Constant(reference.mean()).cwiseQuotient(reference);
  std::vector<float> luminances;
  for (std::size_t i = 0; i < all[0].size(); ++i)
    luminances.push_back(luminance(cv::Vec3f(all[0][i] * gains[0], all[1][i] * gains[1], all[2][i] * gains[2])));
  const float median_luminance = median(luminances);
  if (median_luminance > 0.f) gains *= static_cast<float>(median_reflectance) / median_luminance;
  albedo.forEach<cv::Vec3f>([&gains](cv::Vec3f& a, const int*) {
    for (int c = 0; c < 3; ++c) a[c] = std::isfinite(a[c]) ? std::clamp(a[c] * gains[c], 0.f, 1.f) : 0.f;
  });
  return gains;
}

// The linearised day image, white-balanced and scaled, with the note why.
void keepDayImage(const cv::Mat& day, const SurfaceMap& map, const DayLightRemovalOptions& o, const std::string& why,
                  DayLightRemoval& out) {
  out.method = DayLightMethod::DayImage;
  out.albedo = day.clone();
  out.report.notes.push_back(why + ": the day image stands in for the albedo");
  out.white_balance = whiteBalance(out.albedo, map, o.median_reflectance, out.report);
}

// Finds the sun (coarse grid, then pattern search from the best three) and whether it explains
// enough: fills out.sun_direction, sun_gain, ambient_scale and method. `smooth`: the day image
// box-filtered against its noise.
void findSun(const SurfaceMap& map, const cv::Mat& smooth, const std::vector<Eigen::Vector3f>& ambient,
             const RayCaster& caster, const HemisphereFrame& frame, const DayLightRemovalOptions& o,
             DayLightRemoval& out) {
  const PairSet coarse_pairs = samplePairs(map, smooth, ambient, o.search_pairs, o.seed);
  const PairSet pairs = samplePairs(map, smooth, ambient, o.refine_pairs, o.seed + 1);
  out.report.add("pairs", static_cast<std::int64_t>(pairs.pairs.size()));
  const std::vector<float> no_sun(pairs.points.size(), 0.f);
  const double ambient_only_cost = classCost(pairs, no_sun, 1.f, 3);
  CandidateScore best;
  if (static_cast<int>(pairs.pairs.size()) >= kMinPairs)
    for (const CandidateScore& start : coarseSearch(coarse_pairs, caster, frame, o, 3)) {
      const CandidateScore refined = refineCandidate(pairs, caster, frame, start, o);
      if (refined.cost < best.cost) best = refined;
    }
  out.sun_gain = ambient_only_cost > 0 && std::isfinite(best.cost) ? 1.0 - best.cost / ambient_only_cost : 0.0;
  const double drop_per_point = (ambient_only_cost - best.cost) / std::max<std::size_t>(1, pairs.points.size());
  if (out.sun_gain >= o.min_sun_gain && drop_per_point >= kMinCostDrop) {
    out.method = DayLightMethod::SunAndSky;
    out.sun_direction = frame.direction(best.elevation_rad, best.azimuth_rad);
    out.ambient_scale = channelAmbientScales(pairs, directShading(pairs, caster, out.sun_direction));
    return;
  }
  out.method = DayLightMethod::SkyOnly;
  out.ambient_scale = Eigen::Vector3f::Ones();
  char note[240];
  if (static_cast<int>(pairs.pairs.size()) < kMinPairs)
    std::snprintf(note, sizeof note, "no clear sun: %d pixel pairs on one surface (< %d); the ambient light alone "
                  "is divided out", static_cast<int>(pairs.pairs.size()), kMinPairs);
  else
    std::snprintf(note, sizeof note,
                  "no clear sun: the best direction lowers the ambient-only cost by %.0f %% (< %.0f %%); "
                  "the ambient light alone is divided out",
                  100 * out.sun_gain, 100 * o.min_sun_gain);
  out.report.notes.push_back(note);
}

void writeReport(const Eigen::Vector3f& up, DayLightRemoval& out) {
  out.report.add("method", std::string(dayLightMethodName(out.method)));
  out.report.add("sun_gain", out.sun_gain);
  if (out.method == DayLightMethod::SunAndSky) {
    out.report.add("sun_elevation", std::asin(std::clamp(out.sun_direction.dot(up), -1.f, 1.f)) * 180 / kPi, "deg");
    for (int k = 0; k < 3; ++k) out.report.add("sun_direction_" + std::string(1, "xyz"[k]), out.sun_direction[k]);
  }
  for (int c = 0; c < 3; ++c) {
    out.report.add("ambient_scale_" + std::string(1, "rgb"[c]), out.ambient_scale[c]);
    out.report.add("gain_" + std::string(1, "rgb"[c]), out.white_balance[c]);
  }
}

}  // namespace

const char* dayLightMethodName(DayLightMethod method) {
  switch (method) {
    case DayLightMethod::SunAndSky: return "sun-and-sky";
    case DayLightMethod::SkyOnly: return "sky-only";
    case DayLightMethod::DayImage: return "day-image";
  }
  return "day-image";
}

DayLightGeometry dayLightGeometry(const DepthMesh& depth_mesh, const PinholeCamera& camera, const cv::Mat& normals) {
  DayLightGeometry g;
  g.camera = camera;
  g.normals = normals;
  const SurfaceMesh& mesh = depth_mesh.mesh;
  g.vertices.reserve(3 * mesh.n_vertices());
  for (const auto vh : mesh.vertices()) {
    const auto p = mesh.point(vh);
    for (int k = 0; k < 3; ++k) g.vertices.push_back(static_cast<float>(p[k]));
  }
  const bool has_instance = depth_mesh.properties.instance.is_valid();
  for (const auto fh : mesh.faces()) {
    int instance = 0;
    for (const auto vh : mesh.fv_range(fh)) {
      g.triangles.push_back(static_cast<std::uint32_t>(vh.idx()));
      if (has_instance && instance == 0) instance = mesh.property(depth_mesh.properties.instance, vh);
    }
    g.triangle_instance.push_back(instance);
  }
  return g;
}

DayLightRemoval removeDayLight(const cv::Mat& day_linear, const DayLightGeometry& geometry,
                               const DayLightRemovalOptions& o) {
  const Stopwatch clock;
  DayLightRemoval out;
  out.report.name = "day_light";
  CV_Assert(day_linear.type() == CV_32FC3 && day_linear.cols == geometry.camera.width &&
            day_linear.rows == geometry.camera.height);
  cv::Mat day = day_linear.clone();  // NaN, infinite and negative values read as 0
  day.forEach<cv::Vec3f>([](cv::Vec3f& c, const int*) {
    for (int k = 0; k < 3; ++k) c[k] = std::isfinite(c[k]) ? std::max(c[k], 0.f) : 0.f;
  });
  SurfaceMap map;
  map.width = day_linear.cols;
  map.height = day_linear.rows;
  map.valid.assign(static_cast<std::size_t>(map.width) * map.height, 0);
  map.instance.assign(map.valid.size(), 0);
  const bool has_mesh = !geometry.triangles.empty() && geometry.triangles.size() % 3 == 0 &&
                        geometry.triangle_instance.size() * 3 == geometry.triangles.size();
  if (!has_mesh) {
    keepDayImage(day, map, o, "no mesh", out);
    writeReport(Eigen::Vector3f(0.f, -1.f, 0.f), out);
    out.report.seconds = clock.seconds();
    return out;
  }
  const RayCaster caster(geometry.vertices, geometry.triangles);
  map = castCameraRays(geometry, caster);
  out.report.add("surface_pixels", map.valid_count);
  if (map.valid_count < static_cast<std::int64_t>(map.valid.size() / 100)) {
    keepDayImage(day, map, o, "less than 1 % of the pixels show a surface", out);
    writeReport(Eigen::Vector3f(0.f, -1.f, 0.f), out);
    out.report.seconds = clock.seconds();
    return out;
  }
  out.report.add("camera_rays_seconds", clock.seconds(), "s");
  const Eigen::Vector3f up = upDirection(map);
  cv::Mat smooth;
  cv::blur(day, smooth, cv::Size(kSmoothingPx, kSmoothingPx));
  const SkyRadiance sky = skyRadiance(day, map, geometry.camera, up);
  if (!sky.measured) out.report.notes.push_back("no sky in view: the sky taken as grey at the surfaces' 95th percentile");
  const Eigen::Vector3f surface_median = surfacePercentile(day, map, 50);
  const AmbientSources sources{smooth, sky, geometry.camera, surface_median, surfacePercentile(day, map, 25), up};
  const std::vector<Eigen::Vector3f> ambient = ambientIrradiance(map, caster, sources, o.ambient_rays);
  out.report.add("ambient_seconds", clock.seconds(), "s");
  findSun(map, smooth, ambient, caster, HemisphereFrame(up), o, out);
  out.report.add("sun_search_seconds", clock.seconds(), "s");
  out.albedo = divideShading(day, map, ambient, kAmbientFloor * surface_median, caster, out.sun_direction,
                             out.method == DayLightMethod::SunAndSky, out.ambient_scale);
  out.white_balance = whiteBalance(out.albedo, map, o.median_reflectance, out.report);
  writeReport(up, out);
  out.report.seconds = clock.seconds();
  return out;
}

}  // namespace solo
