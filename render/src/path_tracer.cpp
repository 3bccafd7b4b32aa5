#include "solo/render/path_tracer.h"

#include "solo/render/ggx.h"
#include "solo/render/ray_caster.h"
#include "solo/render/sampler.h"
#include "solo/render/spherical_triangle.h"
#include "slot_shading.h"

#include <Eigen/Geometry>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <limits>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <unistd.h>
#include <utility>
#include <vector>

namespace solo {
namespace {

constexpr float kPi = 3.14159265358979f;

// The emitter's angular factor for light leaving `light_point` (camera frame) along the unit
// direction `out`, at |cosine| `abs_cosine` to the face's normal.
float profile(const Emitter& e, float abs_cosine, const Eigen::Vector3f& light_point, const Eigen::Vector3f& out) {
  switch (e.profile) {
    case EmitterProfile::CosineLobe: return std::cos(kPi * (abs_cosine - 1.f) * 0.5f);
    case EmitterProfile::TowardCamera: {
      const float distance = light_point.norm();
      if (!(distance > 0.f)) return 1.f;
      const float toward_camera = -out.dot(light_point) / distance;
      return toward_camera > 0.f ? std::pow(std::min(toward_camera, 1.f), e.beam_exponent) : 0.f;
    }
    case EmitterProfile::Uniform: break;
  }
  return 1.f;
}

Eigen::Vector3f cosineSample(const Eigen::Vector3f& n, float u1, float u2) {
  const float r = std::sqrt(u1), phi = 2.f * kPi * u2;
  Eigen::Vector3f t, b;
  orthonormalBasis(n, t, b);
  const float z = std::sqrt(std::max(0.f, 1.f - u1));
  return (t * (r * std::cos(phi)) + b * (r * std::sin(phi)) + n * z).normalized();
}

Eigen::Vector3f skyRadiance(const RenderScene& scene, const Eigen::Vector3f& w) {
  if (!scene.sky_zenith_radiance) return scene.sky_radiance;
  const float elevation = std::max(0.f, w.dot(scene.sky_up));
  return scene.sky_radiance + (*scene.sky_zenith_radiance - scene.sky_radiance) * std::sqrt(elevation);
}

// The sun's disc: uniform directions in a cone. 1 - cos(radius) is kept apart from cos
// because at the sun's 4.65 mrad it is 1.1e-5, below what 1 - cos resolves in float.
struct SunDisc {
  bool on = false;
  Eigen::Vector3f direction, t, b;
  Eigen::Vector3f radiance;  // illuminance / (pi sin^2 r)
  float one_minus_cos = 0;
  float pdf = 0;  // 1 / (2 pi (1 - cos r)), per sr

  explicit SunDisc(const SunLight& sun) {
    const float r = std::clamp(sun.angular_radius_rad, 1e-5f, 0.5f);
    on = sun.illuminance.maxCoeff() > 0.f && sun.direction.norm() > 0.f;
    direction = sun.direction.normalized();
    orthonormalBasis(direction, t, b);
    const float half = std::sin(0.5f * r);
    one_minus_cos = 2.f * half * half;
    const float sin_r = std::sin(r);
    radiance = sun.illuminance / (kPi * sin_r * sin_r);
    pdf = 1.f / (2.f * kPi * one_minus_cos);
  }
  bool contains(const Eigen::Vector3f& w) const { return 1.f - w.dot(direction) <= one_minus_cos; }
  Eigen::Vector3f sample(float u1, float u2) const {
    const float m = u1 * one_minus_cos;  // 1 - cos(theta)
    const float sin_theta = std::sqrt(std::max(0.f, m * (2.f - m))), phi = 2.f * kPi * u2;
    return (t * (sin_theta * std::cos(phi)) + b * (sin_theta * std::sin(phi)) + direction * (1.f - m)).normalized();
  }
};

float powerHeuristic(float a, float b) { return a * a / (a * a + b * b); }

float luminance(const Eigen::Vector3f& xyz) { return xyz.y(); }

// A point on an emitting triangle for next-event estimation from `origin`: by solid angle,
// warped toward the receiver's cosine (spherical_triangle.h), when the triangle looks large;
// else by area. `pdf` is per steradian either way; emitterPdf() applies the same rule to a
// direction that BSDF sampling found, so the MIS weights of both strategies agree.
struct EmitterSample {
  bool ok = false;
  Eigen::Vector3f wi;  // unit, from origin
  float distance = 0;  // metres, origin to the triangle along wi
  float cos_light = 0; // |cosine| at the emitter
  float pdf = 0;       // per steradian, given the triangle
};

// The rule both sampleEmitter() and emitterPdf() follow: by solid angle when the triangle
// subtends at least kMinSphericalSolidAngle from `origin`. A cheap test comes first: a triangle
// within a sphere of radius r seen from more than 20 r subtends at most
// 2 pi (1 - cos(asin(1 / 20))) = 0.0079 sr, below the threshold, so most triangles need no
// solid angle at all.
static_assert(kMinSphericalSolidAngle >= 0.0079, "the bounding-sphere test assumes a threshold of at least 0.0079 sr");
bool sampledBySolidAngle(const EmissiveTriangle& t, const Eigen::Vector3f& origin, bool by_solid_angle) {
  if (!by_solid_angle) return false;
  const Eigen::Vector3f centre = (t.p0 + t.p1 + t.p2) / 3.f;
  const float radius2 =
      std::max({(t.p0 - centre).squaredNorm(), (t.p1 - centre).squaredNorm(), (t.p2 - centre).squaredNorm()});
  if (!((origin - centre).squaredNorm() < 400.f * radius2)) return false;
  return triangleSolidAngle(origin.cast<double>(), t.p0.cast<double>(), t.p1.cast<double>(), t.p2.cast<double>()) >=
         kMinSphericalSolidAngle;
}

EmitterSample sampleEmitter(const EmissiveTriangle& t, const Eigen::Vector3f& origin, const Eigen::Vector3f& normal,
                            float u1, float u2, bool by_solid_angle) {
  EmitterSample s;
  if (sampledBySolidAngle(t, origin, by_solid_angle)) {
    const Eigen::Vector3d o = origin.cast<double>(), a = t.p0.cast<double>();
    Eigen::Vector3d w;
    double pdf = 0;
    if (!sampleSphericalTriangleCosine(o, normal.cast<double>(), a, t.p1.cast<double>(), t.p2.cast<double>(), u1, u2, &w,
                                       &pdf))
      return s;
    const Eigen::Vector3d triangle_normal = t.normal.cast<double>();
    const double cos_w = w.dot(triangle_normal);
    const double distance = (a - o).dot(triangle_normal) / cos_w;
    if (!(distance > 0) || !std::isfinite(distance)) return s;
    s.wi = w.cast<float>();
    s.distance = static_cast<float>(distance);
    s.cos_light = static_cast<float>(std::abs(cos_w));
    s.pdf = static_cast<float>(pdf);
  } else {
    const float root = std::sqrt(u1);
    const Eigen::Vector3f q = t.p0 * (1.f - root) + t.p1 * (root * (1.f - u2)) + t.p2 * (root * u2);
    Eigen::Vector3f wi = q - origin;
    const float distance2 = wi.squaredNorm();
    s.distance = std::sqrt(distance2);
    if (!(s.distance > 0.f)) return s;
    s.wi = wi / s.distance;
    s.cos_light = std::abs(t.normal.dot(s.wi));
    if (!(s.cos_light > 1e-6f)) return s;
    s.pdf = distance2 / (s.cos_light * t.area);
  }
  s.ok = s.pdf > 0.f && std::isfinite(s.pdf) && s.cos_light > 0.f;
  return s;
}

// The per-steradian pdf with which sampleEmitter() from `origin` with receiver normal `normal`
// would have found direction `wi`, which meets the triangle `distance` away at |cosine|
// `cos_light`.
float emitterPdf(const EmissiveTriangle& t, const Eigen::Vector3f& origin, const Eigen::Vector3f& normal,
                 const Eigen::Vector3f& wi, float distance, float cos_light, bool by_solid_angle) {
  if (sampledBySolidAngle(t, origin, by_solid_angle))
    return static_cast<float>(sphericalTriangleCosinePdf(origin.cast<double>(), normal.cast<double>(), t.p0.cast<double>(),
                                                         t.p1.cast<double>(), t.p2.cast<double>(), wi.cast<double>()));
  return distance * distance / (cos_light * t.area);
}

// One shadow ray per path vertex instead of one per light: the lights' unoccluded contributions
// stream in, one is kept with probability proportional to its contribution (X + Y + Z), by one
// uniform number consumed as they come (weighted reservoir sampling), and its contribution is
// divided by that probability. Unbiased; the only variance it adds is the visibility's (none
// when one light dominates or none is occluded).
class OneLightChoice {
 public:
  explicit OneLightChoice(float u) : u_(u) {}
  void offer(const Eigen::Vector3f& contribution, const Eigen::Vector3f& wi, float distance) {
    const float weight = contribution.sum();
    if (!(weight > 0.f)) return;
    total_ += weight;
    const float p = weight / total_;
    if (u_ < p) {
      contribution_ = contribution;
      wi_ = wi;
      distance_ = distance;
      weight_ = weight;
      u_ = std::min(u_ / p, kOneMinusEpsilon);
    } else {
      u_ = std::min((u_ - p) / (1.f - p), kOneMinusEpsilon);
    }
  }
  bool empty() const { return !(weight_ > 0.f); }
  Eigen::Vector3f contribution() const { return contribution_ * (total_ / weight_); }
  /// The uniform number left after the choice: uniform again, and independent of which light
  /// was kept (each offer rescales it into the part of [0, 1) its outcome took).
  float leftover() const { return u_; }
  const Eigen::Vector3f& wi() const { return wi_; }
  float distance() const { return distance_; }

