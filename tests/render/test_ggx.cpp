// The GGX specular lobe and the diffuse + specular surface against closed forms and
// quadrature: the NDF's projected integral, the sampler's density against its draws, the
// directional albedo's table, energy conservation and reciprocity of the coupled material.

#include <solo/render/ggx.h>
#include <solo/render/surface_bsdf.h>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace {

constexpr double kPi = 3.14159265358979323846;

Eigen::Vector3f direction(double cos_theta, double phi) {
  const double s = std::sqrt(std::max(0.0, 1 - cos_theta * cos_theta));
  return Eigen::Vector3d(s * std::cos(phi), s * std::sin(phi), cos_theta).cast<float>();
}

// int_hemisphere g(w) dw on a (theta, phi) midpoint grid, theta dense near the normal
// (where small-alpha lobes live) through theta = (pi/2) t^2.
template <class F>
double hemisphereIntegral(F g, int n_theta, int n_phi, bool full_sphere = false) {
  double sum = 0;
  const double theta_max = full_sphere ? kPi : kPi / 2;
  for (int i = 0; i < n_theta; ++i) {
    const double t = (i + 0.5) / n_theta;
    const double theta = theta_max * t * t, dtheta = theta_max * 2 * t / n_theta;
    for (int j = 0; j < n_phi; ++j) {
      const double phi = 2 * kPi * (j + 0.5) / n_phi;
      sum += g(direction(std::cos(theta), phi)) * std::sin(theta) * dtheta * (2 * kPi / n_phi);
    }
  }
  return sum;
}

}  // namespace

TEST(Ggx, NormalDistributionIntegratesToOneOverProjectedSolidAngle) {
  for (float alpha : {0.01f, 0.05f, 0.2f, 0.5f, 1.0f}) {
    // int D(h) cos_h dw_h = 2 pi int_0^{pi/2} D(cos t) cos t sin t dt, the peak resolved by
    // the substitution t = (pi/2) s^2.
    const int n = 400000;
    double sum = 0;
    for (int i = 0; i < n; ++i) {
      const double s = (i + 0.5) / n, theta = kPi / 2 * s * s, dtheta = kPi * s / n;
      sum += solo::ggxD(static_cast<float>(std::cos(theta)), alpha) * std::cos(theta) * std::sin(theta) * dtheta;
    }
    EXPECT_NEAR(2 * kPi * sum, 1.0, 1e-3) << "alpha " << alpha;
  }
  EXPECT_NEAR(solo::ggxAlpha(0.5f), 0.25f, 1e-7f);
  EXPECT_EQ(solo::ggxAlpha(0.f), solo::kGgxMinAlpha);
  EXPECT_NEAR(solo::schlickFresnel(1.f, solo::kDielectricF0), 0.04f, 1e-7f);
  EXPECT_NEAR(solo::schlickFresnel(0.f, solo::kDielectricF0), 1.f, 1e-6f);
}

TEST(Ggx, VisibleNormalSamplerDrawsItsDensity) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(0.f, 1.f);
  for (float alpha : {0.1f, 0.4f, 0.8f})
    for (float cos_o : {0.2f, 0.6f, 0.95f}) {
      SCOPED_TRACE(testing::Message() << "alpha " << alpha << " cos_o " << cos_o);
      const Eigen::Vector3f wo = direction(cos_o, 0.3);
      // The density integrates to 1 over the whole sphere of reflected directions.
      const double total = hemisphereIntegral(
          [&](const Eigen::Vector3f& w) { return solo::ggxReflectionPdf(wo, w, alpha); }, 1500, 600, true);
      EXPECT_NEAR(total, 1.0, 5e-3);
      // Histogram of draws in 8 bands of cos_i against the density integrated over each band.
      const int draws = 200000, bands = 8;
      std::vector<double> counts(bands, 0), expected(bands, 0);
      double estimate = 0;
      for (int k = 0; k < draws; ++k) {
        const Eigen::Vector3f h = solo::ggxSampleVisibleNormal(wo, alpha, u(rng), u(rng));
        const Eigen::Vector3f wi = 2.f * wo.dot(h) * h - wo;
        if (wi.z() <= 0.f) continue;
        counts[std::min(bands - 1, static_cast<int>(wi.z() * bands))] += 1.0 / draws;
        estimate += solo::ggxSpecular(wo, wi, alpha) * wi.z() / solo::ggxReflectionPdf(wo, wi, alpha) / draws;
      }
      for (int b = 0; b < bands; ++b) {
        expected[static_cast<std::size_t>(b)] = hemisphereIntegral(
            [&](const Eigen::Vector3f& w) {
              return std::min(bands - 1, static_cast<int>(w.z() * bands)) == b ? solo::ggxReflectionPdf(wo, w, alpha)
                                                                               : 0.f;
            },
            1500, 600);
        const double p = expected[static_cast<std::size_t>(b)];
        EXPECT_NEAR(counts[static_cast<std::size_t>(b)], p, 4 * std::sqrt(p * (1 - p) / draws) + 2e-3) << "band " << b;
      }
      // The importance-sampled albedo equals the quadrature of f cos, and the table.
      const double albedo = hemisphereIntegral(
          [&](const Eigen::Vector3f& w) { return solo::ggxSpecular(wo, w, alpha) * w.z(); }, 1500, 600);
      EXPECT_NEAR(estimate, albedo, 0.01 * albedo + 2e-4);
      EXPECT_NEAR(solo::ggxDirectionalAlbedo(cos_o, alpha), albedo, 0.03 * albedo + 1e-3);
    }
}

