#pragma once
// The renderer's surface reflection at one shading point: a diffuse lobe (Burley's Disney
// diffuse or Lambert) and, only where a roughness map was given, a GGX specular lobe of a
// dielectric (F0 = 0.04, ggx.h). The two are coupled so that what the specular lobe reflects
// is taken from the diffuse lobe (Kelemen and Szirmay-Kalos 2001):
//   f = albedo * diffuse_shape * (1 - E(cos_o)) (1 - E(cos_i)) / (1 - E_avg) + f_ggx,
// E the specular lobe's directional albedo and E_avg its cosine-weighted average. With a
// Lambertian shape the total directional albedo is E(cos_o) + albedo (1 - E(cos_o)) <= 1, and
// the BRDF stays reciprocal. Burley's shape itself reflects up to a few per cent more than it
// receives at roughness near 1 (its retro-reflection), with or without the specular lobe.
// Sampling picks a lobe in proportion to its estimated albedo (clamped to [0.1, 0.9]); pdf()
// is the mixture's density, which is what multiple importance sampling needs.

#include "solo/render/ggx.h"

#include <Eigen/Core>

namespace solo {

enum class DiffuseModel {
  Disney,   ///< Burley's diffuse lobe (the paper's), roughness 0.5 where no map is given
  Lambert,  ///< albedo / pi
};

class SurfaceBsdf {
 public:
  /// n: unit normal on the side of wo; wo: unit direction toward the viewer (n.wo > 0);
  /// albedo: XYZ reflectance in [0, 1]; specular: add the GGX lobe (alpha = roughness^2).
  SurfaceBsdf(const Eigen::Vector3f& n, const Eigen::Vector3f& wo, const Eigen::Vector3f& albedo, float roughness,
              DiffuseModel diffuse, bool specular);

  /// BRDF f(wo, wi), 1/sr per channel; 0 below the surface.
  Eigen::Vector3f eval(const Eigen::Vector3f& wi) const;
  /// Solid-angle density with which sample() returns wi.
  float pdf(const Eigen::Vector3f& wi) const;
  /// eval(wi), and pdf(wi) in *pdf: the same values, with the work they share done once.
  Eigen::Vector3f evalAndPdf(const Eigen::Vector3f& wi, float* pdf) const;
  /// Draws wi from three uniforms in [0, 1) (u0 picks the lobe and is unused without the
  /// specular lobe). Returns false when the draw leaves the upper hemisphere: the path ends
  /// there, which is unbiased since f is 0 for such directions.
  bool sample(float u0, float u1, float u2, Eigen::Vector3f* wi) const;

  bool specular() const { return specular_; }
  const Eigen::Vector3f& albedo() const { return albedo_; }

 private:
  Eigen::Vector3f toLocal(const Eigen::Vector3f& w) const { return {t_.dot(w), b_.dot(w), n_.dot(w)}; }
  Eigen::Vector3f diffuseShape(const Eigen::Vector3f& wi, float cos_i) const;

  Eigen::Vector3f n_, t_, b_, wo_, wo_local_, albedo_;
  float roughness_, alpha_ = 1.f;
  DiffuseModel diffuse_;
  bool specular_;
  float cos_o_;
  float one_minus_cos_o_pow5_;  // (1 - cos_o)^5, the Schlick weight of wo in Burley's lobe
  float diffuse_coupling_o_ = 1.f;  // (1 - E(cos_o)) / (1 - E_avg)
  GgxLobe lobe_;                     // the specular lobe from wo (specular_ only)
  float specular_probability_ = 0.f;
};

/// A right-handed orthonormal basis (t, b, n) around the unit vector n, branch-free and
/// continuous except at n = -z (Duff et al. 2017, "Building an orthonormal basis, revisited").
void orthonormalBasis(const Eigen::Vector3f& n, Eigen::Vector3f& t, Eigen::Vector3f& b);

}  // namespace solo