 private:
  static constexpr float kOneMinusEpsilon = 0x1.fffffep-1f;
  float u_;
  float total_ = 0.f, weight_ = 0.f, distance_ = 0.f;
  Eigen::Vector3f contribution_, wi_;
};

struct Context {
  const RenderScene& scene;
  const PinholeCamera& camera;
  const PathTracerOptions& options;
  const RayCaster& caster;
  const std::vector<EmissiveTriangle>& emissive;
  const LightSampler& sampler;
  const std::vector<QuadShading>& shading;  // by the caster's slot
  SunDisc sun;
  bool sky_on;  // a non-black sky: next-event estimation toward it
  bool has_roughness;  // a roughness map: the specular lobe
  std::vector<float> rectangle_area, rectangle_cos_half_spread;  // per rectangle light, computed once
  float shadow_roulette_y = 0.f;  // render units; 0 = off (PathTracerOptions::shadow_roulette)
  // RenderScene::surface_pixels when cracks are covered and the camera is the scene's size; else null.
  const std::uint8_t* surface_pixels = nullptr;
  // The caster's triangle per slot when the render uses RenderScene's pixel texture (the camera
  // is the texture's size); else null.
  const std::vector<std::uint32_t>* slot_triangles = nullptr;
};

// The MIS weight of emission that a bounce from `from_point` (receiver normal `from_normal`,
// ray origin `from_origin`) found along unit `direction`, `distance` away, on emissive triangle
// `triangle` (-1: a face the light sampler does not hold) at |cosine| `abs_cos`, the bounce's
// density being `bounce_pdf`: against the light sampler's density for that direction. 1 for
// emitting faces the light sampler never picks.
float bounceEmissionWeight(const Context& c, int triangle, const Eigen::Vector3f& from_point,
                           const Eigen::Vector3f& from_normal, const Eigen::Vector3f& from_origin,
                           const Eigen::Vector3f& direction, float distance, float abs_cos, float bounce_pdf) {
  if (triangle < 0 || !(abs_cos > 0.f)) return 1.f;
  const float light_pdf = c.sampler.pmf(from_point, from_normal, triangle) *
                          emitterPdf(c.emissive[static_cast<std::size_t>(triangle)], from_origin, from_normal, direction,
                                     distance, abs_cos, c.options.solid_angle_emitter_sampling);
  return powerHeuristic(bounce_pdf, light_pdf);
}

struct FirstHit {
  Eigen::Vector3f albedo{0, 0, 0}, normal{0, 0, 0};
  float depth = 0;
  int light_id = 0;
};

float offsetFor(float distance) { return 1e-4f * std::max(1.f, distance); }

// One camera path in flight: its state between two rays.
struct Path {
  Sampler* rng = nullptr;     // its pixel's, positioned at the path's sample
  FirstHit* first = nullptr;  // the AOVs to fill at the camera ray's hit, or null
  Eigen::Vector3f origin = Eigen::Vector3f::Zero(), direction = Eigen::Vector3f::UnitZ();
  Eigen::Vector3f radiance = Eigen::Vector3f::Zero(), throughput = Eigen::Vector3f::Ones();
  Eigen::Vector3f previous_point = Eigen::Vector3f::Zero(), previous_normal = Eigen::Vector3f::UnitZ();
  // Radiance after at most one scattering; NaN until the second vertex is reached.
  Eigen::Vector3f direct = Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN());
  float previous_bsdf_pdf = 0.f;
  float emission_scale = 1.f;  // 1 / the previous vertex's emission splits
  float z_per_distance = 1.f;  // the camera ray's depth per unit distance
  float u_choice = 0.f, u_pick = 0.f;  // the vertex's light choice and light pick
  // Set by locate() at the ray's hit: the point, the normal on the ray's side, the picked
  // emissive triangle (-1: none) and its probability.
  Eigen::Vector3f point = Eigen::Vector3f::Zero(), normal = Eigen::Vector3f::UnitZ();
  int picked = -1;
  float pick_pmf = 0.f;
  int bounce = 0;
  bool alive = true;
  bool sees_emitter = false;  // the camera ray hit an emitting face
  Eigen::Vector3f camera_albedo = Eigen::Vector3f::Zero();  // reflectance at the camera ray's hit
  bool camera_missed = false;  // the camera ray hit nothing
  std::int32_t texel = -1;  // the camera sample's pixel in RenderScene's pixel texture, -1 = unused
  SlotHit hit;
};

// A shadow ray and what it adds to its path's radiance when nothing blocks it.
struct ShadowRay {
  Eigen::Vector3f origin, direction, contribution;
  float t_far;
  std::uint32_t path;
};

// Traces camera paths as a wave: every live path's next ray, then every hit's shading (which
// queues the vertex's shadow rays and draws the next direction), then every shadow ray, until
// no path is left. Embree's traversal runs back to back for a whole wave, and a wave's face
// records are prefetched together before any is shaded, so their cache misses overlap instead
// of stalling one path at a time. Each path draws its numbers in the order a path traced alone
// would, and adds to its radiance in the same order, so the result is the same.
class WaveTracer {
 public:
  WaveTracer(const Context& c, std::vector<RecordedRay>* log) : c_(c), log_(log) {}

  // A path from the camera through (px, py), sample `rng` already started. With
  // film_within_pixel_centres the position is kept kFrameInset_px inside the outermost pixel
  // centres (off the depth mesh's boundary edge, where a hit is a matter of rounding).
  static Path cameraPath(const Context& c, float px, float py, Sampler& rng, FirstHit* first) {
    constexpr float kFrameInset_px = 1.f / 64.f;
    Path p;
    p.rng = &rng;
    p.first = first;
    const PinholeCamera& cam = c.camera;
    if (c.options.film_within_pixel_centres) {
      px = std::clamp(px, kFrameInset_px, std::max(kFrameInset_px, static_cast<float>(cam.width - 1) - kFrameInset_px));
      py = std::clamp(py, kFrameInset_px, std::max(kFrameInset_px, static_cast<float>(cam.height - 1) - kFrameInset_px));
    }
    if (c.slot_triangles) {
      const int x = std::clamp(static_cast<int>(std::lround(px)), 0, cam.width - 1);
      const int y = std::clamp(static_cast<int>(std::lround(py)), 0, cam.height - 1);
      p.texel = y * cam.width + x;
    }
    p.direction = {static_cast<float>((px - cam.cx) / cam.fx), static_cast<float>((py - cam.cy) / cam.fy), 1.f};
    p.z_per_distance = 1.f / p.direction.norm();
    p.direction.normalize();
    return p;
  }

  // Traces `paths` to their ends; then each path's radiance is its XYZ sample value.
  void trace(std::vector<Path>& paths) {
    for (std::size_t first = 0; first < paths.size(); first += kWaveSize) {
      active_.clear();
      for (std::size_t i = first; i < std::min(paths.size(), first + kWaveSize); ++i)
        active_.push_back(static_cast<std::uint32_t>(i));
      traceWave(paths);
    }
    for (Path& p : paths) p.radiance = pathValue(p);
  }

  std::int64_t rays = 0, clamped = 0, split_vertices = 0, shadow_rays_skipped = 0;

 private:
  static constexpr std::size_t kWaveSize = 16;

  // Traces the paths listed in active_ to their ends.
  void traceWave(std::vector<Path>& paths) {
    while (!active_.empty()) {
      // A vertex's first two numbers (its light choice and its light pick) are drawn before
      // its ray, so that the light sampler can prefetch while Embree traverses. A path that
      // ends here draws two numbers it does not use; that moves only later independent numbers.
      for (std::uint32_t i : active_) {
        Path& p = paths[i];
        p.u_choice = p.rng->get1D();
        p.u_pick = p.rng->get1D();
        c_.sampler.prefetch(p.u_pick);
      }
      for (std::uint32_t i : active_) paths[i].hit = closestHit(paths[i].origin, paths[i].direction);
      for (std::uint32_t i : active_)
        if (paths[i].hit.hit) __builtin_prefetch(&slotShading(c_.shading, paths[i].hit.slot));
      // The light picks for the whole wave before any shading, so that each picked triangle
      // loads while the wave's other vertices are located and shaded.
      for (std::uint32_t i : active_)
        if (paths[i].hit.hit) locate(paths[i]);
      shadow_rays_.clear();
      for (std::uint32_t i : active_) shade(paths[i], i);
      for (const ShadowRay& s : shadow_rays_)
        if (!occluded(s.origin, s.direction, s.t_far)) paths[s.path].radiance += s.contribution;
      active_.erase(std::remove_if(active_.begin(), active_.end(), [&](std::uint32_t i) { return !paths[i].alive; }),
                    active_.end());
    }
  }

  // Every ray goes through these two: counted, and recorded when a log is kept.
  SlotHit closestHit(const Eigen::Vector3f& o, const Eigen::Vector3f& d) {
    ++rays;
    if (log_) log_->push_back({o, d, std::numeric_limits<float>::infinity(), false});
    return c_.caster.intersectSlot(o, d);
  }
  bool occluded(const Eigen::Vector3f& o, const Eigen::Vector3f& d, float t_far) {
    ++rays;
    if (log_) log_->push_back({o, d, t_far, true});
    return c_.caster.occluded(o, d, 0.f, t_far);
  }

  // The hit point of the path's ray, the face's normal turned toward the ray's origin, and the
  // light pick there (next-event estimation's triangle, prefetched).
  void locate(Path& path) {
    const SlotShading& face = slotShading(c_.shading, path.hit.slot);
    path.point = path.origin + path.direction * path.hit.distance;
    path.normal = decodeOctahedral(face.normal);
    if (path.normal.dot(-path.direction) < 0.f) path.normal = -path.normal;
    path.pick_pmf = 0.f;
    path.picked = path.bounce < c_.options.max_bounces
                      ? c_.sampler.pick(path.point, path.normal, path.u_pick, &path.pick_pmf)
                      : -1;
    if (path.picked >= 0) __builtin_prefetch(&c_.emissive[static_cast<std::size_t>(path.picked)]);
  }

