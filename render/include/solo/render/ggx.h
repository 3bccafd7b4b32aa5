#pragma once
// GGX (Trowbridge-Reitz) microfacet specular reflection of a dielectric: the normal
// distribution D, Smith's height-correlated masking-shadowing G2, Schlick's Fresnel, sampling
// of the visible normals (Heitz 2018, "Sampling the GGX Distribution of Visible Normals") and
// the directional albedo of the lobe (tabulated once by quadrature).
// Directions are unit vectors in the local shading frame: the normal is +z.
// alpha = roughness^2 (Burley's remapping), clamped to [kGgxMinAlpha, 1]. Isotropic only.

#include <Eigen/Core>

namespace solo {

/// Reflectance at normal incidence of a dielectric of refractive index 1.5 ((n-1)/(n+1))^2:
/// paint, asphalt binder, glass, plastics. The specular lobe is colourless.
constexpr float kDielectricF0 = 0.04f;
/// Below this alpha the lobe's peak (1 / (pi alpha^2)) overflows single-precision sums.
constexpr float kGgxMinAlpha = 1e-3f;

/// alpha = roughness^2, clamped to [kGgxMinAlpha, 1].
float ggxAlpha(float roughness);
/// Normal distribution D(h), 1/sr, for cos_h = h.z; integrates to 1 as int D(h) cos_h dw_h.
float ggxD(float cos_h, float alpha);
/// Smith's Lambda for a direction at cos_theta from the normal.
float ggxLambda(float cos_theta, float alpha);
/// Smith masking of one direction: 1 / (1 + Lambda).
float ggxG1(float cos_theta, float alpha);
/// Height-correlated masking-shadowing: 1 / (1 + Lambda(o) + Lambda(i)).
float ggxG2(float cos_o, float cos_i, float alpha);
/// Schlick's approximation F0 + (1 - F0)(1 - cos_d)^5, cos_d = the angle to the microfacet normal.
float schlickFresnel(float cos_d, float f0);

/// Specular BRDF D G2 F / (4 cos_o cos_i), 1/sr; 0 when wo or wi is below the surface.
float ggxSpecular(const Eigen::Vector3f& wo, const Eigen::Vector3f& wi, float alpha, float f0 = kDielectricF0);

/// A microfacet normal drawn from the normals visible from wo (wo.z > 0), u1, u2 in [0, 1).
Eigen::Vector3f ggxSampleVisibleNormal(const Eigen::Vector3f& wo, float alpha, float u1, float u2);
/// Solid-angle density of wi = reflect(wo, h) with h from ggxSampleVisibleNormal:
/// G1(wo) D(h) / (4 cos_o). Directions below the surface still have a density (the sampler
/// produces them; their BRDF is 0).
float ggxReflectionPdf(const Eigen::Vector3f& wo, const Eigen::Vector3f& wi, float alpha);

/// Directional albedo E(cos_o) = int ggxSpecular(wo, wi) cos_i dw_i with F0 = kDielectricF0,
/// bilinear in a table over (cos_o, sqrt(alpha)), 64 x 32 nodes, built once (80 ms on 2 busy cores) by
/// stratified quadrature
/// (about 1e-3 absolute accuracy).
float ggxDirectionalAlbedo(float cos_o, float alpha);
/// Cosine-weighted average 2 int_0^1 E(mu) mu dmu of the directional albedo.
float ggxAverageAlbedo(float alpha);

/// The lobe seen from one direction wo (local frame, unit) at one alpha: what every evaluation
/// from wo shares (Smith's term of wo, the albedo table's row for alpha), computed once. Each
/// method returns bit for bit what the free function of the same name returns.
class GgxLobe {
 public:
  GgxLobe() = default;
  GgxLobe(const Eigen::Vector3f& wo, float alpha);
  float specular(const Eigen::Vector3f& wi) const;       ///< ggxSpecular(wo, wi, alpha)
  float reflectionPdf(const Eigen::Vector3f& wi) const;  ///< ggxReflectionPdf(wo, wi, alpha)
  /// specular(wi), and reflectionPdf(wi) in *pdf, sharing their half vector and D.
  float specularAndPdf(const Eigen::Vector3f& wi, float* pdf) const;
  float directionalAlbedo(float cos_theta) const;        ///< ggxDirectionalAlbedo(cos_theta, alpha)
  float averageAlbedo() const { return average_albedo_; }  ///< ggxAverageAlbedo(alpha)

 private:
  Eigen::Vector3f wo_ = Eigen::Vector3f::UnitZ();
  float alpha_ = 1.f, alpha2_ = 1.f;
  float s_o_ = 1.f;            // sqrt(cos_o^2 (1 - alpha^2) + alpha^2), Smith's term of wo
  int alpha_node_ = 0;         // the table's lower alpha node
  float alpha_fraction_ = 0.f;  // and the weight of the upper one
  float average_albedo_ = 0.f;
};

}  // namespace solo
