// The normal-guided objective: hand-computed values, the exact gradient, planes.

#include <solo/geometry/normal_guided_objective.h>

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace {

solo::PinholeCamera camera(int width, int height, double f = 100) {
  solo::PinholeCamera c;
  c.fx = c.fy = f, c.cx = (width - 1) / 2.0, c.cy = (height - 1) / 2.0, c.width = width, c.height = height;
  return c;
}

TEST(NormalGuidedObjective, HandComputedThreePixelRow) {
  // z = (2, 3, 5), n = (0, 0, -1) everywhere, principal point at the middle pixel, f = 10.
  // Paper model: r_u = n_x + n_z f D / z. D: forward (1), central (1.5), backward (2).
  const cv::Mat depth = (cv::Mat_<float>(1, 3) << 2, 3, 5);
  const cv::Mat normals(1, 3, CV_32FC3, cv::Scalar(0, 0, -1));
  solo::NormalGuidedObjectiveOptions o = solo::NormalGuidedObjectiveOptions::paper();
  o.tangent_model = solo::TangentModel::PaperGraph;
  const solo::NormalGuidedObjective objective(depth, normals, {}, camera(3, 1, 10), o);
  ASSERT_EQ(objective.unknowns(), 3);
  std::vector<double> z = {2, 3, 5};
  solo::ObjectiveValue v;
  ASSERT_TRUE(objective.evaluate(z.data(), v));
  const double r0 = -10 * 1.0 / 2, r1 = -10 * 1.5 / 3, r2 = -10 * 2.0 / 5;
  // Per-pixel constants are stored in float: relative 1e-7.
  EXPECT_NEAR(v.tangent, 50.0 / 3 * (r0 * r0 + r1 * r1 + r2 * r2), 1e-6 * v.tangent);
  EXPECT_EQ(v.data, 0);
  z[1] = 4;  // data term (4 - 3)^2 / 3
  ASSERT_TRUE(objective.evaluate(z.data(), v));
  EXPECT_NEAR(v.data, 1.0 / 3, 1e-12);
}

TEST(NormalGuidedObjective, HandComputedOneSidedStencilAndFootprintData) {
  // As above with the one-sided stencil: the middle pixel has the residuals of D = 1 and D = 2,
  // half weight each; the ends keep their one difference. Data term in footprints: f = 10, so
  // (4 - 3) m at d~ = 3 m is 10 / 3 footprints.
  const cv::Mat depth = (cv::Mat_<float>(1, 3) << 2, 3, 5);
  const cv::Mat normals(1, 3, CV_32FC3, cv::Scalar(0, 0, -1));
  solo::NormalGuidedObjectiveOptions o = solo::NormalGuidedObjectiveOptions::paper();
  o.tangent_model = solo::TangentModel::PaperGraph;
  o.tangent_stencil = solo::TangentStencil::OneSided;
  o.data_units = solo::DataUnits::Footprints;
  const solo::NormalGuidedObjective objective(depth, normals, {}, camera(3, 1, 10), o);
  std::vector<double> z = {2, 3, 5};
  solo::ObjectiveValue v;
  ASSERT_TRUE(objective.evaluate(z.data(), v));
  const double r0 = -10 * 1.0 / 2, r1a = -10 * 1.0 / 3, r1b = -10 * 2.0 / 3, r2 = -10 * 2.0 / 5;
  EXPECT_NEAR(v.tangent, 50.0 / 3 * (r0 * r0 + 0.5 * (r1a * r1a + r1b * r1b) + r2 * r2), 1e-6 * v.tangent);
  z[1] = 4;
  ASSERT_TRUE(objective.evaluate(z.data(), v));
  EXPECT_NEAR(v.data, 1.0 / 3 * (10.0 / 3) * (10.0 / 3), 1e-12);
}

TEST(NormalGuidedObjective, TheCentralStencilCannotSeeAnOddEvenAlternation) {
  // A fronto-parallel plane at 10 m whose odd columns are 2 % nearer: its central differences
  // are all 0 (the alternation costs the paper's tangent term nothing), the one-sided ones are not.
  cv::Mat depth(6, 8, CV_32F, cv::Scalar(10));
  for (int x = 1; x < 8; x += 2) depth.col(x).setTo(9.8);
  const cv::Mat normals(6, 8, CV_32FC3, cv::Scalar(0, 0, -1));
  solo::NormalGuidedObjectiveOptions central = solo::NormalGuidedObjectiveOptions::paper(), one_sided = central;
  central.tangent_model = one_sided.tangent_model = solo::TangentModel::PaperGraph;
  one_sided.tangent_stencil = solo::TangentStencil::OneSided;
  solo::ObjectiveValue vc, vo;
  const solo::NormalGuidedObjective a(depth, normals, {}, camera(8, 6, 50), central);
  a.evaluate(a.filteredDepths().data(), vc);
  const solo::NormalGuidedObjective b(depth, normals, {}, camera(8, 6, 50), one_sided);
  b.evaluate(b.filteredDepths().data(), vo);
  // Only the two border columns (one-sided there in both stencils) see the alternation.
  EXPECT_LT(vc.tangent, 0.3 * vo.tangent);
  EXPECT_GT(vo.tangent, 10.0) << "every pixel's one-sided slopes are 0.2 m / 10 m * 50 = 1";
}

TEST(NormalGuidedObjective, DeadZoneLossIsFlatInsideItsTolerance) {
  double d1 = -1, d2 = -1;
  EXPECT_EQ(solo::tangentLoss(solo::TangentLoss::DeadZone, 0.1, 0.0081, &d1, &d2), 0.0);
  EXPECT_EQ(d1, 0.0);
  EXPECT_NEAR(solo::tangentLoss(solo::TangentLoss::DeadZone, 0.1, 0.09, &d1, &d2), 0.04, 1e-12);  // (0.3 - 0.1)^2
  EXPECT_NEAR(d1, 1 - 0.1 / 0.3, 1e-12);
  const double h = 1e-7, s = 0.09;
  double p1 = 0, m1 = 0;
  solo::tangentLoss(solo::TangentLoss::DeadZone, 0.1, s + h, &p1), solo::tangentLoss(solo::TangentLoss::DeadZone, 0.1, s - h, &m1);
  EXPECT_NEAR(d2, (p1 - m1) / (2 * h), 1e-5);
}

TEST(NormalGuidedObjective, GradientMatchesFiniteDifferences) {
  std::mt19937_64 random(5);
  std::uniform_real_distribution<float> depth_of(2.f, 20.f), unit(-1.f, 1.f);
  cv::Mat depth(7, 9, CV_32F), normals(7, 9, CV_32FC3), uncertain(7, 9, CV_8U, cv::Scalar(0)), labels(7, 9, CV_32S, cv::Scalar(1));
  for (int y = 0; y < 7; ++y)
    for (int x = 0; x < 9; ++x) {
      depth.at<float>(y, x) = depth_of(random);
      normals.at<cv::Vec3f>(y, x) = cv::normalize(cv::Vec3f(unit(random), unit(random), -1.5f));
    }
  depth.at<float>(3, 4) = 0;  // a hole: one-sided differences around it
  depth.at<float>(0, 0) = 0;
  normals.at<cv::Vec3f>(5, 5) = {0, 0, 0};
  uncertain.at<uchar>(2, 2) = 255;
  labels.colRange(6, 9).setTo(2);
  std::vector<solo::NormalGuidedObjectiveOptions> variants;
  for (const auto model : {solo::TangentModel::Perspective, solo::TangentModel::PaperGraph})
    for (const auto stencil : {solo::TangentStencil::Central, solo::TangentStencil::OneSided})
      for (const auto loss : {solo::TangentLoss::Squared, solo::TangentLoss::Cauchy, solo::TangentLoss::DeadZone}) {
        solo::NormalGuidedObjectiveOptions o;
        o.tangent_model = model, o.tangent_stencil = stencil, o.tangent_loss = loss;
        o.data_units = stencil == solo::TangentStencil::OneSided ? solo::DataUnits::Footprints : solo::DataUnits::Metres;
        variants.push_back(o);
      }
  for (const solo::NormalGuidedObjectiveOptions& o : variants) {
    const solo::NormalGuidedObjective objective(depth, normals, uncertain, camera(9, 7, 8), o, labels);
    std::vector<double> z = objective.filteredDepths();
    for (double& v : z) v *= 1 + 0.05 * unit(random);
    std::vector<double> gradient(z.size());
    solo::ObjectiveValue value;
    ASSERT_TRUE(objective.evaluate(z.data(), value, gradient.data()));
    const std::vector<double> diagonal = objective.gaussNewtonDiagonal(z.data());
    for (std::size_t i = 0; i < z.size(); ++i) {
      const double h = 1e-6 * z[i];
      std::vector<double> plus = z, minus = z;
      plus[i] += h, minus[i] -= h;
      solo::ObjectiveValue vp, vm;
      objective.evaluate(plus.data(), vp), objective.evaluate(minus.data(), vm);
      EXPECT_NEAR(gradient[i], (vp.total - vm.total) / (2 * h), 1e-6 * (1 + std::abs(gradient[i]))) << i;
      EXPECT_GT(diagonal[i], 0);
    }
  }
}

TEST(NormalGuidedObjective, AFrontoParallelPlaneWithItsNormalCostsNothing) {
  const cv::Mat depth(5, 6, CV_32F, cv::Scalar(7));
  const cv::Mat normals(5, 6, CV_32FC3, cv::Scalar(0, 0, -1));
  for (const auto model : {solo::TangentModel::Perspective, solo::TangentModel::PaperGraph}) {
    solo::NormalGuidedObjectiveOptions o;
    o.tangent_model = model;
    const solo::NormalGuidedObjective objective(depth, normals, {}, camera(6, 5), o);
    solo::ObjectiveValue v;
    ASSERT_TRUE(objective.evaluate(objective.filteredDepths().data(), v));
    EXPECT_EQ(v.total, 0);
  }
}

TEST(NormalGuidedObjective, PerspectiveTangentsFitAGroundPlaneThePaperGraphCannot) {
  // Road 1.5 m below the camera, seen below the horizon: z = 1.5 f / (v - cy), n = (0, -1, 0).
  const int w = 8, h = 40;
  const solo::PinholeCamera c = camera(w, h, 50);
  cv::Mat depth(h, w, CV_32F, cv::Scalar(0));
  for (int y = 25; y < h; ++y) depth.row(y).setTo(1.5 * 50 / (y - c.cy));
  const cv::Mat normals(h, w, CV_32FC3, cv::Scalar(0, -1, 0));
  solo::NormalGuidedObjectiveOptions perspective = solo::NormalGuidedObjectiveOptions::paper(), paper = perspective;
  paper.tangent_model = solo::TangentModel::PaperGraph;
  solo::ObjectiveValue vp, vg;
  const solo::NormalGuidedObjective exact(depth, normals, {}, c, perspective);
  exact.evaluate(exact.filteredDepths().data(), vp);
  const solo::NormalGuidedObjective graph(depth, normals, {}, c, paper);
  graph.evaluate(graph.filteredDepths().data(), vg);
  EXPECT_LT(vp.tangent, 0.5) << "only the O(h^2) error of the differences remains";
  EXPECT_NEAR(vg.tangent, 50.0, 1e-5) << "r_v = n_y = -1 whatever z: the graph has no vertical tangent";
}

TEST(NormalGuidedObjective, NonPositiveDepthsAreRejected) {
  const cv::Mat depth(2, 2, CV_32F, cv::Scalar(1));
  const solo::NormalGuidedObjective objective(depth, cv::Mat(2, 2, CV_32FC3, cv::Scalar(0, 0, -1)), {}, camera(2, 2));
  std::vector<double> z = {1, 1, -1, 1};
  solo::ObjectiveValue v;
  EXPECT_FALSE(objective.evaluate(z.data(), v));
  EXPECT_TRUE(std::isinf(v.total));
}

}  // namespace