  // The path's vertex at its ray's end (or the sky past it): emission found there, the
  // vertex's shadow rays queued, its next direction drawn; `alive` false when the path ends.
  void shade(Path& path, std::uint32_t index) {
    const Context& c = c_;
    Sampler& rng = *path.rng;
    const SlotHit& hit = path.hit;
    path.alive = false;  // until a next direction is drawn
    if (!hit.hit) {
      path.camera_missed = path.bounce == 0;
      addSkyAndSunFound(path);
      return;
    }
    SlotShading texel_shading;
    const SlotShading& face =
        texelShading(path, texel_shading) ? texel_shading : slotShading(c.shading, hit.slot);
    const Eigen::Vector3f& n = path.normal;
    const float abs_cos_hit = std::abs(n.dot(path.direction));
    addEmissionFound(path, face.emitter, face.emissive, abs_cos_hit);
    if (path.bounce == 1) path.direct = path.radiance;  // light scattered at most once; the rest is indirect
    const Eigen::Vector3f wo = -path.direction;
    // An emitting face has no specular lobe, as in the Cycles export (its diffuse lobe reflects
    // its reflectance, which the night scene sets to 0): a lit window's glossy glass mirrored
    // other lamps in a few of its pixels' samples, fireflies the denoiser keeps (it leaves
    // emitter pixels exact).
    const SurfaceBsdf bsdf(n, wo, face.reflectance, face.roughness, c.options.diffuse,
                           c.has_roughness && face.emitter < 0);
    if (path.bounce == 0) recordCameraHit(path, bsdf, face.emitter);
    if (path.bounce == c.options.max_bounces) return;
    const Eigen::Vector3f shadow_origin = path.point + n * offsetFor(hit.distance);
    sampleSceneLights(path, index, bsdf, shadow_origin);
    sampleSkyAndSun(path, index, bsdf, shadow_origin);

    // BSDF sampling: the lobe mixture (cosine-weighted hemisphere without a specular lobe).
    const float u_lobe = bsdf.specular() ? rng.get1D() : 0.f;
    const auto [u1, u2] = rng.get2D();
    Eigen::Vector3f wi;
    const bool sampled = bsdf.sample(u_lobe, u1, u2, &wi);
    const int splits = emissionSplits(path);
    addSplitEmission(path, bsdf, shadow_origin, splits);
    path.emission_scale = 1.f / static_cast<float>(splits);
    if (!sampled) return;
    continuePath(path, bsdf, shadow_origin, wi);
  }

  // A camera ray's hit on a face whose three vertices were made from pixels, one of them the
  // sample's own: `out` is the face's shading with that pixel's texel (reflectance, roughness,
  // emitter). Its emission is found at the camera ray only, where no MIS weight applies.
  bool texelShading(const Path& path, SlotShading& out) const {
    if (path.bounce != 0 || path.texel < 0) return false;
    const RenderScene& scene = c_.scene;
    const auto& face = scene.faces[(*c_.slot_triangles)[path.hit.slot]];
    bool own = false;
    for (const std::uint32_t v : face) {
      const std::int32_t t = scene.vertex_texel[v];
      if (t < 0) return false;
      own = own || t == path.texel;
    }
    if (!own) return false;
    const auto texel = static_cast<std::size_t>(path.texel);
    out = slotShading(c_.shading, path.hit.slot);
    out.reflectance = scene.texel_reflectance[texel];
    if (!scene.texel_roughness.empty()) out.roughness = scene.texel_roughness[texel];
    out.emitter = scene.texel_emitter[texel];
    out.emissive = -1;
    return true;
  }

  // A ray that left the scene: sky and sun, MIS-weighted against their next-event estimation
  // after the first bounce.
  void addSkyAndSunFound(Path& path) const {
    const Context& c = c_;
    const int bounce = path.bounce;
    const Eigen::Vector3f& direction = path.direction;
    Eigen::Vector3f& radiance = path.radiance;
    const Eigen::Vector3f& throughput = path.throughput;
    if (c.sky_on) {
      const float sky_pdf = std::max(0.f, path.previous_normal.dot(direction)) / kPi;
      const float weight = bounce == 0 ? 1.f : powerHeuristic(path.previous_bsdf_pdf, sky_pdf);
      radiance += throughput.cwiseProduct(skyRadiance(c.scene, direction)) * weight;
    }
    if (c.sun.on && c.sun.contains(direction)) {
      const float weight = bounce == 0 ? 1.f : powerHeuristic(path.previous_bsdf_pdf, c.sun.pdf);
      radiance += throughput.cwiseProduct(c.sun.radiance) * weight;
    }
  }

  // The emission of the face hit (emitter `emitter_index`, emissive triangle `emissive`, -1:
  // none), seen at |cosine| `abs_cos_hit`; MIS-weighted after the first bounce.
  void addEmissionFound(Path& path, int emitter_index, int emissive, float abs_cos_hit) const {
    if (emitter_index < 0) return;
    const Context& c = c_;
    const Emitter& e = c.scene.emitters[static_cast<std::size_t>(emitter_index)];
    const Eigen::Vector3f emitted =
        e.radiance * profile(e, abs_cos_hit, path.point, -path.direction);
    if (path.bounce == 0) {
      path.radiance += emitted;
    } else {
      const float weight = bounceEmissionWeight(c, emissive, path.previous_point, path.previous_normal, path.origin,
                                                path.direction, path.hit.distance, abs_cos_hit,
                                                path.previous_bsdf_pdf);
      path.radiance += path.throughput.cwiseProduct(emitted) * (weight * path.emission_scale);
    }
  }

  // The camera ray's hit: whether it sees an emitter, and the AOVs when the path fills them.
  void recordCameraHit(Path& path, const SurfaceBsdf& bsdf, int emitter_index) const {
    path.sees_emitter = emitter_index >= 0;
    path.camera_albedo = bsdf.albedo();
    if (!path.first) return;
    path.first->albedo = bsdf.albedo();
    path.first->normal = path.normal;
    path.first->depth = path.hit.distance * path.z_per_distance;
    path.first->light_id = emitter_index >= 0 ? c_.scene.emitters[static_cast<std::size_t>(emitter_index)].light_id : 0;
  }

  // Next-event estimation toward the scene's lights: one sample on an emissive triangle
  // (MIS-weighted against BSDF sampling) and one on each rectangle light (the headlights, not
  // geometry: light sampling only, weight 1). Their unoccluded contributions are computed
  // first; then one shadow ray goes to a light chosen in proportion to its contribution
  // (one_shadow_ray) or one to each.
  void sampleSceneLights(Path& path, std::uint32_t index, const SurfaceBsdf& bsdf, const Eigen::Vector3f& shadow_origin) {
    const Context& c = c_;
    Sampler& rng = *path.rng;
    const Eigen::Vector3f& n = path.normal;
    const Eigen::Vector3f& throughput = path.throughput;
    const int tri = path.picked;
    const float pick_pmf = path.pick_pmf;
    OneLightChoice choice(path.u_choice);
    const auto offer = [&](const Eigen::Vector3f& contribution, const Eigen::Vector3f& wi, float distance) {
      if (!contribution.allFinite()) {
        path.radiance += contribution;  // the sample is dropped, as any non-finite one
      } else if (!(contribution.maxCoeff() > 0.f)) {
        // nothing a shadow ray could add
      } else if (c.options.one_shadow_ray) {
        choice.offer(contribution, wi, distance);
      } else {
        shadow_rays_.push_back({shadow_origin, wi, contribution, distance * (1.f - 1e-4f), index});
      }
    };
    const auto [su, sv] = rng.get2D();
    if (tri >= 0 && pick_pmf > 0.f) {
      const EmissiveTriangle& t = c.emissive[static_cast<std::size_t>(tri)];
      const EmitterSample sample = sampleEmitter(t, shadow_origin, n, su, sv, c.options.solid_angle_emitter_sampling);
      const float cos_surface = n.dot(sample.wi);
      if (sample.ok && cos_surface > 0.f) {
        const Emitter& e = c.scene.emitters[t.emitter];
        const Eigen::Vector3f emitted =
            e.radiance * profile(e, sample.cos_light, shadow_origin + sample.wi * sample.distance, -sample.wi);
        const float light_pdf = pick_pmf * sample.pdf;
        float bsdf_pdf = 0.f;
        const Eigen::Vector3f f = bsdf.evalAndPdf(sample.wi, &bsdf_pdf);
        const float weight = powerHeuristic(light_pdf, bsdf_pdf);
        offer(throughput.cwiseProduct(f).cwiseProduct(emitted) * (cos_surface * weight / light_pdf), sample.wi,
              sample.distance);
      }
    }
    for (std::size_t l = 0; l < c.scene.rectangle_lights.size(); ++l) {
      const RectangleLight& light = c.scene.rectangle_lights[l];
      const float area = c.rectangle_area[l];
      const auto [lu, lv] = rng.get2D();
      const Eigen::Vector3f q = light.centre + light.edge_u * (lu - 0.5f) + light.edge_v * (lv - 0.5f);
      Eigen::Vector3f wi = q - shadow_origin;
      const float distance2 = wi.squaredNorm();
      const float distance = std::sqrt(distance2);
      if (!(distance > 0.f) || !(area > 0.f)) continue;
      wi /= distance;
      const float cos_surface = n.dot(wi);
      const float cos_light = light.normal.dot(-wi);
      if (cos_surface <= 0.f || cos_light <= c.rectangle_cos_half_spread[l]) continue;
      const float pdf = distance2 / (cos_light * area);
      offer(throughput.cwiseProduct(bsdf.eval(wi)).cwiseProduct(light.radiance) * (cos_surface / pdf), wi, distance);
    }
    if (!choice.empty()) queueChosenLight(choice, shadow_origin, index);
  }

