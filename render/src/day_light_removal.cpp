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
#include <unordered_map>

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

// The sun given in the options (DayLightRemovalOptions::sun_direction): no search; its shadows
// through the mesh and the ambient scales fitted to it as for a found sun. Fills out as
// findSun does; sun_gain is the share of the ambient-only cost the given sun removes.
void useGivenSun(const SurfaceMap& map, const cv::Mat& smooth, const std::vector<Eigen::Vector3f>& ambient,
                 const RayCaster& caster, const DayLightRemovalOptions& o, DayLightRemoval& out) {
  const PairSet pairs = samplePairs(map, smooth, ambient, o.refine_pairs, o.seed + 1);
  out.report.add("pairs", static_cast<std::int64_t>(pairs.pairs.size()));
  out.method = DayLightMethod::SunAndSky;
  out.sun_direction = o.sun_direction.normalized();
  const std::vector<float> direct = directShading(pairs, caster, out.sun_direction);
  out.ambient_scale = channelAmbientScales(pairs, direct);
  const std::vector<float> no_sun(pairs.points.size(), 0.f);
  const double ambient_only_cost = classCost(pairs, no_sun, 1.f, 3);
  const double sun_cost = classCost(pairs, direct, out.ambient_scale.mean(), 3);
  out.sun_gain = ambient_only_cost > 0 ? 1.0 - sun_cost / ambient_only_cost : 0.0;
  out.report.notes.push_back("sun direction given: its shadows traced through the mesh, no search");
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

// Sun and shadows read from the image: within a material region (one instance, one surface
// orientation) the sunlit and shadowed pixels form two modes of log(I / E); the gap between
// them gives the sun's shading of that orientation, the modes give the visibility.
constexpr float kMinShadowGapLog = 0.5f;    // least log gap between a region's lit and shadowed modes
constexpr double kMinModeShare = 0.08;      // each mode holds at least this share of its region
constexpr int kMinRegionPixels = 200;       // usable pixels a region needs to be split
constexpr double kMinModeSeparation = 0.6;  // Otsu's between-class share of the region's variance
constexpr int kHistogramBins = 64;
constexpr int kGuidedRadiusPx = 3;          // the visibility's edge-aware softening (penumbrae)
constexpr float kGuidedEps = 0.02f;
constexpr double kMinDarkPieceShare = 0.5;  // of the dark mode in its largest connected piece
constexpr float kMinSunCosine = 0.05f;      // a face with n.s at most this is in its own shadow
constexpr double kSunGridDeg = 2;           // the image sun search's grid step
constexpr int kMinStatsPixels = 50;         // usable pixels a region needs to count in the sun search
constexpr float kSunColourTolerance = 0.2f; // log deviation of a region's lit / shadowed colour from the sun's

// The region of every pixel (-1 without a surface): its instance and the signed axis of the
// up-aligned frame closest to its normal.
std::vector<int> materialRegions(const SurfaceMap& map, const HemisphereFrame& frame, int& region_count) {
  std::unordered_map<std::int64_t, int> ids;
  std::vector<int> region(map.valid.size(), -1);
  for (std::size_t i = 0; i < map.valid.size(); ++i) {
    if (!map.valid[i]) continue;
    const Eigen::Vector3f& n = map.normal[i];
    const std::array<float, 3> d = {n.dot(frame.up), n.dot(frame.east), n.dot(frame.north)};
    int axis = 0;
    for (int k = 1; k < 3; ++k)
      if (std::abs(d[static_cast<std::size_t>(k)]) > std::abs(d[static_cast<std::size_t>(axis)])) axis = k;
    const int bin = 2 * axis + (d[static_cast<std::size_t>(axis)] < 0.f ? 1 : 0);
    const std::int64_t key = static_cast<std::int64_t>(map.instance[i]) * 8 + bin;
    region[i] = ids.emplace(key, static_cast<int>(ids.size())).first->second;
  }
  region_count = static_cast<int>(ids.size());
  return region;
}

// log(luminance(I) / luminance(E)) of every usable pixel of the smoothed day image; NaN elsewhere.
std::vector<float> ambientLogRatio(const SurfaceMap& map, const cv::Mat& smooth, const std::vector<Eigen::Vector3f>& ambient,
                                   const Eigen::Vector3f& floor) {
  std::vector<float> ratio(map.valid.size(), std::numeric_limits<float>::quiet_NaN());
  for (std::size_t i = 0; i < map.valid.size(); ++i) {
    if (!usablePixel(map, smooth, i)) continue;
    const cv::Vec3f c = smooth.at<cv::Vec3f>(static_cast<int>(i / map.width), static_cast<int>(i % map.width));
    const Eigen::Vector3f e = ambient[i].cwiseMax(floor);
    ratio[i] = std::log(luminance(c)) - std::log(luminance(cv::Vec3f(e[0], e[1], e[2])));
  }
  return ratio;
}

// The median of a non-empty vector (reorders it).
float medianOf(std::vector<float>& values) {
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2), values.end());
  return values[values.size() / 2];
}

