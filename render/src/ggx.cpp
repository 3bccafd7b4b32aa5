#include "solo/render/ggx.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>
#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>

namespace solo {
namespace {

constexpr float kPi = 3.14159265358979f;
// Nodes uniform in sqrt(alpha) (= roughness) and in cos_o: at grazing angles and small alpha
// the albedo changes fast with both, and a table uniform in alpha misses it by 1 %.
constexpr int kAlphaNodes = 32, kCosNodes = 64;

struct AlbedoTables {
  std::array<float, kAlphaNodes * kCosNodes> directional{};  // [alpha node][cos node]
  std::array<float, kAlphaNodes> average{};                  // per alpha node
};

float alphaCoordinate(float alpha) { return std::sqrt(std::clamp(alpha, 0.f, 1.f)) * (kAlphaNodes - 1); }

// The table row of alpha: its lower node and the upper node's weight.
void alphaRow(float alpha, int* a0, float* ta) {
  const float fa = alphaCoordinate(alpha);
  *a0 = std::min(static_cast<int>(fa), kAlphaNodes - 2);
  *ta = fa - static_cast<float>(*a0);
}

float lookupDirectionalInRow(const AlbedoTables& t, float cos_o, int a0, float ta) {
  const float fc = std::clamp(cos_o, 0.f, 1.f) * (kCosNodes - 1);
  const int c0 = std::min(static_cast<int>(fc), kCosNodes - 2);
  const float tc = fc - static_cast<float>(c0);
  const auto at = [&t](int a, int c) { return t.directional[static_cast<std::size_t>(a * kCosNodes + c)]; };
  return (1 - ta) * ((1 - tc) * at(a0, c0) + tc * at(a0, c0 + 1)) +
         ta * ((1 - tc) * at(a0 + 1, c0) + tc * at(a0 + 1, c0 + 1));
}

float lookupDirectional(const AlbedoTables& t, float cos_o, float alpha) {
  int a0 = 0;
  float ta = 0;
  alphaRow(alpha, &a0, &ta);
  return lookupDirectionalInRow(t, cos_o, a0, ta);
}

// E(cos_o) by stratified visible-normal sampling: f cos_i / pdf = F G2 / G1(wo) per sample,
// so the quadrature converges fast and has no peak to miss at small alpha.
float integrateDirectional(float cos_o, float alpha) {
  const float c = std::max(cos_o, 5e-3f);
  const Eigen::Vector3f wo(std::sqrt(1.f - c * c), 0.f, c);
  constexpr int n = 24;
  double sum = 0;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const Eigen::Vector3f h = ggxSampleVisibleNormal(wo, alpha, (i + 0.5f) / n, (j + 0.5f) / n);
      const float o_dot_h = wo.dot(h);
      const Eigen::Vector3f wi = 2.f * o_dot_h * h - wo;
      if (wi.z() <= 0.f) continue;
      sum += schlickFresnel(o_dot_h, kDielectricF0) * ggxG2(wo.z(), wi.z(), alpha) / ggxG1(wo.z(), alpha);
    }
  return static_cast<float>(sum / (n * n));
}

const AlbedoTables& tables() {
  static const AlbedoTables t = [] {
    AlbedoTables table;
    // Isolated: the first lookup may come from inside the renderer's parallel loop, and a
    // thread waiting here must not pick up another tile that waits on this same table.
    tbb::this_task_arena::isolate([&table] {
      tbb::parallel_for(0, kAlphaNodes, [&table](int a) {
        const float root = static_cast<float>(a) / (kAlphaNodes - 1);
        const float alpha = std::max(kGgxMinAlpha, root * root);
        for (int c = 0; c < kCosNodes; ++c)
          table.directional[static_cast<std::size_t>(a * kCosNodes + c)] =
              integrateDirectional(static_cast<float>(c) / (kCosNodes - 1), alpha);
      });
    });
    // The average is taken over the interpolated table itself, so that the diffuse coupling
    // that divides by 1 - average (surface_bsdf.cpp) integrates exactly.
    for (int a = 0; a < kAlphaNodes; ++a) {
      const float root = static_cast<float>(a) / (kAlphaNodes - 1);
      const float alpha = root * root;
      constexpr int n = 1024;
      double sum = 0;
      for (int i = 0; i < n; ++i) {
        const float mu = (i + 0.5f) / n;
        sum += lookupDirectional(table, mu, alpha) * mu;
      }
      table.average[static_cast<std::size_t>(a)] = static_cast<float>(2.0 * sum / n);
    }
    return table;
  }();
  return t;
}

// What the specular lobe needs of the half vector h of unit wo and wi, without normalising it:
// with s = wo + wi, cos_h^2 = s_z^2 / |s|^2 and wo.h = (1 + wo.wi) / |s| = |s| / 2. False when
// wo and wi are opposite (no half vector) or h is below the surface (D = 0 there).
struct HalfVector {
  float cos_h2 = 0.f;  // h_z^2
  float o_dot_h = 0.f;  // wo.h, in [0, 1]
};
bool halfVector(const Eigen::Vector3f& wo, const Eigen::Vector3f& wi, HalfVector* h) {
  const Eigen::Vector3f sum = wo + wi;
  const float length2 = sum.squaredNorm();
  if (!(length2 > 0.f) || !(sum.z() > 0.f)) return false;
  h->cos_h2 = sum.z() * sum.z() / length2;
  h->o_dot_h = std::min(1.f, 0.5f * std::sqrt(length2));
  return true;
}

// D(h) from cos_h^2: alpha^2 / (pi (cos_h^2 (alpha^2 - 1) + 1)^2), as ggxD.
float distribution(float cos_h2, float alpha2) {
  const float d = cos_h2 * (alpha2 - 1.f) + 1.f;
  return alpha2 / (kPi * d * d);
}

// sqrt(cos^2 (1 - alpha^2) + alpha^2) = cos (2 Lambda(cos) + 1): Smith's Lambda in the form
// that lets the height-correlated G2 / (4 cos_o cos_i) become one quotient,
// 1 / (2 (cos_i S_o + cos_o S_i)) (Heitz 2014, "Understanding the masking-shadowing function").
float smithS(float cos_theta, float alpha2) { return std::sqrt(cos_theta * cos_theta * (1.f - alpha2) + alpha2); }

// D G2 F / (4 cos_o cos_i) for cos_o, cos_i > 0.
float specularValue(const HalfVector& h, float cos_o, float s_o, float cos_i, float alpha2, float f0) {
  return distribution(h.cos_h2, alpha2) * schlickFresnel(h.o_dot_h, f0) /
         (2.f * (cos_i * s_o + cos_o * smithS(cos_i, alpha2)));
}

// G1(wo) D(h) / (4 cos_o) = D(h) / (2 (cos_o + S_o)).
float reflectionDensity(const HalfVector& h, float cos_o, float s_o, float alpha2) {
  return distribution(h.cos_h2, alpha2) / (2.f * (cos_o + s_o));
}

}  // namespace