TEST(Ggx, CoupledMaterialConservesEnergyAndIsReciprocal) {
  std::mt19937 rng(9);
  std::uniform_real_distribution<float> u(0.f, 1.f);
  const Eigen::Vector3f n(0, 0, 1);
  for (float roughness : {0.05f, 0.3f, 0.7f, 1.0f})
    for (float cos_o : {0.05f, 0.3f, 0.7f, 1.0f}) {
      SCOPED_TRACE(testing::Message() << "roughness " << roughness << " cos_o " << cos_o);
      const Eigen::Vector3f wo = direction(cos_o, 1.1);
      // White Lambert + GGX: E_spec + (1 - E_spec) = 1 up to the table's accuracy, never more.
      const solo::SurfaceBsdf white(n, wo, Eigen::Vector3f::Ones(), roughness, solo::DiffuseModel::Lambert, true);
      const solo::SurfaceBsdf grey(n, wo, Eigen::Vector3f::Constant(0.5f), roughness, solo::DiffuseModel::Lambert,
                                   true);
      const int draws = 100000;
      double white_albedo = 0, grey_albedo = 0;
      for (int k = 0; k < draws; ++k) {
        const float u0 = u(rng), u1 = u(rng), u2 = u(rng);
        Eigen::Vector3f wi;
        if (white.sample(u0, u1, u2, &wi)) white_albedo += white.eval(wi).y() * wi.z() / white.pdf(wi) / draws;
        if (grey.sample(u0, u1, u2, &wi)) grey_albedo += grey.eval(wi).y() * wi.z() / grey.pdf(wi) / draws;
      }
      EXPECT_LE(white_albedo, 1.005);
      EXPECT_GE(white_albedo, 0.98);
      const double e = solo::ggxDirectionalAlbedo(cos_o, solo::ggxAlpha(roughness));
      EXPECT_NEAR(grey_albedo, e + 0.5 * (1 - e), 0.01);
      // Reciprocity and the density's consistency at a few direction pairs.
      const Eigen::Vector3f wi = direction(0.4, 2.5);
      const solo::SurfaceBsdf swapped(n, wi, Eigen::Vector3f::Constant(0.5f), roughness, solo::DiffuseModel::Lambert,
                                      true);
      EXPECT_NEAR(grey.eval(wi).y(), swapped.eval(wo).y(), 2e-4 * std::max(1.f, grey.eval(wi).y()));
      EXPECT_GT(grey.pdf(wi), 0.f);
    }
  // Without the specular lobe the material is the diffuse lobe and its density the cosine's.
  const Eigen::Vector3f wo = direction(0.6, 0.0), wi = direction(0.8, 2.0);
  const solo::SurfaceBsdf plain(n, wo, Eigen::Vector3f::Constant(0.5f), 0.3f, solo::DiffuseModel::Lambert, false);
  EXPECT_NEAR(plain.eval(wi).y(), 0.5 / kPi, 1e-7);
  EXPECT_NEAR(plain.pdf(wi), 0.8 / kPi, 1e-6);
}