// Otsu's split of `values` on a histogram between their 1st and 99th percentiles.
struct ModeSplit {
  float threshold = 0, low_mean = 0, high_mean = 0;
  double low_share = 0, separation = 0;  // separation: between-class share of the variance
};

ModeSplit otsuSplit(std::vector<float> values) {
  ModeSplit out;
  std::sort(values.begin(), values.end());
  const float lo = values[values.size() / 100], hi = values[values.size() - 1 - values.size() / 100];
  if (!(hi > lo)) return out;
  std::array<double, kHistogramBins> count{}, sum{};
  double total_sum = 0, total_sq = 0;
  for (const float v : values) {
    const int b = std::clamp(static_cast<int>((v - lo) / (hi - lo) * kHistogramBins), 0, kHistogramBins - 1);
    count[static_cast<std::size_t>(b)] += 1;
    sum[static_cast<std::size_t>(b)] += v;
    total_sum += v;
    total_sq += double(v) * v;
  }
  const double n = static_cast<double>(values.size()), mean = total_sum / n;
  const double variance = std::max(total_sq / n - mean * mean, 1e-12);
  double n0 = 0, s0 = 0, best = -1;
  for (int b = 0; b + 1 < kHistogramBins; ++b) {
    n0 += count[static_cast<std::size_t>(b)];
    s0 += sum[static_cast<std::size_t>(b)];
    if (n0 <= 0 || n0 >= n) continue;
    const double m0 = s0 / n0, m1 = (total_sum - s0) / (n - n0);
    const double between = (n0 / n) * (1 - n0 / n) * (m1 - m0) * (m1 - m0);
    if (between <= best) continue;
    best = between;
    out = {lo + (hi - lo) * static_cast<float>(b + 1) / kHistogramBins, static_cast<float>(m0), static_cast<float>(m1),
           n0 / n, between / variance};
  }
  return out;
}

// A region split into a sunlit and a shadowed mode (`bimodal`): the split's threshold on
// log(I / E), the lit pixels' mean normal and the observation y_c = (exp(median log(I_c / E_c)
// of the lit pixels - that of the shadowed ones) - 1) x the lit pixels' median E_c, the sun's
// term that makes both modes one albedo (the model's n.w_c).
struct RegionModes {
  bool bimodal = false;
  float threshold = 0;
  Eigen::Vector3f normal = Eigen::Vector3f::Zero();
  Eigen::Vector3f observed = Eigen::Vector3f::Zero();
  double weight = 0;
};

// Whether the region's dark mode is mostly one connected piece, as a cast shadow is, and not
// many small ones, as the windows of a wall are.
bool darkModeConnected(const std::vector<std::size_t>& pixels, int width, const std::vector<float>& log_ratio,
                       float threshold) {
  int x0 = width, y0 = std::numeric_limits<int>::max(), x1 = -1, y1 = -1;
  for (const std::size_t i : pixels) {
    const int y = static_cast<int>(i / width), x = static_cast<int>(i % width);
    x0 = std::min(x0, x), x1 = std::max(x1, x), y0 = std::min(y0, y), y1 = std::max(y1, y);
  }
  cv::Mat dark(y1 - y0 + 1, x1 - x0 + 1, CV_8U, cv::Scalar(0));
  int dark_count = 0;
  for (const std::size_t i : pixels)
    if (log_ratio[i] <= threshold) {
      dark.at<std::uint8_t>(static_cast<int>(i / width) - y0, static_cast<int>(i % width) - x0) = 255;
      ++dark_count;
    }
  cv::morphologyEx(dark, dark, cv::MORPH_CLOSE, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(3, 3)));
  cv::Mat labels, stats, centroids;
  const int count = cv::connectedComponentsWithStats(dark, labels, stats, centroids, 8);
  int largest = 0;
  for (int k = 1; k < count; ++k) largest = std::max(largest, stats.at<int>(k, cv::CC_STAT_AREA));
  return largest >= kMinDarkPieceShare * dark_count;
}