float ggxAlpha(float roughness) { return std::clamp(roughness * roughness, kGgxMinAlpha, 1.f); }

float ggxD(float cos_h, float alpha) {
  if (cos_h <= 0.f) return 0.f;
  const float a2 = alpha * alpha;
  const float d = cos_h * cos_h * (a2 - 1.f) + 1.f;
  return a2 / (kPi * d * d);
}

float ggxLambda(float cos_theta, float alpha) {
  const float c2 = std::max(cos_theta * cos_theta, 1e-12f);
  const float tan2 = std::max(0.f, 1.f - c2) / c2;
  return 0.5f * (std::sqrt(1.f + alpha * alpha * tan2) - 1.f);
}

float ggxG1(float cos_theta, float alpha) { return 1.f / (1.f + ggxLambda(cos_theta, alpha)); }

float ggxG2(float cos_o, float cos_i, float alpha) {
  return 1.f / (1.f + ggxLambda(cos_o, alpha) + ggxLambda(cos_i, alpha));
}

float schlickFresnel(float cos_d, float f0) {
  const float m = 1.f - std::clamp(cos_d, 0.f, 1.f);
  const float m2 = m * m;
  return f0 + (1.f - f0) * m2 * m2 * m;
}

float ggxSpecular(const Eigen::Vector3f& wo, const Eigen::Vector3f& wi, float alpha, float f0) {
  if (wo.z() <= 0.f || wi.z() <= 0.f) return 0.f;
  HalfVector h;
  if (!halfVector(wo, wi, &h)) return 0.f;
  const float alpha2 = alpha * alpha;
  return specularValue(h, wo.z(), smithS(wo.z(), alpha2), wi.z(), alpha2, f0);
}