  // The shadow ray toward the light `choice` kept, unless shadow-ray roulette skips it.
  void queueChosenLight(const OneLightChoice& choice, const Eigen::Vector3f& shadow_origin, std::uint32_t index) {
    Eigen::Vector3f contribution = choice.contribution();
    const float largest = contribution.maxCoeff();
    // Shadow-ray roulette: a contribution far below the noise the sensor will add is traced
    // with probability largest / threshold and, when traced, divided by it (unbiased; it adds
    // at most largest x threshold of variance to the sample).
    bool traced = true;
    if (largest < c_.shadow_roulette_y) {
      const float keep = largest / c_.shadow_roulette_y;
      traced = choice.leftover() < keep;
      contribution /= keep;
      shadow_rays_skipped += !traced;
    }
    if (traced)
      shadow_rays_.push_back({shadow_origin, choice.wi(), contribution, choice.distance() * (1.f - 1e-4f), index});
  }

  // Next-event estimation toward the sky (a cosine-weighted direction) and the sun (a direction
  // in its disc), each MIS-weighted against BSDF sampling.
  void sampleSkyAndSun(Path& path, std::uint32_t index, const SurfaceBsdf& bsdf, const Eigen::Vector3f& shadow_origin) {
    const Context& c = c_;
    Sampler& rng = *path.rng;
    const Eigen::Vector3f& n = path.normal;
    const Eigen::Vector3f& throughput = path.throughput;
    constexpr float kInfinity = std::numeric_limits<float>::infinity();
    if (c.sky_on) {
      const auto [u1, u2] = rng.get2D();
      const Eigen::Vector3f wi = cosineSample(n, u1, u2);
      const float cos_surface = n.dot(wi);
      if (cos_surface > 1e-7f) {
        const float sky_pdf = cos_surface / kPi;
        float bsdf_pdf = 0.f;
        const Eigen::Vector3f f = bsdf.evalAndPdf(wi, &bsdf_pdf);
        const float weight = powerHeuristic(sky_pdf, bsdf_pdf);
        shadow_rays_.push_back({shadow_origin, wi,
                                throughput.cwiseProduct(f).cwiseProduct(skyRadiance(c.scene, wi)) *
                                    (cos_surface * weight / sky_pdf),
                                kInfinity, index});
      }
    }
    if (c.sun.on) {
      const auto [u1, u2] = rng.get2D();
      const Eigen::Vector3f wi = c.sun.sample(u1, u2);
      const float cos_surface = n.dot(wi);
      if (cos_surface > 0.f) {
        float bsdf_pdf = 0.f;
        const Eigen::Vector3f f = bsdf.evalAndPdf(wi, &bsdf_pdf);
        const float weight = powerHeuristic(c.sun.pdf, bsdf_pdf);
        shadow_rays_.push_back({shadow_origin, wi,
                                throughput.cwiseProduct(f).cwiseProduct(c.sun.radiance) *
                                    (cos_surface * weight / c.sun.pdf),
                                kInfinity, index});
      }
    }
  }

  // Emission splitting (PathTracerOptions::emission_splits): beside a large emitter the
  // bounce's emission term is a rare, bright hit; it is averaged over `splits` directions, the
  // extra ones here (traced at once, outside the wave: they are rare), the path's own at the
  // next vertex scaled by emission_scale. The choice depends only on this vertex, so the
  // estimate stays unbiased. Returns the vertex's split count (1: none).
  int emissionSplits(const Path& path) {
    const Context& c = c_;
    if (!(c.options.emission_splits > 1 && path.picked >= 0)) return 1;
    const EmissiveTriangle& t = c.emissive[static_cast<std::size_t>(path.picked)];
    if (!(((t.p0 + t.p1 + t.p2) / 3.f - path.point).squaredNorm() <
          c.options.split_distance_m * c.options.split_distance_m))
      return 1;
    ++split_vertices;
    return c.options.emission_splits;
  }

  // The emission found along the vertex's `splits` - 1 extra BSDF directions, each weighted
  // 1 / splits.
  void addSplitEmission(Path& path, const SurfaceBsdf& bsdf, const Eigen::Vector3f& shadow_origin, int splits) {
    const Context& c = c_;
    Sampler& rng = *path.rng;
    const Eigen::Vector3f& point = path.point;
    const Eigen::Vector3f& n = path.normal;
    for (int extra = 1; extra < splits; ++extra) {
      const float v_lobe = bsdf.specular() ? rng.get1D() : 0.f;
      const auto [v1, v2] = rng.get2D();
      Eigen::Vector3f w;
      if (!bsdf.sample(v_lobe, v1, v2, &w)) continue;
      float p = 0.f;
      const Eigen::Vector3f f = bsdf.evalAndPdf(w, &p);
      if (!(p > 0.f)) continue;
      const SlotHit h = closestHit(shadow_origin, w);
      if (!h.hit) continue;
      const SlotShading& hit_face = slotShading(c.shading, h.slot);
      if (hit_face.emitter < 0) continue;
      const Emitter& e = c.scene.emitters[static_cast<std::size_t>(hit_face.emitter)];
      const float abs_cos = std::abs(decodeOctahedral(hit_face.normal).dot(w));
      const float weight = bounceEmissionWeight(c, hit_face.emissive, point, n, shadow_origin, w, h.distance, abs_cos, p);
      const Eigen::Vector3f emitted = e.radiance * profile(e, abs_cos, shadow_origin + w * h.distance, -w);
      path.radiance += path.throughput.cwiseProduct(f).cwiseProduct(emitted) * (n.dot(w) / p * weight / static_cast<float>(splits));
    }
  }

  // The path's next ray along the sampled direction `wi`, with Russian roulette; `alive` stays
  // false when the path ends here.
  void continuePath(Path& path, const SurfaceBsdf& bsdf, const Eigen::Vector3f& shadow_origin,
                    const Eigen::Vector3f& wi) const {
    const Context& c = c_;
    const Eigen::Vector3f& n = path.normal;
    const Eigen::Vector3f& throughput = path.throughput;
    const float cos_surface = n.dot(wi);
    float bsdf_pdf = 0.f;
    const Eigen::Vector3f f = bsdf.evalAndPdf(wi, &bsdf_pdf);
    if (!(bsdf_pdf > 0.f)) return;
    path.throughput = throughput.cwiseProduct(f) * (cos_surface / bsdf_pdf);
    if (path.bounce + 1 >= c.options.russian_roulette_after) {
      const float survive = std::clamp(path.throughput.maxCoeff(), 0.05f, 1.f);
      if (path.rng->get1D() >= survive) return;
      path.throughput /= survive;
    }
    if (!(path.throughput.maxCoeff() > 0.f)) return;
    path.previous_bsdf_pdf = bsdf_pdf;
    path.previous_point = path.point;
    path.previous_normal = n;
    path.origin = shadow_origin;
    path.direction = wi;
    path.bounce = path.bounce + 1;
    path.alive = true;
  }

  // The path's value: its radiance, with light scattered more than once clamped when asked.
  Eigen::Vector3f clampIndirect(const Path& p) {
    if (c_.options.indirect_clamp > 0.f && !std::isnan(p.direct.x())) {
      Eigen::Vector3f indirect = p.radiance - p.direct;
      if (indirect.y() > c_.options.indirect_clamp) {
        indirect *= c_.options.indirect_clamp / indirect.y();
        ++clamped;
      }
      return p.direct + indirect;
    }
    return p.radiance;
  }

  // The path's value: clampIndirect's, restricted to the component asked for.
  Eigen::Vector3f pathValue(const Path& p) {
    const Eigen::Vector3f value = clampIndirect(p);
    if (c_.options.component == PathComponent::All) return value;
    // A path that ended at its first vertex, or whose second ray hit nothing, scattered its light
    // at most once.
    const Eigen::Vector3f direct = std::isnan(p.direct.x()) ? p.radiance : p.direct;
    if (c_.options.component == PathComponent::Direct) return direct;
    return value - direct;
  }

  const Context& c_;
  std::vector<RecordedRay>* log_;
  std::vector<std::uint32_t> active_;
  std::vector<ShadowRay> shadow_rays_;
};

class ProgressBar {
 public:
  ProgressBar(bool enabled, int total) : enabled_(enabled && ::isatty(2)), total_(total) {}
  void tick() {
    const int done = ++done_;
    if (!enabled_) return;
    std::unique_lock<std::mutex> lock(mutex_, std::try_to_lock);
    if (!lock.owns_lock() && done != total_) return;
    const int width = 40, filled = width * done / total_;
    std::fprintf(stderr, "\rrender [%.*s%*s] %3d%%", filled, "########################################",
                 width - filled, "", 100 * done / total_);
    if (done == total_) std::fprintf(stderr, "\n");
    std::fflush(stderr);
  }

 private:
  bool enabled_;
  int total_;
  std::atomic<int> done_{0};
  std::mutex mutex_;
};

// Whether the scene's pixel texture is complete (render_scene.h): a texel per pixel of its
// grid, a texel index per vertex.
bool hasPixelTexture(const RenderScene& scene) {
  const std::size_t texels =
      static_cast<std::size_t>(std::max(0, scene.texture_width)) * static_cast<std::size_t>(std::max(0, scene.texture_height));
  return texels > 0 && scene.vertex_texel.size() == scene.vertices.size() && scene.texel_reflectance.size() == texels &&
         scene.texel_emitter.size() == texels && (scene.texel_roughness.empty() || scene.texel_roughness.size() == texels);
}

}  // namespace