// The region's modes when Otsu's split of its log(I / E) is a shadow split (gap, shares,
// separation, one dark piece); else not bimodal.
RegionModes regionModes(const std::vector<std::size_t>& pixels, const SurfaceMap& map, const cv::Mat& smooth,
                        const std::vector<Eigen::Vector3f>& ambient, const Eigen::Vector3f& floor,
                        const std::vector<float>& log_ratio) {
  RegionModes out;
  std::vector<float> values;
  for (const std::size_t i : pixels) values.push_back(log_ratio[i]);
  const ModeSplit split = otsuSplit(values);
  if (split.high_mean - split.low_mean < kMinShadowGapLog || split.separation < kMinModeSeparation ||
      std::min(split.low_share, 1 - split.low_share) < kMinModeShare)
    return out;
  if (!darkModeConnected(pixels, map.width, log_ratio, split.threshold)) return out;
  std::array<std::vector<float>, 3> log_lit, log_dark, e_lit;
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  for (const std::size_t i : pixels) {
    const cv::Vec3f c = smooth.at<cv::Vec3f>(static_cast<int>(i / map.width), static_cast<int>(i % map.width));
    const Eigen::Vector3f e = ambient[i].cwiseMax(floor);
    const bool lit = log_ratio[i] > split.threshold;
    if (lit) normal += map.normal[i].cast<double>();
    for (std::size_t k = 0; k < 3; ++k) {
      const float l = std::log(c[static_cast<int>(k)] / e[static_cast<int>(k)]);
      (lit ? log_lit : log_dark)[k].push_back(l);
      if (lit) e_lit[k].push_back(e[static_cast<int>(k)]);
    }
  }
  out.bimodal = normal.norm() > 0;
  out.threshold = split.threshold;
  out.normal = normal.normalized().cast<float>();
  for (std::size_t k = 0; k < 3; ++k)  // medians: the pixels the smoothing mixed across an edge do not count
    out.observed[static_cast<int>(k)] =
        std::expm1(medianOf(log_lit[k]) - medianOf(log_dark[k])) * medianOf(e_lit[k]);
  out.weight = std::sqrt(static_cast<double>(pixels.size()));
  return out;
}

// Drops the regions whose lit / shadowed colour ratio is not the sun's: the sun's colour is
// one for the whole image (the weighted median of the regions' observed_c / observed_g).
void keepSunColouredRegions(std::vector<RegionModes>& regions) {
  std::array<std::vector<std::pair<float, double>>, 2> chroma;
  for (const RegionModes& r : regions)
    if (r.bimodal && r.observed.minCoeff() > 0.f)
      for (int k = 0; k < 2; ++k) chroma[static_cast<std::size_t>(k)].emplace_back(std::log(r.observed[2 * k] / r.observed[1]), r.weight);
  std::array<float, 2> median{};
  for (int k = 0; k < 2; ++k) {
    auto& v = chroma[static_cast<std::size_t>(k)];
    if (v.empty()) return;
    std::sort(v.begin(), v.end());
    double total = 0, acc = 0;
    for (const auto& e : v) total += e.second;
    for (const auto& e : v)
      if ((acc += e.second) >= total / 2) {
        median[static_cast<std::size_t>(k)] = e.first;
        break;
      }
  }
  for (RegionModes& r : regions)
    if (r.bimodal && (r.observed.minCoeff() <= 0.f ||
                      std::abs(std::log(r.observed[0] / r.observed[1]) - median[0]) > kSunColourTolerance ||
                      std::abs(std::log(r.observed[2] / r.observed[1]) - median[1]) > kSunColourTolerance))
      r.bimodal = false;
}

// A region's luminance statistics for the sun search: the mean log luminance of I and the
// mean luminance of E over its lit mode (the whole region when it is not split) and its
// shadowed mode.
struct RegionStats {
  int instance = 0;
  bool split = false;
  Eigen::Vector3f normal = Eigen::Vector3f::Zero();
  double weight = 0;
  std::array<float, 2> log_i{}, e{};  // [0] lit mode or whole region, [1] shadowed mode
};

RegionStats regionStats(const std::vector<std::size_t>& pixels, const SurfaceMap& map, const cv::Mat& smooth,
                        const std::vector<Eigen::Vector3f>& ambient, const Eigen::Vector3f& floor,
                        const RegionModes& modes, const std::vector<float>& log_ratio) {
  RegionStats out;
  out.instance = map.instance[pixels.front()];
  out.split = modes.bimodal;
  std::array<double, 2> log_i{}, e{};
  std::array<int, 2> count{};
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  for (const std::size_t i : pixels) {
    const cv::Vec3f c = smooth.at<cv::Vec3f>(static_cast<int>(i / map.width), static_cast<int>(i % map.width));
    const Eigen::Vector3f a = ambient[i].cwiseMax(floor);
    const std::size_t m = modes.bimodal && log_ratio[i] <= modes.threshold ? 1 : 0;
    log_i[m] += std::log(luminance(c));
    e[m] += luminance(cv::Vec3f(a[0], a[1], a[2]));
    ++count[m];
    if (m == 0) normal += map.normal[i].cast<double>();
  }
  for (std::size_t m = 0; m < 2; ++m)
    if (count[m] > 0) out.log_i[m] = static_cast<float>(log_i[m] / count[m]), out.e[m] = static_cast<float>(e[m] / count[m]);
  out.normal = normal.norm() > 0 ? Eigen::Vector3f(normal.normalized().cast<float>()) : Eigen::Vector3f::Zero();
  out.weight = std::sqrt(static_cast<double>(pixels.size()));
  return out;
}