Eigen::Vector3f ggxSampleVisibleNormal(const Eigen::Vector3f& wo, float alpha, float u1, float u2) {
  // Stretch to the hemisphere configuration, sample the projected disc of visible
  // hemisphere points, unstretch (Heitz 2018, listing 1).
  const Eigen::Vector3f vh = Eigen::Vector3f(alpha * wo.x(), alpha * wo.y(), wo.z()).normalized();
  const float length2 = vh.x() * vh.x() + vh.y() * vh.y();
  const Eigen::Vector3f t1 = length2 > 0.f ? Eigen::Vector3f(Eigen::Vector3f(-vh.y(), vh.x(), 0.f) / std::sqrt(length2))
                                           : Eigen::Vector3f(Eigen::Vector3f::UnitX());
  const Eigen::Vector3f t2 = vh.cross(t1);
  const float r = std::sqrt(u1), phi = 2.f * kPi * u2;
  const float p1 = r * std::cos(phi);
  const float s = 0.5f * (1.f + vh.z());
  const float p2 = (1.f - s) * std::sqrt(std::max(0.f, 1.f - p1 * p1)) + s * r * std::sin(phi);
  const Eigen::Vector3f nh = p1 * t1 + p2 * t2 + std::sqrt(std::max(0.f, 1.f - p1 * p1 - p2 * p2)) * vh;
  return Eigen::Vector3f(alpha * nh.x(), alpha * nh.y(), std::max(1e-7f, nh.z())).normalized();
}

float ggxReflectionPdf(const Eigen::Vector3f& wo, const Eigen::Vector3f& wi, float alpha) {
  if (wo.z() <= 0.f) return 0.f;
  HalfVector h;
  if (!halfVector(wo, wi, &h)) return 0.f;
  const float alpha2 = alpha * alpha;
  return reflectionDensity(h, wo.z(), smithS(wo.z(), alpha2), alpha2);
}

float ggxDirectionalAlbedo(float cos_o, float alpha) { return lookupDirectional(tables(), cos_o, alpha); }

float ggxAverageAlbedo(float alpha) {
  const AlbedoTables& t = tables();
  int a0 = 0;
  float ta = 0;
  alphaRow(alpha, &a0, &ta);
  return (1 - ta) * t.average[static_cast<std::size_t>(a0)] + ta * t.average[static_cast<std::size_t>(a0 + 1)];
}

GgxLobe::GgxLobe(const Eigen::Vector3f& wo, float alpha)
    : wo_(wo), alpha_(alpha), alpha2_(alpha * alpha), s_o_(smithS(wo.z(), alpha2_)) {
  alphaRow(alpha, &alpha_node_, &alpha_fraction_);
  const AlbedoTables& t = tables();  // as ggxAverageAlbedo, on the row found above
  average_albedo_ = (1 - alpha_fraction_) * t.average[static_cast<std::size_t>(alpha_node_)] +
                    alpha_fraction_ * t.average[static_cast<std::size_t>(alpha_node_ + 1)];
}

float GgxLobe::specular(const Eigen::Vector3f& wi) const {
  if (wo_.z() <= 0.f || wi.z() <= 0.f) return 0.f;
  HalfVector h;
  if (!halfVector(wo_, wi, &h)) return 0.f;
  return specularValue(h, wo_.z(), s_o_, wi.z(), alpha2_, kDielectricF0);
}

float GgxLobe::reflectionPdf(const Eigen::Vector3f& wi) const {
  if (wo_.z() <= 0.f) return 0.f;
  HalfVector h;
  if (!halfVector(wo_, wi, &h)) return 0.f;
  return reflectionDensity(h, wo_.z(), s_o_, alpha2_);
}

float GgxLobe::specularAndPdf(const Eigen::Vector3f& wi, float* pdf) const {
  *pdf = 0.f;
  if (wo_.z() <= 0.f) return 0.f;
  HalfVector h;
  if (!halfVector(wo_, wi, &h)) return 0.f;
  *pdf = reflectionDensity(h, wo_.z(), s_o_, alpha2_);
  if (wi.z() <= 0.f) return 0.f;
  return specularValue(h, wo_.z(), s_o_, wi.z(), alpha2_, kDielectricF0);
}

float GgxLobe::directionalAlbedo(float cos_theta) const {
  return lookupDirectionalInRow(tables(), cos_theta, alpha_node_, alpha_fraction_);
}

}  // namespace solo
