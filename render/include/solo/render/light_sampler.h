#pragma once
// Chooses which emitting triangle a shading point samples next-event estimation from.
// Three strategies, selectable: uniform over triangles, proportional to emitted power, and a
// light hierarchy in the spirit of pbrt-v4's BVH light sampler (Conty and Kulla 2018) that
// also weighs each cluster's distance and orientation from the shading point.
// Triangles of zero radiance never enter any of them.

#include "solo/render/render_scene.h"

#include <Eigen/Core>

#include <memory>
#include <string>
#include <vector>

namespace solo {

enum class LightSamplerKind { Uniform, Power, Hierarchy };
const char* lightSamplerName(LightSamplerKind kind);
/// "uniform", "power", "hierarchy"; throws std::invalid_argument otherwise.
LightSamplerKind lightSamplerFromName(const std::string& name);

/// One emitting triangle, with what every sampler and next-event estimation need: 64 bytes,
/// one cache line, so that sampling a picked triangle misses the cache once.
struct alignas(64) EmissiveTriangle {
  std::uint32_t face = 0;
  std::uint32_t emitter = 0;  ///< index into RenderScene::emitters
  Eigen::Vector3f p0, p1, p2;
  Eigen::Vector3f normal;  ///< unit
  float area = 0;          ///< m^2
  float power = 0;         ///< luminance Y * area * pi * (profile integral factor)
};

/// Emitting triangles of a scene (non-zero radiance only), in face order.
std::vector<EmissiveTriangle> collectEmissiveTriangles(const RenderScene& scene);

class LightSampler {
 public:
  virtual ~LightSampler() = default;
  /// Picks a triangle index (into the collected list) for a shading point with normal n;
  /// returns -1 when nothing can be picked. pmf receives the probability of the pick.
  virtual int pick(const Eigen::Vector3f& point, const Eigen::Vector3f& normal, float u, float* pmf) const = 0;
  /// Probability that pick() at this shading point returns `triangle` (for MIS).
  virtual float pmf(const Eigen::Vector3f& point, const Eigen::Vector3f& normal, int triangle) const = 0;
  /// A hint that pick(..., u, ...) follows: a sampler whose pick ignores the shading point may
  /// start loading what it will read, so that the load overlaps the ray cast that finds the point.
  virtual void prefetch(float /*u*/) const {}
};

/// The sampler of `kind`; with `near_field`, mixed with near-field selection: a shading point
/// within 0.5 m of emitting triangles picks among their clusters by distance and orientation
/// with a probability of up to 1/2 that grows with their importance (docs/rendering.md).
std::unique_ptr<LightSampler> makeLightSampler(LightSamplerKind kind, const std::vector<EmissiveTriangle>& triangles,
                                               bool near_field = true);

}  // namespace solo