// The cost of sun direction s with strength k (in units of E): a split region's lit and
// shadowed modes must give one albedo, and the regions of one instance (one material) must
// agree with the weighted median of those whose visibility is known (split, or turned away
// from the sun); the others take whichever of lit and shadowed agrees better (written to
// `lit` when given: 1 lit, 0 shadowed, 2 undecided).
double sunCost(const std::vector<RegionStats>& stats, const std::vector<std::vector<int>>& instances,
               const Eigen::Vector3f& s, float k, std::vector<std::uint8_t>* lit) {
  const float clip = kClassCostClip * kClassCostClip;
  double cost = 0, counted = 0;
  std::vector<std::pair<float, double>> known;
  for (const std::vector<int>& members : instances) {
    known.clear();
    for (const int r : members) {
      const RegionStats& st = stats[static_cast<std::size_t>(r)];
      const float cosine = st.normal.dot(s);
      if (st.split) {
        const float h_lit = st.log_i[0] - std::log(std::max(0.f, k * cosine) + st.e[0]);
        const float d = h_lit - (st.log_i[1] - std::log(st.e[1]));
        cost += st.weight * std::min(d * d, clip);
        counted += st.weight;
        known.emplace_back(h_lit, st.weight);
      } else if (cosine <= kMinSunCosine) {
        known.emplace_back(st.log_i[0] - std::log(st.e[0]), st.weight);
      }
    }
    float centre = 0;
    if (!known.empty()) {
      std::sort(known.begin(), known.end());
      double total = 0, acc = 0;
      for (const auto& e : known) total += e.second;
      for (const auto& e : known)
        if ((acc += e.second) >= total / 2) {
          centre = e.first;
          break;
        }
    }
    for (const int r : members) {
      const RegionStats& st = stats[static_cast<std::size_t>(r)];
      const float cosine = st.normal.dot(s);
      const float h_shadow = st.log_i[0] - std::log(st.e[0]);
      const float h_lit = st.log_i[0] - std::log(std::max(0.f, k * cosine) + st.e[0]);
      bool choose_lit = st.split;
      if (!st.split && cosine > kMinSunCosine) choose_lit = std::abs(h_lit - centre) < std::abs(h_shadow - centre);
      if (lit) (*lit)[static_cast<std::size_t>(r)] = known.empty() && !st.split && cosine > kMinSunCosine ? 2 : choose_lit;
      if (known.empty()) continue;
      const float d = (choose_lit ? h_lit : h_shadow) - centre;
      cost += st.weight * std::min(d * d, clip);
      counted += st.weight;
    }
  }
  return counted > 0 ? cost / counted : std::numeric_limits<double>::infinity();
}

struct SunCandidate {
  Eigen::Vector3f direction = Eigen::Vector3f::Zero();
  float strength = 0;
  double cost = std::numeric_limits<double>::infinity();
};

// The best (s, k) on a grid: elevations and azimuths every kSunGridDeg, strengths log-spaced.
SunCandidate searchImageSun(const std::vector<RegionStats>& stats, const std::vector<std::vector<int>>& instances,
                            const HemisphereFrame& frame) {
  const std::vector<float> strengths = ambientScaleGrid(24);
  std::vector<Eigen::Vector3f> directions;
  const double step = kSunGridDeg * kPi / 180;
  for (double elevation = step; elevation < kPi / 2; elevation += step)
    for (double azimuth = 0; azimuth < 2 * kPi - 1e-9; azimuth += step / std::max(0.1, std::cos(elevation)))
      directions.push_back(frame.direction(elevation, azimuth));
  std::vector<SunCandidate> best(directions.size());
  tbb::parallel_for(std::size_t{0}, directions.size(), [&](std::size_t d) {
    for (const float k : strengths) {
      const double cost = sunCost(stats, instances, directions[d], k, nullptr);
      if (cost < best[d].cost) best[d] = {directions[d], k, cost};
    }
  });
  SunCandidate out;
  for (const SunCandidate& c : best)
    if (c.cost < out.cost) out = c;
  return out;
}