struct PreparedRenderScene::Impl {
  explicit Impl(const RenderScene& rendered) : scene(rendered) {}
  const RenderScene& scene;
  std::unique_ptr<RayCaster> caster;
  double build_seconds = 0;
  std::vector<EmissiveTriangle> emissive;
  std::vector<QuadShading> shading;  // by the caster's slot
  std::vector<std::uint32_t> slot_triangles;  // the caster's triangle per slot, with a pixel texture
  double prepare_seconds = 0;  // the whole construction, BVH included
  // Light samplers built on first use, one per kind, shared by every render of the scene
  // (the hierarchy over the 1080p street's 188 000 emitting triangles takes a noticeable
  // fraction of a second to build; a preview and the final render need it twice).
  mutable std::mutex samplers_mutex;
  mutable std::array<std::unique_ptr<LightSampler>, 6> samplers;  // per kind, without and with near field

  const LightSampler& lightSampler(LightSamplerKind kind, bool near_field) const {
    const std::lock_guard<std::mutex> lock(samplers_mutex);
    std::unique_ptr<LightSampler>& sampler = samplers.at(2 * static_cast<std::size_t>(kind) + (near_field ? 1 : 0));
    if (!sampler) sampler = makeLightSampler(kind, emissive, near_field);
    return *sampler;
  }
};

PreparedRenderScene::PreparedRenderScene(const RenderScene& scene) : impl_(new Impl(scene)) {
  const Stopwatch prepare_clock;
  CV_Assert(scene.face_reflectance.size() == scene.faces.size());
  CV_Assert(scene.face_emitter.empty() || scene.face_emitter.size() == scene.faces.size());
  std::vector<float> vertices;
  vertices.reserve(scene.vertices.size() * 3);
  for (const Eigen::Vector3f& v : scene.vertices) vertices.insert(vertices.end(), {v.x(), v.y(), v.z()});
  std::vector<std::uint32_t> indices;
  indices.reserve(scene.faces.size() * 3);
  for (const auto& f : scene.faces) indices.insert(indices.end(), f.begin(), f.end());
  Stopwatch build_clock;
  impl_->caster = std::make_unique<RayCaster>(std::move(vertices), std::move(indices));
  impl_->build_seconds = build_clock.seconds();

  impl_->emissive = collectEmissiveTriangles(scene);
  std::vector<int> face_to_emissive(scene.faces.size(), -1);
  for (std::size_t i = 0; i < impl_->emissive.size(); ++i)
    face_to_emissive[impl_->emissive[i].face] = static_cast<int>(i);
  std::vector<std::uint32_t> slot_triangles = impl_->caster->slotTriangles();
  impl_->shading = buildSlotShading(scene, slot_triangles, face_to_emissive);
  if (hasPixelTexture(scene)) impl_->slot_triangles = std::move(slot_triangles);
  impl_->prepare_seconds = prepare_clock.seconds();
}

PreparedRenderScene::~PreparedRenderScene() = default;
const RenderScene& PreparedRenderScene::scene() const { return impl_->scene; }
double PreparedRenderScene::bvhBuildSeconds() const { return impl_->build_seconds; }
double PreparedRenderScene::prepareSeconds() const { return impl_->prepare_seconds; }

RenderOutput renderPathTraced(const RenderScene& scene, const PathTracerOptions& options) {
  const PreparedRenderScene prepared(scene);
  RenderOutput out = renderPathTraced(prepared, scene.camera, options);
  out.report.seconds += prepared.prepareSeconds();  // the render's time includes its BVH
  return out;
}

namespace {

constexpr int kTile = 16;  // tile side, pixels

// The render's shared state: the scene, its lights and the per-render constants.
Context makeContext(const RenderScene& scene, const PinholeCamera& camera, const PathTracerOptions& options,
                    const PreparedRenderScene::Impl& p, const LightSampler& sampler) {
  const bool sky_on = scene.sky_radiance.maxCoeff() > 0.f ||
                      (scene.sky_zenith_radiance && scene.sky_zenith_radiance->maxCoeff() > 0.f);
  Context context{scene, camera, options, *p.caster, p.emissive, sampler, p.shading, SunDisc(scene.sun),
                  sky_on, !scene.face_roughness.empty(), {}, {}};
  for (const RectangleLight& light : scene.rectangle_lights) {
    context.rectangle_area.push_back(light.edge_u.cross(light.edge_v).norm());
    context.rectangle_cos_half_spread.push_back(std::cos(0.5f * light.spread_rad));
  }
  const std::size_t pixels = static_cast<std::size_t>(camera.width) * static_cast<std::size_t>(camera.height);
  if (options.cover_mesh_cracks && scene.surface_pixels.size() == pixels && camera.width == scene.camera.width &&
      camera.height == scene.camera.height)
    context.surface_pixels = scene.surface_pixels.data();
  if (options.pixel_texture && !p.slot_triangles.empty() && camera.width == scene.texture_width &&
      camera.height == scene.texture_height)
    context.slot_triangles = &p.slot_triangles;
  if (options.noise_sigma && options.shadow_roulette > 0) {
    // A threshold that is not a finite positive float would skip every shadow ray (or none
    // reliably): the roulette is then off.
    const float threshold = static_cast<float>(options.shadow_roulette * options.noise_sigma(0.0));
    if (std::isfinite(threshold) && threshold > 0.f) context.shadow_roulette_y = threshold;
  }
  return context;
}

RenderOutput allocateOutput(int width, int height) {
  RenderOutput out;
  out.radiance.create(height, width, CV_32FC3);
  out.albedo.create(height, width, CV_32FC3);
  out.mean_albedo.create(height, width, CV_32FC3);
  out.normal.create(height, width, CV_32FC3);
  out.depth_m.create(height, width, CV_32F);
  out.light_id.create(height, width, CV_32S);
  out.emitter_coverage.create(height, width, CV_32F);
  out.samples.create(height, width, CV_32S);
  out.std_error.create(height, width, CV_32F);
  return out;
}

// How many samples a pixel takes, and how its error is estimated.
struct SampleBudget {
  int replicates = 1;  // independent replicates of the point set (sampler.h)
  int min_samples = 2, max_samples = 2;
  bool pooled = false;  // replicate variances pooled over the tile (pool_error_gain)
  // AdaptiveRule::ImageError: a pixel takes samples_per_sigma x (uniform_share x image_sigma +
  // (1 - uniform_share) x its neighbours' per-sample standard deviation of Y), within min and
  // max; the image's constants from the pilot. Every pixel first takes first_samples
  // (min_samples, or fewer when the min_samples budget is spread by the rule).
  bool allocate = false;
  int first_samples = 2;
  double samples_per_sigma = 0, image_sigma = 0, uniform_share = 0;
  // The target needs fewer samples than min_samples everywhere and the rule spreads them.
  bool spreadsMinSamples() const { return first_samples < min_samples; }
};

// Whether the ImageError rule applies: adaptive, with relative_error the only target.
bool allocatesSamples(const PathTracerOptions& options) {
  const bool adaptive = std::max(2, options.min_samples) < options.max_samples;
  return adaptive && options.adaptive_rule == AdaptiveRule::ImageError && options.relative_error > 0 &&
         options.absolute_error.empty() && !options.noise_sigma;
}

SampleBudget sampleBudget(const PathTracerOptions& options) {
  SampleBudget budget;
  const bool adaptive = std::max(2, options.min_samples) < options.max_samples;
  budget.allocate = allocatesSamples(options);
  // Replicates (sampler.h) only where stopping decisions are made: a fixed sample count, and
  // the ImageError rule, keep the single, best stratified point set.
  const int replicates =
      options.sampler == SamplerKind::Sobol && adaptive && !budget.allocate ? options.error_replicates : 1;
  if (replicates != 1 && replicates != 2 && replicates != 4 && replicates != 8)
    throw std::invalid_argument("renderPathTraced: error_replicates must be 1, 2, 4 or 8, got " +
                                std::to_string(options.error_replicates));
  budget.replicates = replicates;
  // Checks fall on multiples of the replicate count, where every replicate has as many samples.
  budget.min_samples = (std::max(2, options.min_samples) + replicates - 1) / replicates * replicates;
  budget.max_samples = std::max(budget.min_samples, options.max_samples);
  budget.pooled = replicates > 1 && options.pool_error_gain;
  budget.first_samples = budget.min_samples;
  return budget;
}

// A pixel's running state; a tile's pixels advance in rounds of 8 samples so that the pooled
// error estimate (TileRenderer::tileGain) can use the whole tile before each round's stopping
// decisions.
struct PixelState {
  int x, y;
  Sampler rng;
  FirstHit first;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  Eigen::Vector3d albedo_sum = Eigen::Vector3d::Zero();  // of the counted samples' camera hits
  double mean_y = 0, m2_y = 0;  // running mean and squared deviations of Y (Welford)
  std::array<double, kMaxReplicates> replicate_sum{};
  std::array<int, kMaxReplicates> replicate_count{};
  int n = 0, taken = 0;  // finite samples, samples taken
  int allotted = 0;      // the ImageError rule's sample count for the pixel
  int emitter_hits = 0;  // samples whose camera ray hit an emitter
  int crack_samples = 0; // samples not counted: a surface pixel's camera ray that hit nothing
  bool surface = false;  // RenderScene::surface_pixels marks it (and cracks are covered)
  bool done = false;
  double stopped_variance = -1;  // variance of the mean when the target stopped it
  // Variance of the mean as if the samples were independent: sample variance / n.
  double independentVariance() const { return n > 1 ? m2_y / (n - 1) / n : 0.0; }
  // Variance of the mean from the spread of the replicate means (unbiased for any sampler).
  double replicateVariance(int replicates) const {
    double means[kMaxReplicates], grand = 0;
    for (int r = 0; r < replicates; ++r) {
      if (replicate_count[static_cast<std::size_t>(r)] == 0) return std::numeric_limits<double>::infinity();
      means[r] = replicate_sum[static_cast<std::size_t>(r)] / replicate_count[static_cast<std::size_t>(r)];
      grand += means[r] / replicates;
    }
    double squares = 0;
    for (int r = 0; r < replicates; ++r) squares += (means[r] - grand) * (means[r] - grand);
    return squares / (replicates * (replicates - 1));
  }
};

// What the tiles add up for the report.
struct RenderTotals {
  std::atomic<std::int64_t> rays{0}, samples{0}, dropped{0}, clamped{0}, stopped_by_target{0}, split_vertices{0},
      shadow_skipped{0}, crack_samples{0};
};

// Renders one tile: every pixel's first samples, then rounds of more for the pixels short of
// their error target, then the pixels' values into the output.
class TileRenderer {
 public:
  TileRenderer(const Context& c, const SampleBudget& budget, int x0, int y0, std::vector<RecordedRay>* log)
      : c_(c), options_(c.options), budget_(budget), tracer_(c, log) {
    const int width = c.camera.width, height = c.camera.height;
    pixels_.reserve(kTile * kTile);
    for (int y = y0; y < std::min(y0 + kTile, height); ++y)
      for (int x = x0; x < std::min(x0 + kTile, width); ++x)
        pixels_.push_back({x, y,
                           Sampler(options_.sampler, options_.seed,
                                   static_cast<std::uint64_t>(y) * static_cast<std::uint64_t>(width) + static_cast<std::uint64_t>(x), budget_.replicates),
                           {}});
    tile_width_ = std::min(x0 + kTile, width) - x0;
    tile_rows_ = static_cast<int>(pixels_.size()) / tile_width_;
    if (c.surface_pixels)
      for (PixelState& p : pixels_)
        p.surface = c.surface_pixels[static_cast<std::size_t>(p.y) * static_cast<std::size_t>(width) + static_cast<std::size_t>(p.x)] != 0;
  }