// Burley's diffuse lobe (Burley 2012, eq. 3) as printed: the half vector normalised in double,
// f = albedo / pi (1 + (F_D90 - 1)(1 - cos_i)^5)(1 + (F_D90 - 1)(1 - cos_o)^5),
// F_D90 = 1/2 + 2 roughness cos_d^2, against the renderer's form without the half vector; at
// grazing, normal and retro-reflecting pairs, where the two forms are furthest apart.
TEST(SurfaceBsdf, DisneyDiffuseMatchesBurleysHalfVectorForm) {
  const Eigen::Vector3f n = Eigen::Vector3f::UnitZ();
  const double albedo = 0.7;
  for (const double roughness : {0.0, 0.5, 1.0})
    for (const double cos_o : {1.0, 0.6, 0.05, 1e-3})
      for (const double cos_i : {1.0, 0.8, 0.2, 1e-3})
        for (const double phi : {0.0, 1.0, 3.14159265358979}) {
          const Eigen::Vector3f wo = direction(cos_o, 0.0), wi = direction(cos_i, phi);
          const Eigen::Vector3d h = (wi.cast<double>() + wo.cast<double>()).normalized();
          const double cos_d = wi.cast<double>().dot(h);
          const double fd90 = 0.5 + 2 * roughness * cos_d * cos_d;
          const auto schlick = [fd90](double c) { return 1 + (fd90 - 1) * std::pow(1 - c, 5); };
          const double expected = albedo / kPi * schlick(wi.z()) * schlick(wo.z());
          const solo::SurfaceBsdf bsdf(n, wo, Eigen::Vector3f::Constant(static_cast<float>(albedo)),
                                       static_cast<float>(roughness), solo::DiffuseModel::Disney, false);
          EXPECT_NEAR(bsdf.eval(wi).y(), expected, 2e-6 * expected)
              << "roughness " << roughness << " cos_o " << cos_o << " cos_i " << cos_i << " phi " << phi;
        }
}

// GgxLobe keeps what evaluations from one wo share; it must change no bit of any of them.
TEST(Ggx, LobeFromOneDirectionEqualsTheFreeFunctionsBitForBit) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0, 1);
  for (const float roughness : {0.f, 0.05f, 0.3f, 0.5f, 0.77f, 1.f}) {
    const float alpha = solo::ggxAlpha(roughness);
    for (const double cos_o : {1.0, 0.7, 0.2, 0.01, -0.3}) {
      const Eigen::Vector3f wo = direction(cos_o, 0.4);
      const solo::GgxLobe lobe(wo, alpha);
      EXPECT_EQ(lobe.averageAlbedo(), solo::ggxAverageAlbedo(alpha));
      for (int k = 0; k < 200; ++k) {
        const Eigen::Vector3f wi = direction(2 * u(rng) - 1, 2 * kPi * u(rng));
        EXPECT_EQ(lobe.specular(wi), solo::ggxSpecular(wo, wi, alpha)) << roughness << " " << cos_o;
        EXPECT_EQ(lobe.reflectionPdf(wi), solo::ggxReflectionPdf(wo, wi, alpha)) << roughness << " " << cos_o;
        EXPECT_EQ(lobe.directionalAlbedo(wi.z()), solo::ggxDirectionalAlbedo(wi.z(), alpha));
        float pdf = -1.f;
        EXPECT_EQ(lobe.specularAndPdf(wi, &pdf), lobe.specular(wi));
        EXPECT_EQ(pdf, lobe.reflectionPdf(wi));
      }
    }
  }
}