// w_c = k_c s: k_c the least squares fit of the split regions' observed_c to k_c n.s; without
// a split region every channel takes the search's strength.
std::array<Eigen::Vector3f, 3> channelSunVectors(const std::vector<RegionModes>& modes, const SunCandidate& sun) {
  std::array<Eigen::Vector3f, 3> w;
  for (int c = 0; c < 3; ++c) {
    double num = 0, den = 0;
    for (const RegionModes& m : modes) {
      if (!m.bimodal) continue;
      const double cosine = std::max(0.f, m.normal.dot(sun.direction));
      num += m.weight * cosine * m.observed[c];
      den += m.weight * cosine * cosine;
    }
    w[static_cast<std::size_t>(c)] = sun.direction * (den > 0 ? static_cast<float>(num / den) : sun.strength);
  }
  return w;
}

// He's guided filter of `p` by `guide` (both CV_32F) over a (2r + 1)^2 box.
cv::Mat guidedFilter(const cv::Mat& guide, const cv::Mat& p, int radius, float eps) {
  const cv::Size box(2 * radius + 1, 2 * radius + 1);
  cv::Mat mean_i, mean_p, corr_ip, corr_ii;
  cv::boxFilter(guide, mean_i, CV_32F, box);
  cv::boxFilter(p, mean_p, CV_32F, box);
  cv::boxFilter(guide.mul(p), corr_ip, CV_32F, box);
  cv::boxFilter(guide.mul(guide), corr_ii, CV_32F, box);
  const cv::Mat a = (corr_ip - mean_i.mul(mean_p)) / (corr_ii - mean_i.mul(mean_i) + eps);
  const cv::Mat b = mean_p - a.mul(mean_i);
  cv::Mat mean_a, mean_b;
  cv::boxFilter(a, mean_a, CV_32F, box);
  cv::boxFilter(b, mean_b, CV_32F, box);
  return mean_a.mul(guide) + mean_b;
}

// The sun's visibility where the image cannot split a region: 0 where the surface turns away
// from the sun, else a shadow ray through the mesh.
float rayVisibility(const SurfaceMap& map, std::size_t i, const RayCaster& caster, const Eigen::Vector3f& sun) {
  if (map.normal[i].dot(sun) <= 0.f) return 0.f;
  const RayStart start = rayStart(map.point[i], map.normal[i]);
  return caster.occluded(start.origin, sun, start.t_near, std::numeric_limits<float>::infinity()) ? 0.f : 1.f;
}

// What the image says of the sun: the material regions, their modes, the visibility chosen for
// the regions without a split, and w_c (zero without a sun).
struct ImageSun {
  std::vector<int> region;
  std::vector<RegionModes> modes;
  std::vector<std::uint8_t> lit;  // per region without a split: 1 lit, 0 shadowed, 2 undecided (a shadow ray)
  std::vector<float> log_ratio;
  std::vector<std::vector<std::size_t>> members;  // per region: its pixels with a finite log_ratio
  std::array<Eigen::Vector3f, 3> w{Eigen::Vector3f::Zero(), Eigen::Vector3f::Zero(), Eigen::Vector3f::Zero()};
  int split = 0;  // regions split into a lit and a shadowed mode
};

// The sun's visibility per pixel: in a bimodal region its lit mode (a clipped pixel counts as
// lit, a dark one as shadowed), softened by a guided filter on the image's log luminance so
// that penumbrae blend; in the other regions rayVisibility.
cv::Mat sunVisibility(const SurfaceMap& map, const cv::Mat& smooth, const ImageSun& sun_fit, const RayCaster& caster,
                      const Eigen::Vector3f& sun) {
  cv::Mat hard(map.height, map.width, CV_32F, cv::Scalar(0)), guide(map.height, map.width, CV_32F, cv::Scalar(0));
  std::vector<std::uint8_t> split(map.valid.size(), 0);
  tbb::parallel_for(0, map.height, [&](int y) {
    for (int x = 0; x < map.width; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * map.width + x;
      const cv::Vec3f c = smooth.at<cv::Vec3f>(y, x);
      guide.at<float>(y, x) = std::log(luminance(c) + 1e-3f);
      if (sun_fit.region[i] < 0) continue;
      const RegionModes& modes = sun_fit.modes[static_cast<std::size_t>(sun_fit.region[i])];
      if (!modes.bimodal) {
        const std::uint8_t lit = sun_fit.lit[static_cast<std::size_t>(sun_fit.region[i])];
        hard.at<float>(y, x) = lit == 2 ? rayVisibility(map, i, caster, sun) : static_cast<float>(lit);
        continue;
      }
      split[i] = 1;
      const float r = sun_fit.log_ratio[i];
      hard.at<float>(y, x) = std::isfinite(r) ? (r > modes.threshold ? 1.f : 0.f)
                                              : (std::max({c[0], c[1], c[2]}) >= kClippedValue ? 1.f : 0.f);
    }
  });
  const cv::Mat soft = guidedFilter(guide, hard, kGuidedRadiusPx, kGuidedEps);
  for (std::size_t i = 0; i < split.size(); ++i)
    if (split[i]) {
      const int y = static_cast<int>(i / map.width), x = static_cast<int>(i % map.width);
      hard.at<float>(y, x) = std::clamp(soft.at<float>(y, x), 0.f, 1.f);
    }
  return hard;
}