  // Every pixel's first samples, one wave per sample index; then rounds of up to 8 more for
  // the pixels still short of their target. A pixel's samples stay in order, so its state
  // evolves as if it were sampled alone.
  void render() {
    for (PixelState& p : pixels_) wave_.push_back(&p);
    for (int k = 0; k < budget_.first_samples; ++k) takeSamples();
    if (budget_.allocate) {
      allotSamples();
      return;
    }
    for (;;) {
      if (budget_.pooled) gain_ = tileGain();
      if (!decideStops()) break;
      for (int k = 0; k < 8; ++k) {
        wave_.clear();
        for (PixelState& p : pixels_)
          if (!p.done && p.taken < budget_.max_samples) wave_.push_back(&p);
        if (wave_.empty()) break;
        takeSamples();
      }
    }
  }

  // The pixels' values and AOVs into `out`, the tile's counts into `totals`; `unseen` (CV_8U)
  // marks the surface pixels none of whose camera rays hit anything.
  void write(RenderOutput& out, RenderTotals& totals, cv::Mat& unseen) const {
    std::int64_t samples_taken = 0, crack_samples = 0;
    for (const PixelState& p : pixels_) {
      crack_samples += p.crack_samples;
      unseen.at<std::uint8_t>(p.y, p.x) = p.surface && p.n == 0 && p.crack_samples > 0;
      if (p.stopped_variance >= 0) ++totals.stopped_by_target;
      // At least the pixel's own samples' spread: a pixel stopped on its neighbours' estimate
      // may hold a rare bright sample they do not show, and the denoiser weighs it by this.
      double standard_error = std::sqrt(p.stopped_variance >= 0 ? std::max(p.stopped_variance, variance(p)) : variance(p));
      if (!std::isfinite(standard_error)) standard_error = std::sqrt(p.independentVariance());
      samples_taken += p.taken;
      const Eigen::Vector3d mean = p.n > 0 ? Eigen::Vector3d(p.sum / p.n) : Eigen::Vector3d::Zero();
      const int x = p.x, y = p.y;
      out.radiance.at<cv::Vec3f>(y, x) = {static_cast<float>(mean.x()), static_cast<float>(mean.y()), static_cast<float>(mean.z())};
      out.albedo.at<cv::Vec3f>(y, x) = {p.first.albedo.x(), p.first.albedo.y(), p.first.albedo.z()};
      const Eigen::Vector3d mean_albedo = p.n > 0 ? Eigen::Vector3d(p.albedo_sum / p.n) : Eigen::Vector3d::Zero();
      out.mean_albedo.at<cv::Vec3f>(y, x) = {static_cast<float>(mean_albedo.x()), static_cast<float>(mean_albedo.y()),
                                             static_cast<float>(mean_albedo.z())};
      out.normal.at<cv::Vec3f>(y, x) = {p.first.normal.x(), p.first.normal.y(), p.first.normal.z()};
      out.depth_m.at<float>(y, x) = p.first.depth;
      out.light_id.at<int>(y, x) = p.first.light_id;
      out.emitter_coverage.at<float>(y, x) = p.taken > 0 ? static_cast<float>(p.emitter_hits) / p.taken : 0.f;
      out.samples.at<int>(y, x) = p.taken;
      out.std_error.at<float>(y, x) = static_cast<float>(standard_error);
    }
    totals.rays += tracer_.rays;
    totals.samples += samples_taken;
    totals.dropped += nonfinite_;
    totals.clamped += tracer_.clamped;
    totals.split_vertices += tracer_.split_vertices;
    totals.shadow_skipped += tracer_.shadow_rays_skipped;
    totals.crack_samples += crack_samples;
  }

 private:
  // One more sample for each pixel of wave_ (distinct pixels), traced together (WaveTracer).
  void takeSamples() {
    const int replicates = budget_.replicates;
    paths_.clear();
    for (PixelState* p : wave_) {
      p->rng.startSample(static_cast<std::uint32_t>(p->taken));
      const auto [jx, jy] = p->rng.get2D();
      // A surface pixel's AOVs come from its first sample that hits.
      const bool aovs = p->taken == 0 || (p->surface && p->n == 0);
      paths_.push_back(WaveTracer::cameraPath(c_, static_cast<float>(p->x) + jx - 0.5f,
                                              static_cast<float>(p->y) + jy - 0.5f, p->rng,
                                              aovs ? &p->first : nullptr));
    }
    tracer_.trace(paths_);
    for (std::size_t k = 0; k < wave_.size(); ++k) {
      PixelState& p = *wave_[k];
      const Eigen::Vector3f& value = paths_[k].radiance;
      p.emitter_hits += paths_[k].sees_emitter;
      const int replicate = p.taken % replicates;
      ++p.taken;
      if (p.surface && paths_[k].camera_missed) {
        ++p.crack_samples;  // through a mesh crack: not part of the pixel's surface
        continue;
      }
      if (!std::isfinite(value.x()) || !std::isfinite(value.y()) || !std::isfinite(value.z())) {
        ++nonfinite_;  // never reaches the image
        continue;
      }
      ++p.n;
      p.sum += value.cast<double>();
      p.albedo_sum += paths_[k].camera_albedo.cast<double>();
      const double delta = luminance(value) - p.mean_y;
      p.mean_y += delta / p.n;
      p.m2_y += delta * (luminance(value) - p.mean_y);
      p.replicate_sum[static_cast<std::size_t>(replicate)] += luminance(value);
      ++p.replicate_count[static_cast<std::size_t>(replicate)];
    }
  }

  // The ImageError rule: each pixel's count from its neighbours' per-sample standard deviation
  // (independent of its own samples, so its mean stays unbiased), then waves of one more sample
  // for every pixel short of its count.
  void allotSamples() {
    for (std::size_t k = 0; k < pixels_.size(); ++k) {
      PixelState& p = pixels_[k];
      const double sigma = neighbourSigma(k);
      const double spread = budget_.uniform_share * budget_.image_sigma + (1 - budget_.uniform_share) * sigma;
      const double wanted = spread > 0 ? std::ceil(budget_.samples_per_sigma * spread) : budget_.min_samples;
      p.allotted = std::isfinite(wanted) ? static_cast<int>(std::clamp<double>(wanted, budget_.first_samples, budget_.max_samples))
                                         : budget_.max_samples;
    }
    for (;;) {
      wave_.clear();
      for (PixelState& p : pixels_)
        if (p.taken < p.allotted) wave_.push_back(&p);
      if (wave_.empty()) break;
      takeSamples();
    }
  }

  // The mean per-sample standard deviation of Y over the pixel's 3x3 neighbours in the tile
  // (itself excluded); its own when it has no neighbour with two samples.
  double neighbourSigma(std::size_t k) const {
    const int i = static_cast<int>(k) % tile_width_, j = static_cast<int>(k) / tile_width_;
    double sum = 0;
    int count = 0;
    for (int jj = std::max(0, j - 1); jj <= std::min(tile_rows_ - 1, j + 1); ++jj)
      for (int ii = std::max(0, i - 1); ii <= std::min(tile_width_ - 1, i + 1); ++ii) {
        const PixelState& q = pixels_[static_cast<std::size_t>(jj * tile_width_ + ii)];
        if ((ii == i && jj == j) || q.n < 2) continue;
        sum += std::sqrt(q.m2_y / (q.n - 1));
        ++count;
      }
    if (count > 0) return sum / count;
    const PixelState& p = pixels_[k];
    return p.n > 1 ? std::sqrt(p.m2_y / (p.n - 1)) : 0.0;
  }