// ggxSpecular and ggxReflectionPdf evaluate the height-correlated Smith term as one quotient
// and the half vector without normalising it; in double precision from the textbook factors
// (D, G2 = 1 / (1 + Lambda_o + Lambda_i), Schlick's F, G1 = 1 / (1 + Lambda_o)) they must agree
// to float rounding, from normal incidence to grazing and from a mirror-like to a fully rough lobe.
// Near the lobe's peak D's denominator d = cos_h^2 (alpha^2 - 1) + 1 cancels, so the rounding of
// cos_h^2 (a few 1e-8) is amplified by 1 / d there: the tolerance allows for that and no more.
TEST(Ggx, SpecularAndDensityEqualTheTextbookProducts) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0, 1);
  const auto lambda = [](double c, double a) { return 0.5 * (std::sqrt(1 + a * a * (1 - c * c) / (c * c)) - 1); };
  for (const float roughness : {0.f, 0.05f, 0.3f, 0.5f, 0.77f, 1.f}) {
    const double a = solo::ggxAlpha(roughness);
    for (const double cos_o : {1.0, 0.7, 0.2, 0.01}) {
      const Eigen::Vector3f wo = direction(cos_o, 0.4);
      for (int k = 0; k < 300; ++k) {
        const Eigen::Vector3f wi = direction(std::max(1e-3, u(rng)), 2 * kPi * u(rng));
        const Eigen::Vector3d o = wo.cast<double>(), i = wi.cast<double>(), h = (o + i).normalized();
        const double peak = h.z() * h.z() * (a * a - 1) + 1;
        const double d = a * a / (kPi * peak * peak);
        const double tolerance = 2e-5 + 4e-7 / peak;  // relative
        const double f = 0.04 + 0.96 * std::pow(1 - o.dot(h), 5);
        const double g2 = 1 / (1 + lambda(o.z(), a) + lambda(i.z(), a));
        const double specular = d * g2 * f / (4 * o.z() * i.z());
        const double pdf = d / (1 + lambda(o.z(), a)) / (4 * o.z());
        EXPECT_NEAR(solo::ggxSpecular(wo, wi, static_cast<float>(a)), specular, tolerance * specular + 1e-30)
            << roughness << " " << cos_o << " " << wi.z();
        EXPECT_NEAR(solo::ggxReflectionPdf(wo, wi, static_cast<float>(a)), pdf, tolerance * pdf + 1e-30)
            << roughness << " " << cos_o << " " << wi.z();
      }
    }
  }
}

// The tracer asks for the BRDF and its density together; evalAndPdf must return exactly what
// eval and pdf return, for either diffuse model, with and without the specular lobe, below
// the surface as above it.
TEST(SurfaceBsdf, EvalAndPdfTogetherEqualEvalAndPdfBitForBit) {
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> u(0, 1);
  const Eigen::Vector3f n = Eigen::Vector3f(0.2f, -0.3f, 0.9f).normalized();
  int above = 0;
  for (const auto model : {solo::DiffuseModel::Disney, solo::DiffuseModel::Lambert})
    for (const bool specular : {false, true})
      for (const float roughness : {0.f, 0.3f, 1.f})
        for (int k = 0; k < 100; ++k) {
          const Eigen::Vector3f wo = (n + direction(2 * u(rng) - 1, 2 * kPi * u(rng))).normalized();
          if (n.dot(wo) <= 0.f) continue;
          const solo::SurfaceBsdf bsdf(n, wo, Eigen::Vector3f(0.2f, 0.5f, 0.7f), roughness, model, specular);
          const Eigen::Vector3f wi = direction(2 * u(rng) - 1, 2 * kPi * u(rng));
          above += n.dot(wi) > 0.f;
          float pdf = -1.f;
          const Eigen::Vector3f f = bsdf.evalAndPdf(wi, &pdf);
          EXPECT_EQ(f, bsdf.eval(wi)) << specular << " " << roughness;
          EXPECT_EQ(pdf, bsdf.pdf(wi)) << specular << " " << roughness;
        }
  EXPECT_GT(above, 300);  // both sides of the surface were tried
}

TEST(SurfaceBsdf, OrthonormalBasisIsRightHandedAroundAnyUnitNormal) {
  const std::vector<Eigen::Vector3f> normals = {
      Eigen::Vector3f::UnitZ(), -Eigen::Vector3f::UnitZ(), Eigen::Vector3f::UnitX(),
      Eigen::Vector3f(0.3f, -0.4f, 0.866f).normalized(), Eigen::Vector3f(1e-4f, 2e-4f, -1.f).normalized(),
      Eigen::Vector3f(-0.7f, 0.7f, -0.1f).normalized()};
  for (const Eigen::Vector3f& n : normals) {
    Eigen::Vector3f t, b;
    solo::orthonormalBasis(n, t, b);
    EXPECT_NEAR(t.norm(), 1.f, 1e-5f) << n.transpose();
    EXPECT_NEAR(b.norm(), 1.f, 1e-5f) << n.transpose();
    EXPECT_NEAR(t.dot(b), 0.f, 1e-5f) << n.transpose();
    EXPECT_NEAR(t.dot(n), 0.f, 1e-5f) << n.transpose();
    EXPECT_NEAR(b.dot(n), 0.f, 1e-5f) << n.transpose();
    EXPECT_LT((t.cross(b) - n).norm(), 1e-5f) << "right-handed: t x b = n for " << n.transpose();
  }
}