// The statistics of every region with kMinStatsPixels usable pixels (`stats`, by region) and
// the regions grouped by instance, in a fixed order.
std::vector<std::vector<int>> instanceGroups(const std::vector<std::vector<std::size_t>>& members, const SurfaceMap& map,
                                             const cv::Mat& smooth, const std::vector<Eigen::Vector3f>& ambient,
                                             const Eigen::Vector3f& floor, const ImageSun& sun_fit,
                                             std::vector<RegionStats>& stats) {
  stats.assign(members.size(), RegionStats{});
  std::unordered_map<int, std::vector<int>> by_instance;
  for (std::size_t r = 0; r < members.size(); ++r)
    if (members[r].size() >= static_cast<std::size_t>(kMinStatsPixels)) {
      stats[r] = regionStats(members[r], map, smooth, ambient, floor, sun_fit.modes[r], sun_fit.log_ratio);
      by_instance[stats[r].instance].push_back(static_cast<int>(r));
    }
  std::vector<std::vector<int>> instances;
  for (auto& entry : by_instance) instances.push_back(std::move(entry.second));
  std::sort(instances.begin(), instances.end());
  return instances;
}

// Splits every region with enough usable pixels into its modes; when some region keeps a
// split of the sun's colour, searches the sun and decides the other regions' visibility.
ImageSun fitImageSun(const SurfaceMap& map, const cv::Mat& smooth, const std::vector<Eigen::Vector3f>& ambient,
                     const Eigen::Vector3f& floor, const HemisphereFrame& frame) {
  ImageSun out;
  int region_count = 0;
  out.region = materialRegions(map, frame, region_count);
  out.log_ratio = ambientLogRatio(map, smooth, ambient, floor);
  out.members.resize(static_cast<std::size_t>(region_count));
  std::vector<std::vector<std::size_t>>& members = out.members;
  for (std::size_t i = 0; i < map.valid.size(); ++i)
    if (out.region[i] >= 0 && std::isfinite(out.log_ratio[i])) members[static_cast<std::size_t>(out.region[i])].push_back(i);
  out.modes.resize(members.size());
  tbb::parallel_for(std::size_t{0}, members.size(), [&](std::size_t r) {
    if (members[r].size() >= static_cast<std::size_t>(kMinRegionPixels))
      out.modes[r] = regionModes(members[r], map, smooth, ambient, floor, out.log_ratio);
  });
  keepSunColouredRegions(out.modes);
  for (const RegionModes& m : out.modes) out.split += m.bimodal ? 1 : 0;
  out.lit.assign(members.size(), 2);
  if (out.split == 0) return out;
  std::vector<RegionStats> stats;
  const std::vector<std::vector<int>> instances = instanceGroups(members, map, smooth, ambient, floor, out, stats);
  const SunCandidate sun = searchImageSun(stats, instances, frame);
  if (!std::isfinite(sun.cost)) return out;
  sunCost(stats, instances, sun.direction, sun.strength, &out.lit);
  for (std::size_t r = 0; r < members.size(); ++r)
    if (members[r].size() < static_cast<std::size_t>(kMinStatsPixels)) out.lit[r] = 2;
  out.w = channelSunVectors(out.modes, sun);
  return out;
}

constexpr float kMinShadowAmbient = 0.2f, kMaxShadowAmbient = 1.5f;  // bounds of g_c (below)
// Pixels this close to the other mode take a visibility of their own: the sun (0.53 degrees)
// draws a penumbra 0.9 % of the caster's distance wide, tens of pixels on a near road.
constexpr int kPenumbraBandPx = 20;

struct ShadowAmbient {
  std::vector<Eigen::Vector3f> scale, lit_albedo;  // per region; ones / zeros where not split
};