  // The tile's stratification gain: summed replicate variances over summed independent-sample
  // variances. Its numerator and denominator pool every pixel of the tile, so it is steady
  // where one pixel's replicate spread (R - 1 degrees of freedom) is not; pixels with larger
  // variance weigh more, so it leans toward the gain of the tile's noisiest pixels.
  double tileGain() const {
    double replicate = 0, independent = 0;
    for (const PixelState& p : pixels_) {
      const double v = p.replicateVariance(budget_.replicates);
      if (!std::isfinite(v)) continue;
      replicate += v;
      independent += p.independentVariance();
    }
    return independent > 0 ? replicate / independent : 1.0;
  }

  // The variance of the pixel's mean, by the budget's estimate (with the tile's current gain).
  double variance(const PixelState& p) const {
    if (budget_.replicates == 1) return p.independentVariance();
    return budget_.pooled ? gain_ * p.independentVariance() : p.replicateVariance(budget_.replicates);
  }

  // stop_on_neighbours: the mean and per-sample variance of Y over the pixel's neighbours in
  // the tile (3x3, itself excluded), so that whether a pixel stops does not depend on its own
  // samples; false when it has no neighbour with two samples.
  bool neighbours(std::size_t k, double* mean_y, double* sample_variance) const {
    const int i = static_cast<int>(k) % tile_width_, j = static_cast<int>(k) / tile_width_;
    double sum_mean = 0, sum_variance = 0;
    int count = 0;
    for (int jj = std::max(0, j - 1); jj <= std::min(tile_rows_ - 1, j + 1); ++jj)
      for (int ii = std::max(0, i - 1); ii <= std::min(tile_width_ - 1, i + 1); ++ii) {
        const PixelState& q = pixels_[static_cast<std::size_t>(jj * tile_width_ + ii)];
        if ((ii == i && jj == j) || q.n < 2) continue;
        sum_mean += q.mean_y;
        sum_variance += q.m2_y / (q.n - 1);
        ++count;
      }
    if (count == 0) return false;
    *mean_y = sum_mean / count;
    *sample_variance = sum_variance / count;
    return true;
  }

  // Stops the pixels that reached their error target or max_samples; returns whether any is
  // left to sample.
  bool decideStops() {
    bool active = false;
    for (PixelState& p : pixels_) {
      if (p.done) continue;
      double mean_y = p.mean_y, neighbour_variance = 0;
      const bool from_neighbours = options_.stop_on_neighbours && p.n > 0 &&
                                   neighbours(static_cast<std::size_t>(&p - pixels_.data()), &mean_y, &neighbour_variance);
      const double v = from_neighbours ? (budget_.replicates > 1 && budget_.pooled ? gain_ : 1.0) * neighbour_variance / p.n
                                       : variance(p);
      const float absolute = options_.absolute_error.empty() ? 0.f : options_.absolute_error.at<float>(p.y, p.x);
      double target = std::max(options_.relative_error * std::abs(mean_y), static_cast<double>(absolute));
      if (options_.noise_sigma) target = std::max(target, options_.noise_factor * options_.noise_sigma(mean_y));
      if (std::sqrt(v) <= target) {
        p.done = true;
        p.stopped_variance = v;  // the estimate it stopped on; the tile's gain moves on later
      } else if (p.taken >= budget_.max_samples) {
        p.done = true;
      } else {
        active = true;
      }
    }
    return active;
  }

  const Context& c_;
  const PathTracerOptions& options_;
  const SampleBudget budget_;
  std::vector<PixelState> pixels_;
  int tile_width_ = 0, tile_rows_ = 0;
  WaveTracer tracer_;
  std::vector<Path> paths_;
  std::vector<PixelState*> wave_;
  std::int64_t nonfinite_ = 0;
  double gain_ = 1.0;  // the tile's stratification gain (tileGain), when pooled
};

// Noise estimate: median relative standard error over pixels that received light; none when
// none did.
std::optional<double> relativeStdErrorMedian(const RenderOutput& out) {
  std::vector<float> relative;
  for (int y = 0; y < out.radiance.rows; ++y)
    for (int x = 0; x < out.radiance.cols; ++x) {
      const float v = out.radiance.at<cv::Vec3f>(y, x)[1];
      if (v > 0.f) relative.push_back(out.std_error.at<float>(y, x) / v);
    }
  if (relative.empty()) return std::nullopt;
  std::nth_element(relative.begin(), relative.begin() + static_cast<std::ptrdiff_t>(relative.size() / 2), relative.end());
  return static_cast<double>(relative[relative.size() / 2]);
}

// The report's entries for the variance reductions that are on: indirect clamp, emission
// splitting, shadow-ray roulette.
void reportVarianceReduction(StageReport& r, const Context& context, const RenderTotals& totals) {
  const PathTracerOptions& options = context.options;
  if (options.indirect_clamp > 0.f) {
    r.add("indirect_clamp", static_cast<double>(options.indirect_clamp), "cd/m2");
    r.add("indirect_samples_clamped", static_cast<double>(totals.clamped.load()) / static_cast<double>(std::max<std::int64_t>(1, totals.samples.load())));
    r.notes.push_back("indirect light clamped at " + std::to_string(options.indirect_clamp) +
                      " cd/m2 per sample: fewer fireflies, biased darker");
  }
  if (options.emission_splits > 1) {
    r.add("emission_splits", static_cast<std::int64_t>(options.emission_splits));
    r.add("split_distance", static_cast<double>(options.split_distance_m), "m");
    r.add("vertices_split_per_sample", static_cast<double>(totals.split_vertices.load()) /
                                           static_cast<double>(std::max<std::int64_t>(1, totals.samples.load())));
  }
  if (context.shadow_roulette_y > 0.f) {
    r.add("shadow_roulette_threshold_y", static_cast<double>(context.shadow_roulette_y));
    r.add("shadow_rays_skipped", totals.shadow_skipped.load());
    char note[200];
    std::snprintf(note, sizeof note,
                  "shadow-ray roulette: next-event contributions below %.3g cd/m2 (%.2f x the sensor noise at black) "
                  "cast their shadow ray with probability contribution / threshold",
                  static_cast<double>(context.shadow_roulette_y), options.shadow_roulette);
    r.notes.push_back(note);
  }
}

// Rings of neighbours a crack pixel looks through for a pixel that shows a surface.
constexpr int kCrackFillPasses = 4;

// The surface pixels that `unseen` marks (every camera ray went through a mesh crack) take the
// value and AOVs of their farthest 8-neighbour that shows a surface, ring by ring: the surface
// behind the crack's near side. Each pass reads only pixels filled before it, so the result does
// not depend on the scan order. Returns the number filled; `unseen` keeps those left.
std::int64_t fillCrackPixels(RenderOutput& out, cv::Mat& unseen) {
  std::vector<cv::Point> left;
  for (int y = 0; y < unseen.rows; ++y)
    for (int x = 0; x < unseen.cols; ++x)
      if (unseen.at<std::uint8_t>(y, x)) left.emplace_back(x, y);
  std::int64_t filled = 0;
  for (int pass = 0; pass < kCrackFillPasses && !left.empty(); ++pass) {
    std::vector<std::pair<cv::Point, cv::Point>> copies;  // (to, from)
    std::vector<cv::Point> still;
    for (const cv::Point& t : left) {
      cv::Point from(-1, -1);
      float farthest = 0.f;
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const cv::Point q(t.x + dx, t.y + dy);
          if (q.x < 0 || q.y < 0 || q.x >= unseen.cols || q.y >= unseen.rows || unseen.at<std::uint8_t>(q)) continue;
          const float depth = out.depth_m.at<float>(q);
          if (depth > farthest) farthest = depth, from = q;
        }
      if (from.x >= 0) copies.emplace_back(t, from);
      else still.push_back(t);
    }
    for (const auto& [to, from] : copies) {
      out.radiance.at<cv::Vec3f>(to) = out.radiance.at<cv::Vec3f>(from);
      out.albedo.at<cv::Vec3f>(to) = out.albedo.at<cv::Vec3f>(from);
      out.mean_albedo.at<cv::Vec3f>(to) = out.mean_albedo.at<cv::Vec3f>(from);
      out.normal.at<cv::Vec3f>(to) = out.normal.at<cv::Vec3f>(from);
      out.depth_m.at<float>(to) = out.depth_m.at<float>(from);
      out.light_id.at<int>(to) = out.light_id.at<int>(from);
      out.emitter_coverage.at<float>(to) = out.emitter_coverage.at<float>(from);
      out.std_error.at<float>(to) = out.std_error.at<float>(from);
    }
    for (const auto& copy : copies) unseen.at<std::uint8_t>(copy.first) = 0;
    filled += static_cast<std::int64_t>(copies.size());
    left.swap(still);
  }
  return filled;
}

// The report's entries for the mesh cracks covered (PathTracerOptions::cover_mesh_cracks).
void reportCracks(StageReport& r, const RenderTotals& totals, std::int64_t filled, std::int64_t left) {
  const double samples = static_cast<double>(std::max<std::int64_t>(1, totals.samples.load()));
  r.add("camera_samples_through_cracks", static_cast<double>(totals.crack_samples.load()) / samples);
  r.add("crack_pixels_filled", filled);
  r.add("crack_pixels_left", left);
  if (totals.crack_samples.load() > 0)
    r.notes.push_back("mesh cracks: " + std::to_string(totals.crack_samples.load()) +
                      " camera samples in pixels with depth hit nothing and were not counted; " + std::to_string(filled) +
                      " pixels with no hit took their farthest neighbour's value");
}

