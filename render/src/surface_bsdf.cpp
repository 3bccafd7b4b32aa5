#include "solo/render/surface_bsdf.h"

#include "solo/render/ggx.h"

#include <algorithm>
#include <cmath>

namespace solo {
namespace {

constexpr float kPi = 3.14159265358979f;

}  // namespace

void orthonormalBasis(const Eigen::Vector3f& n, Eigen::Vector3f& t, Eigen::Vector3f& b) {
  const float sign = std::copysign(1.f, n.z());
  const float a = -1.f / (sign + n.z());
  const float c = n.x() * n.y() * a;
  t = {1.f + sign * n.x() * n.x() * a, sign * c, -sign * n.x()};
  b = {c, sign + n.y() * n.y() * a, -n.y()};
}

SurfaceBsdf::SurfaceBsdf(const Eigen::Vector3f& n, const Eigen::Vector3f& wo, const Eigen::Vector3f& albedo,
                         float roughness, DiffuseModel diffuse, bool specular)
    : n_(n), wo_(wo), albedo_(albedo), roughness_(roughness), diffuse_(diffuse), specular_(specular) {
  orthonormalBasis(n_, t_, b_);
  wo_local_ = toLocal(wo_);
  cos_o_ = std::max(0.f, wo_local_.z());
  const float m = 1.f - cos_o_;
  one_minus_cos_o_pow5_ = m * m * m * m * m;
  if (specular_) {
    alpha_ = ggxAlpha(roughness_);
    lobe_ = GgxLobe(wo_local_, alpha_);
    const float e_o = lobe_.directionalAlbedo(cos_o_);
    diffuse_coupling_o_ = (1.f - e_o) / (1.f - lobe_.averageAlbedo());
    // Lobe choice by estimated albedo: the diffuse lobe reflects about albedo (1 - E(cos_o)).
    const float diffuse_weight = std::max(0.f, albedo_.y()) * (1.f - e_o);
    specular_probability_ = std::clamp(e_o / std::max(1e-6f, e_o + diffuse_weight), 0.1f, 0.9f);
  }
}

Eigen::Vector3f SurfaceBsdf::diffuseShape(const Eigen::Vector3f& wi, float cos_i) const {
  if (diffuse_ == DiffuseModel::Lambert) return Eigen::Vector3f::Constant(1.f / kPi);
  // cos_d, the cosine between wi and the half vector, enters squared: for unit wi and wo,
  // cos_d^2 = (1 + wi.wo) / 2, with no half vector to normalise.
  const float cos_d2 = std::clamp(0.5f * (1.f + wi.dot(wo_)), 0.f, 1.f);
  const float fd90_minus_1 = 2.f * roughness_ * cos_d2 - 0.5f;
  const float m = 1.f - cos_i;
  const float schlick_i = 1.f + fd90_minus_1 * (m * m * m * m * m);
  return Eigen::Vector3f::Constant(schlick_i * (1.f + fd90_minus_1 * one_minus_cos_o_pow5_) / kPi);
}

Eigen::Vector3f SurfaceBsdf::eval(const Eigen::Vector3f& wi) const {
  const float cos_i = n_.dot(wi);
  if (cos_i <= 0.f || cos_o_ <= 0.f) return Eigen::Vector3f::Zero();
  Eigen::Vector3f f = albedo_.cwiseProduct(diffuseShape(wi, cos_i));
  if (!specular_) return f;
  const Eigen::Vector3f wi_local = toLocal(wi);
  f *= diffuse_coupling_o_ * (1.f - lobe_.directionalAlbedo(cos_i));
  return f + Eigen::Vector3f::Constant(lobe_.specular(wi_local));
}

float SurfaceBsdf::pdf(const Eigen::Vector3f& wi) const {
  const float cos_i = n_.dot(wi);
  const float diffuse_pdf = std::max(0.f, cos_i) / kPi;
  if (!specular_) return diffuse_pdf;
  return (1.f - specular_probability_) * diffuse_pdf +
         specular_probability_ * lobe_.reflectionPdf(toLocal(wi));
}

Eigen::Vector3f SurfaceBsdf::evalAndPdf(const Eigen::Vector3f& wi, float* pdf) const {
  const float cos_i = n_.dot(wi);
  const float diffuse_pdf = std::max(0.f, cos_i) / kPi;
  if (!specular_) {
    *pdf = diffuse_pdf;
    if (cos_i <= 0.f || cos_o_ <= 0.f) return Eigen::Vector3f::Zero();
    return albedo_.cwiseProduct(diffuseShape(wi, cos_i));
  }
  const Eigen::Vector3f wi_local = toLocal(wi);
  float specular_pdf = 0.f;
  const float specular = lobe_.specularAndPdf(wi_local, &specular_pdf);
  *pdf = (1.f - specular_probability_) * diffuse_pdf + specular_probability_ * specular_pdf;
  if (cos_i <= 0.f || cos_o_ <= 0.f) return Eigen::Vector3f::Zero();
  Eigen::Vector3f f = albedo_.cwiseProduct(diffuseShape(wi, cos_i));
  f *= diffuse_coupling_o_ * (1.f - lobe_.directionalAlbedo(cos_i));
  return f + Eigen::Vector3f::Constant(specular);
}

bool SurfaceBsdf::sample(float u0, float u1, float u2, Eigen::Vector3f* wi) const {
  if (specular_ && u0 < specular_probability_) {
    const Eigen::Vector3f h = ggxSampleVisibleNormal(wo_local_, alpha_, u1, u2);
    const Eigen::Vector3f local = 2.f * wo_local_.dot(h) * h - wo_local_;
    if (local.z() <= 0.f) return false;
    *wi = (t_ * local.x() + b_ * local.y() + n_ * local.z()).normalized();
    return n_.dot(*wi) > 0.f;
  }
  // Cosine-weighted hemisphere.
  const float r = std::sqrt(u1), phi = 2.f * kPi * u2;
  const float z = std::sqrt(std::max(0.f, 1.f - u1));
  *wi = (t_ * (r * std::cos(phi)) + b_ * (r * std::sin(phi)) + n_ * z).normalized();
  return n_.dot(*wi) > 1e-7f;
}

}  // namespace solo