// What a split region's cast shadow receives of its traced ambient light, per channel: the
// traced E counts the sky that the caster hides (a caster outside the mesh, or its far side
// read as the surfaces' 25th percentile), so the shadowed mode de-lit by E comes out darker than
// the lit mode de-lit by n.w_c + E. g_c = exp(median log(I_c / E_c) over the shadowed mode -
// median log(I_c / (n.w_c + E_c)) over the lit mode) makes the two one albedo; a_c is the lit
// mode's albedo exp(median log(I_c / (n.w_c + E_c))).
ShadowAmbient shadowAmbientScales(const SurfaceMap& map, const cv::Mat& smooth, const std::vector<Eigen::Vector3f>& ambient,
                                  const Eigen::Vector3f& floor, const ImageSun& sun_fit,
                                  const std::array<Eigen::Vector3f, 3>& w) {
  const std::size_t regions = sun_fit.modes.size();
  ShadowAmbient out{std::vector<Eigen::Vector3f>(regions, Eigen::Vector3f::Ones()),
                    std::vector<Eigen::Vector3f>(regions, Eigen::Vector3f::Zero())};
  tbb::parallel_for(std::size_t{0}, regions, [&](std::size_t r) {
    const RegionModes& modes = sun_fit.modes[r];
    if (!modes.bimodal) return;
    std::array<std::vector<float>, 3> lit, dark;
    for (const std::size_t i : sun_fit.members[r]) {
      const cv::Vec3f& c = smooth.at<cv::Vec3f>(static_cast<int>(i / map.width), static_cast<int>(i % map.width));
      const Eigen::Vector3f e = ambient[i].cwiseMax(floor);
      const bool is_lit = sun_fit.log_ratio[i] > modes.threshold;
      for (std::size_t k = 0; k < 3; ++k) {
        const int ch = static_cast<int>(k);
        const float direct = is_lit ? std::max(0.f, map.normal[i].dot(w[k])) : 0.f;
        (is_lit ? lit : dark)[k].push_back(std::log(std::max(c[ch], 1e-6f) / (direct + e[ch])));
      }
    }
    if (lit[0].empty() || dark[0].empty()) return;
    for (std::size_t k = 0; k < 3; ++k) {
      const float lit_log = medianOf(lit[k]);
      out.lit_albedo[r][static_cast<int>(k)] = std::exp(lit_log);
      out.scale[r][static_cast<int>(k)] =
          std::clamp(std::exp(medianOf(dark[k]) - lit_log), kMinShadowAmbient, kMaxShadowAmbient);
    }
  });
  return out;
}

// Pixels of split regions within kPenumbraBandPx of a pixel of the other mode (CV_8U, 255).
cv::Mat penumbraBand(const SurfaceMap& map, const ImageSun& sun_fit) {
  cv::Mat lit(map.height, map.width, CV_8U, cv::Scalar(0)), dark(map.height, map.width, CV_8U, cv::Scalar(0));
  for (std::size_t r = 0; r < sun_fit.modes.size(); ++r) {
    if (!sun_fit.modes[r].bimodal) continue;
    for (const std::size_t i : sun_fit.members[r]) {
      const bool is_lit = sun_fit.log_ratio[i] > sun_fit.modes[r].threshold;
      (is_lit ? lit : dark).at<std::uint8_t>(static_cast<int>(i / map.width), static_cast<int>(i % map.width)) = 255;
    }
  }
  const cv::Mat disc =
      cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * kPenumbraBandPx + 1, 2 * kPenumbraBandPx + 1));
  cv::Mat near_lit, near_dark;
  cv::dilate(lit, near_lit, disc);
  cv::dilate(dark, near_dark, disc);
  return (lit & near_dark) | (dark & near_lit);
}