// Whether camera rays took their pixel's texel (PathTracerOptions::pixel_texture), and why not.
void reportPixelTexture(StageReport& r, const Context& context, const PreparedRenderScene::Impl& p) {
  const bool used = context.slot_triangles != nullptr;
  r.add("pixel_texture", used);
  if (used || p.slot_triangles.empty()) return;
  const RenderScene& scene = context.scene;
  if (!context.options.pixel_texture)
    r.notes.push_back("pixel texture off: camera rays take their faces' material and light");
  else
    r.notes.push_back("pixel texture not used: the render is " + std::to_string(context.camera.width) + "x" +
                      std::to_string(context.camera.height) + ", the mesh's pixel grid " +
                      std::to_string(scene.texture_width) + "x" + std::to_string(scene.texture_height));
}

// The render's report: sampling, rays, BVH, lights and the techniques used.
void reportRender(RenderOutput& out, double seconds, const Context& context, const PreparedRenderScene::Impl& p,
                  const RenderTotals& totals) {
  const PathTracerOptions& options = context.options;
  const RenderScene& scene = context.scene;
  StageReport& r = out.report;
  r.name = "render";
  r.seconds = seconds;
  const double pixels = static_cast<double>(context.camera.width) * context.camera.height;
  r.add("samples_per_pixel_mean", static_cast<double>(totals.samples.load()) / pixels);
  double max_spp = 0;
  cv::minMaxLoc(out.samples, nullptr, &max_spp);
  r.add("samples_per_pixel_max", static_cast<std::int64_t>(max_spp));
  const std::int64_t rays_cast = totals.rays.load();
  r.add("rays", rays_cast);
  r.add("rays_per_second", static_cast<double>(rays_cast) / seconds);
  r.add("bvh_build", p.build_seconds, "s");
  r.add("bvh_primitives", static_cast<std::int64_t>(p.caster->primitiveCount()));
  r.add("emissive_triangles", static_cast<std::int64_t>(context.emissive.size()));
  r.add("light_sampler", std::string(lightSamplerName(options.light_sampler)));
  r.add("near_field_lights", options.near_field_lights);
  r.add("sampler", std::string(samplerKindName(options.sampler)));
  r.add("nonfinite_samples_dropped", totals.dropped.load());
  reportVarianceReduction(r, context, totals);
  if (const std::optional<double> median = relativeStdErrorMedian(out)) r.add("relative_std_error_median", *median);
  if (options.noise_sigma) {
    // The promise of the noise-matched target: the share of pixels it stopped, their estimated
    // render noise below noise_factor x the sensor noise they will get (the rest hit max_samples).
    r.add("noise_factor", options.noise_factor);
    r.add("pixels_below_noise_target", static_cast<double>(totals.stopped_by_target.load()) / pixels);
  }
  if (context.sun.on) {
    r.add("sun_illuminance_y", static_cast<double>(scene.sun.illuminance.y()));
    r.add("sun_angular_radius", static_cast<double>(scene.sun.angular_radius_rad), "rad");
  }
  r.add("seed", static_cast<std::int64_t>(options.seed));
  if (context.emissive.empty()) r.notes.push_back("no emitting triangle: no next-event estimation toward scene lights");
  reportPixelTexture(r, context, p);
  if (scene.face_roughness.empty()) r.notes.push_back("no roughness map: diffuse only");
  else if (options.diffuse == DiffuseModel::Disney) r.notes.push_back("roughness map given: Disney diffuse + GGX specular");
  else r.notes.push_back("roughness map given: Lambert diffuse + GGX specular");
}

}  // namespace

RenderOutput renderPathTraced(const PreparedRenderScene& prepared, const PinholeCamera& camera,
                              const PathTracerOptions& options);

namespace {

// The ImageError rule's constant. Pixel i's mean has variance s_i^2 / n_i (s_i its per-sample
// standard deviation); for a total of samples the image's summed variance is least with n_i
// proportional to s_i, and it equals eps^2 sum(mean_i^2) (relative RMSE eps) at
// n_i = s_i sum(s) / (eps^2 sum(mean^2)). The sums come from a pilot at a quarter of the
// resolution with min_samples per pixel (a sixteenth of the pixels), over the pixels that see no
// emitter (their error is that of their coverage, not of the light transport); per pixel they
// are the averages, which do not depend on the resolution.
// The ImageError rule's share of the samples spread evenly: a pixel's spread estimated from
// min_samples misses rare bright paths (a glossy reflection of a lamp found by few samples), and
// a pixel given few samples for it carries such a path's whole weight. Half even, half in
// proportion to the spread, costs at most 2x a pixel's variance against even sampling; with none
// even the rule lost to fixed sampling on the roughness scene (docs/rendering.md).
constexpr double kUniformShare = 0.5;

void setImageErrorBudget(const PreparedRenderScene& prepared, const PinholeCamera& camera, const PathTracerOptions& options,
                         SampleBudget& budget, std::int64_t* pilot_samples) {
  const int min_samples = budget.min_samples;
  PathTracerOptions pilot = options;
  pilot.min_samples = pilot.max_samples = min_samples;
  pilot.progress = false;
  pilot.ray_log = nullptr;
  pilot.seed = options.seed ^ 0x9e3779b97f4a7c15ULL;
  const PinholeCamera small = camera.scaledTo(std::max(1, camera.width / 4), std::max(1, camera.height / 4));
  const RenderOutput out = renderPathTraced(prepared, small, pilot);
  double sigma_sum = 0, square_sum = 0;
  std::int64_t count = 0;
  for (int y = 0; y < out.radiance.rows; ++y)
    for (int x = 0; x < out.radiance.cols; ++x) {
      if (out.emitter_coverage.at<float>(y, x) > 0.f) continue;
      ++count;
      const double mean_y = out.radiance.at<cv::Vec3f>(y, x)[1];
      // A fixed count reports sample variance / n as its standard error.
      sigma_sum += static_cast<double>(out.std_error.at<float>(y, x)) * std::sqrt(static_cast<double>(out.samples.at<int>(y, x)));
      square_sum += mean_y * mean_y;
    }
  *pilot_samples = static_cast<std::int64_t>(small.width) * small.height * min_samples;
  budget.uniform_share = kUniformShare;
  budget.image_sigma = count > 0 ? sigma_sum / static_cast<double>(count) : 0.0;
  budget.samples_per_sigma = square_sum > 0 ? sigma_sum / (options.relative_error * options.relative_error * square_sum)
                                            : std::numeric_limits<double>::infinity();  // nothing lit: the cap decides
  // The target met with fewer samples than min_samples everywhere: min_samples alone would
  // sample every pixel evenly, so the rule spreads that budget instead (a pilot mean of
  // min_samples) after a first pass of half of it (from 4 on: the spread needs 2 samples).
  if (min_samples >= 4 && budget.image_sigma > 0 && budget.samples_per_sigma * budget.image_sigma < min_samples) {
    budget.first_samples = min_samples / 2;
    budget.samples_per_sigma = min_samples / budget.image_sigma;
  }
}

}  // namespace

RenderOutput renderPathTraced(const PreparedRenderScene& prepared, const PinholeCamera& camera,
                              const PathTracerOptions& options) {
  Stopwatch clock;
  const RenderScene& scene = prepared.scene();
  const PreparedRenderScene::Impl& p = prepared.impl();
  const int width = camera.width, height = camera.height;
  CV_Assert(width > 0 && height > 0);
  CV_Assert(options.absolute_error.empty() || (options.absolute_error.type() == CV_32F &&
                                                options.absolute_error.size() == cv::Size(width, height)));
  const LightSampler& sampler = p.lightSampler(options.light_sampler, options.near_field_lights);
  if (!scene.face_roughness.empty()) ggxAverageAlbedo(0.5f);  // builds the albedo table before the tiles start
  const Context context = makeContext(scene, camera, options, p, sampler);
  RenderOutput out = allocateOutput(width, height);
  SampleBudget budget = sampleBudget(options);
  std::int64_t pilot_samples = 0;
  if (budget.allocate) setImageErrorBudget(prepared, camera, options, budget, &pilot_samples);

  const int tiles_x = (width + kTile - 1) / kTile, tiles_y = (height + kTile - 1) / kTile;
  ProgressBar progress(options.progress, tiles_x * tiles_y);
  std::mutex ray_log_mutex;
  RenderTotals totals;
  cv::Mat unseen(height, width, CV_8U, cv::Scalar(0));
  tbb::parallel_for(0, tiles_x * tiles_y, [&](int tile) {
    std::vector<RecordedRay> tile_rays;
    std::vector<RecordedRay>* log = options.ray_log ? &tile_rays : nullptr;
    TileRenderer renderer(context, budget, (tile % tiles_x) * kTile, (tile / tiles_x) * kTile, log);
    renderer.render();
    renderer.write(out, totals, unseen);
    if (log) {
      const std::lock_guard<std::mutex> lock(ray_log_mutex);
      options.ray_log->insert(options.ray_log->end(), tile_rays.begin(), tile_rays.end());
    }
    progress.tick();
  });
  const std::int64_t filled = context.surface_pixels ? fillCrackPixels(out, unseen) : 0;
  reportRender(out, clock.seconds(), context, p, totals);
  if (context.surface_pixels) reportCracks(out.report, totals, filled, cv::countNonZero(unseen));
  if (budget.allocate) {
    out.report.add("adaptive_rule", std::string("image_error"));
    out.report.add("pilot_samples_per_pixel", static_cast<double>(pilot_samples) / (static_cast<double>(width) * height));
    out.report.add("image_error_budget", std::string(budget.spreadsMinSamples() ? "min_samples" : "relative_error"));
    if (budget.spreadsMinSamples())
      out.report.notes.push_back("the pilot meets the relative error target below min_samples: the min_samples "
                                 "budget is spread by the rule after " +
                                 std::to_string(budget.first_samples) + " samples a pixel");
  }
  return out;
}

}  // namespace solo