// The albedo I / (V max(0, n.w_c) + g_c E_c) at every pixel, E floored; sky pixels keep the day
// image. In a split region g_c is its shadow's ambient scale, taken in proportion to the shadow:
// I / (V n.w_c + (g_c + V (1 - g_c)) E_c); elsewhere g_c = 1. In the penumbra band V is the
// pixel's own, the visibility that gives it the lit mode's albedo in green (clamped to [0, 1]),
// since a penumbra wider than the guided filter leaves partly shaded pixels counted as lit or
// shadowed. Reports the band's pixels and the split regions' median g (green).
cv::Mat divideImageShading(const cv::Mat& day, const SurfaceMap& map, const cv::Mat& smooth,
                           const std::vector<Eigen::Vector3f>& ambient, const Eigen::Vector3f& floor,
                           const ImageSun& sun_fit, const std::array<Eigen::Vector3f, 3>& w, const cv::Mat& visibility,
                           StageReport& report) {
  const ShadowAmbient shadow = shadowAmbientScales(map, smooth, ambient, floor, sun_fit, w);
  const cv::Mat band = penumbraBand(map, sun_fit);
  std::vector<float> scales;
  for (std::size_t r = 0; r < sun_fit.modes.size(); ++r)
    if (sun_fit.modes[r].bimodal) scales.push_back(shadow.scale[r][1]);
  if (!scales.empty()) report.add("shadow_ambient_scale_median", static_cast<double>(medianOf(scales)));
  report.add("penumbra_band_pixels", static_cast<std::int64_t>(cv::countNonZero(band)));
  cv::Mat albedo = day.clone();
  tbb::parallel_for(0, map.height, [&](int y) {
    for (int x = 0; x < map.width; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * map.width + x;
      if (!map.valid[i]) continue;
      const int r = sun_fit.region[i];
      const bool split = r >= 0 && sun_fit.modes[static_cast<std::size_t>(r)].bimodal;
      const Eigen::Vector3f g = split ? shadow.scale[static_cast<std::size_t>(r)] : Eigen::Vector3f::Ones();
      const Eigen::Vector3f e = ambient[i].cwiseMax(floor);
      std::array<float, 3> direct{};
      for (std::size_t k = 0; k < 3; ++k) direct[k] = std::max(0.f, map.normal[i].dot(w[k]));
      float v = visibility.at<float>(y, x);
      const float lit_albedo = split ? shadow.lit_albedo[static_cast<std::size_t>(r)][1] : 0.f;
      if (band.at<std::uint8_t>(y, x) && lit_albedo > 0.f) {
        const float denominator = direct[1] + (1.f - g[1]) * e[1];
        if (denominator > 0.f)
          v = std::clamp((std::max(smooth.at<cv::Vec3f>(y, x)[1], 0.f) / lit_albedo - g[1] * e[1]) / denominator, 0.f,
                         1.f);
      }
      cv::Vec3f& a = albedo.at<cv::Vec3f>(y, x);
      for (int k = 0; k < 3; ++k) {
        const float shading = v * direct[static_cast<std::size_t>(k)] + (g[k] + v * (1.f - g[k])) * e[k];
        if (shading > 0.f) a[k] = std::max(a[k], 0.f) / shading;
      }
    }
  });
  return albedo;
}

// The image's sun and shadows divided out (fills out.albedo before the white balance, and the
// method, sun and scales); without a split region only the ambient light is divided out.
void removeImageShadows(const cv::Mat& day, const SurfaceMap& map, const cv::Mat& smooth,
                        const std::vector<Eigen::Vector3f>& ambient, const Eigen::Vector3f& floor,
                        const HemisphereFrame& frame, const RayCaster& caster, DayLightRemoval& out) {
  const ImageSun sun_fit = fitImageSun(map, smooth, ambient, floor, frame);
  out.report.add("shadow_regions", static_cast<std::int64_t>(sun_fit.split));
  const std::array<Eigen::Vector3f, 3>& w = sun_fit.w;
  if (!(w[1].norm() > 0.f)) {
    out.method = DayLightMethod::SkyOnly;
    out.ambient_scale = Eigen::Vector3f::Ones();
    out.report.notes.push_back("no clear sun: no region shows a lit and a shadowed mode of the sun's colour; the "
                               "ambient light alone is divided out");
    out.albedo = divideShading(day, map, ambient, floor, caster, Eigen::Vector3f::Zero(), false, out.ambient_scale);
    return;
  }
  out.method = DayLightMethod::SunAndSky;
  out.sun_direction = w[1].normalized();
  for (int c = 0; c < 3; ++c) out.ambient_scale[c] = 1.f / std::max(w[static_cast<std::size_t>(c)].norm(), 1e-6f);
  const cv::Mat visibility = sunVisibility(map, smooth, sun_fit, caster, out.sun_direction);
  out.albedo = divideImageShading(day, map, smooth, ambient, floor, sun_fit, w, visibility, out.report);
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
  const bool given_sun = o.sun_direction.allFinite() && o.sun_direction.norm() > 0.f;
  if (o.shadows_from_image && !given_sun) {
    removeImageShadows(day, map, smooth, ambient, kAmbientFloor * surface_median, HemisphereFrame(up), caster, out);
    out.report.add("sun_search_seconds", clock.seconds(), "s");
  } else {
    if (given_sun)
      useGivenSun(map, smooth, ambient, caster, o, out);
    else
      findSun(map, smooth, ambient, caster, HemisphereFrame(up), o, out);
    out.report.add("sun_search_seconds", clock.seconds(), "s");
    out.albedo = divideShading(day, map, ambient, kAmbientFloor * surface_median, caster, out.sun_direction,
                               out.method == DayLightMethod::SunAndSky, out.ambient_scale);
  }
  out.white_balance = whiteBalance(out.albedo, map, o.median_reflectance, out.report);
  writeReport(up, out);
  out.report.seconds = clock.seconds();
  return out;
}

}  // namespace solo
