// Normal-guided depth optimisation (Ceres) and the paper's Adam: accuracy on planes with
// known truth, agreement of the layouts, and the numerical-stability cases (grazing and
// back-facing normals, invalid pixels in the stencil, 0.5 m to 1 km, degenerate images).

#include <solo/geometry/adam_depth_optimizer.h>
#include <solo/geometry/normal_guided_optimization.h>
#include <solo/geometry/normals_from_depth.h>

#include <opencv2/imgproc.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace {

solo::PinholeCamera camera(int width, int height, double f) {
  solo::PinholeCamera c;
  c.fx = c.fy = f, c.cx = (width - 1) / 2.0, c.cy = (height - 1) / 2.0, c.width = width, c.height = height;
  return c;
}

// A tilted plane n . X = c seen by `cam`: exact depth and normals.
struct Plane {
  cv::Mat depth, normals;
};
Plane plane(const solo::PinholeCamera& cam, cv::Vec3d n, double c) {
  n = cv::normalize(n);
  Plane p{cv::Mat(cam.height, cam.width, CV_32F), cv::Mat(cam.height, cam.width, CV_32FC3)};
  for (int y = 0; y < cam.height; ++y)
    for (int x = 0; x < cam.width; ++x) {
      const cv::Vec3d ray((x - cam.cx) / cam.fx, (y - cam.cy) / cam.fy, 1);
      p.depth.at<float>(y, x) = static_cast<float>(c / n.dot(ray));
      p.normals.at<cv::Vec3f>(y, x) = cv::Vec3f(n);
    }
  return p;
}

cv::Mat noisy(const cv::Mat& depth, double relative, std::uint64_t seed) {
  std::mt19937_64 random(seed);
  std::normal_distribution<double> noise(0, relative);
  cv::Mat out = depth.clone();
  for (int y = 0; y < out.rows; ++y)
    for (int x = 0; x < out.cols; ++x)
      if (out.at<float>(y, x) > 0) out.at<float>(y, x) *= static_cast<float>(1 + noise(random));
  return out;
}

double rmse(const cv::Mat& a, const cv::Mat& b) { return cv::norm(a, b, cv::NORM_L2, b > 0) / std::sqrt(cv::countNonZero(b > 0)); }

void expectFiniteAndNotWorse(const solo::NormalGuidedOptimizationResult& r, const cv::Mat& input) {
  EXPECT_TRUE(cv::checkRange(r.depth_m));
  EXPECT_LE(r.final.total, r.initial.total);
  EXPECT_TRUE(std::isfinite(r.final.total));
  EXPECT_EQ(cv::countNonZero(r.depth_m > 0), cv::countNonZero(input > 0)) << "same valid pixels";
}

TEST(NormalGuidedOptimization, RecoversATiltedPlaneFromNoisyDepth) {
  const solo::PinholeCamera cam = camera(64, 48, 60);
  const Plane truth = plane(cam, {0.3, -0.2, -1}, -8);
  const cv::Mat input = noisy(truth.depth, 0.02, 1);
  // The paper's objective trusts the (exact) normals: the tangent term all but vanishes.
  solo::NormalGuidedOptimizationOptions paper;
  paper.objective = solo::NormalGuidedObjectiveOptions::paper();
  const auto r = solo::optimizeDepthWithNormals(input, truth.normals, {}, {}, cam, paper);
  expectFiniteAndNotWorse(r, input);
  EXPECT_LT(rmse(r.depth_m, truth.depth), 0.5 * rmse(input, truth.depth));
  EXPECT_LT(r.final.tangent, 0.05 * r.initial.tangent);
  // The default's Cauchy loss takes 1.2 footprints of independent noise per pixel for normals
  // that disagree (an outlier): it still halves the error, with less of the tangent term gone.
  const auto d = solo::optimizeDepthWithNormals(input, truth.normals, {}, {}, cam);
  expectFiniteAndNotWorse(d, input);
  EXPECT_LT(rmse(d.depth_m, truth.depth), 0.5 * rmse(input, truth.depth));
}

// The residual of a filter: relative depth noise smoothed over sigma_px (a few pixels' wavelength).
cv::Mat smoothlyNoisy(const cv::Mat& depth, double relative, double sigma_px, std::uint64_t seed) {
  std::mt19937_64 random(seed);
  std::normal_distribution<float> noise(0, 1);
  cv::Mat field(depth.size(), CV_32F);
  for (int y = 0; y < field.rows; ++y)
    for (int x = 0; x < field.cols; ++x) field.at<float>(y, x) = noise(random);
  cv::GaussianBlur(field, field, cv::Size(), sigma_px);
  cv::Scalar mean, stddev;
  cv::meanStdDev(field, mean, stddev);
  cv::Mat factor = 1 + (field - mean[0]) * (relative / stddev[0]);
  return depth.mul(factor);
}

// Unit normals rotated by bias_deg about the camera's x axis, plus per-pixel noise_deg.
cv::Mat biasedNormals(const cv::Mat& normals, double bias_deg, double noise_deg, std::uint64_t seed) {
  std::mt19937_64 random(seed);
  std::normal_distribution<double> noise(0, std::tan(noise_deg * CV_PI / 180));
  const double b = bias_deg * CV_PI / 180;
  cv::Mat out(normals.size(), CV_32FC3);
  for (int y = 0; y < out.rows; ++y)
    for (int x = 0; x < out.cols; ++x) {
      const cv::Vec3d n = normals.at<cv::Vec3f>(y, x);
      const cv::Vec3d rotated(n[0], std::cos(b) * n[1] - std::sin(b) * n[2], std::sin(b) * n[1] + std::cos(b) * n[2]);
      out.at<cv::Vec3f>(y, x) = cv::Vec3f(cv::normalize(rotated + cv::Vec3d(noise(random), noise(random), noise(random))));
    }
  return out;
}

double absRel(const cv::Mat& depth, const cv::Mat& truth) {
  double sum = 0;
  int n = 0;
  for (int y = 0; y < truth.rows; ++y)
    for (int x = 0; x < truth.cols; ++x)
      if (truth.at<float>(y, x) > 0 && depth.at<float>(y, x) > 0)
        sum += std::abs(depth.at<float>(y, x) - truth.at<float>(y, x)) / truth.at<float>(y, x), ++n;
  return sum / std::max(1, n);
}

// Mean angle (deg) between the normals of `depth` (normalsFromDepth) and the true normals.
double normalErrorDeg(const cv::Mat& depth, const cv::Mat& true_normals, const solo::PinholeCamera& cam) {
  const cv::Mat n = solo::normalsFromDepth(depth, cam);
  double sum = 0;
  int count = 0;
  for (int y = 0; y < n.rows; ++y)
    for (int x = 0; x < n.cols; ++x) {
      const cv::Vec3f a = n.at<cv::Vec3f>(y, x), b = true_normals.at<cv::Vec3f>(y, x);
      if (a.dot(a) < 0.5f) continue;
      sum += std::acos(std::min(1.0, std::abs(static_cast<double>(a.dot(b))))) * 180 / CV_PI, ++count;
    }
  return sum / std::max(1, count);
}

TEST(NormalGuidedOptimization, BiasedNormalsImproveTheDepthsNormalsWithoutWorseningTheDepth) {
  // A tilted plane seen at 5-12 m; d~ = truth with 0.5 % noise smoothed over 2 px (what the
  // filter leaves); predicted normals 3 deg off the truth (a bias) plus 2 deg of per-pixel noise.
  const solo::PinholeCamera cam = camera(96, 72, 80);
  const Plane truth = plane(cam, {0.3, -0.6, -1}, -6);
  const cv::Mat filtered = smoothlyNoisy(truth.depth, 0.005, 2, 11);
  const cv::Mat predicted = biasedNormals(truth.normals, 3, 2, 12);
  const double filtered_abs_rel = absRel(filtered, truth.depth), filtered_rmse = rmse(filtered, truth.depth);
  const double filtered_normals_deg = normalErrorDeg(filtered, truth.normals, cam);

  const auto refined = solo::optimizeDepthWithNormals(filtered, predicted, {}, {}, cam);
  expectFiniteAndNotWorse(refined, filtered);
  EXPECT_LE(absRel(refined.depth_m, truth.depth), filtered_abs_rel);
  EXPECT_LE(rmse(refined.depth_m, truth.depth), filtered_rmse);
  EXPECT_LT(normalErrorDeg(refined.depth_m, truth.normals, cam), 0.8 * filtered_normals_deg);

  // The paper's objective (central differences, data term in metres) puts the normals' noise
  // into the depth: its normals end further from the truth than the default's.
  solo::NormalGuidedOptimizationOptions paper;
  paper.objective = solo::NormalGuidedObjectiveOptions::paper();
  const auto integrated = solo::optimizeDepthWithNormals(filtered, predicted, {}, {}, cam, paper);
  EXPECT_GT(normalErrorDeg(integrated.depth_m, truth.normals, cam),
            1.5 * normalErrorDeg(refined.depth_m, truth.normals, cam));
}

TEST(NormalGuidedOptimizationStability, ABoxBeforeAWallWithGrazingNormalsAndHoles) {
  // Two instances, a box 4 m in front of a wall at 12 m (a depth jump), a strip of grazing
  // predicted normals, invalid pixels; d~ with smooth noise, normals biased 3 deg.
  const solo::PinholeCamera cam = camera(64, 48, 60);
  Plane wall = plane(cam, {0.1, 0, -1}, -12), box = plane(cam, {-0.2, 0.1, -1}, -4);
  cv::Mat depth = wall.depth.clone(), normals = wall.normals.clone(), labels(48, 64, CV_32S, cv::Scalar(11));
  const cv::Rect inside(20, 14, 24, 20);
  box.depth(inside).copyTo(depth(inside));
  box.normals(inside).copyTo(normals(inside));
  labels(inside).setTo(26001);
  const cv::Mat truth = depth.clone(), true_normals = normals.clone();
  cv::Mat filtered = smoothlyNoisy(depth, 0.004, 2, 21);
  cv::Mat predicted = biasedNormals(normals, 3, 2, 22);
  for (int y = 0; y < 48; ++y)  // grazing: perpendicular to the ray
    for (int x = 0; x < 4; ++x) {
      const cv::Vec3d ray((x - cam.cx) / cam.fx, (y - cam.cy) / cam.fy, 1);
      predicted.at<cv::Vec3f>(y, x) = cv::Vec3f(cv::normalize(ray.cross(cv::Vec3d(0, 1, 0)).cross(ray)));
    }
  filtered(cv::Rect(30, 5, 3, 3)).setTo(0);
  filtered.row(40).setTo(0);
  for (const auto layout : {solo::DepthSolverLayout::WholeImageLbfgs, solo::DepthSolverLayout::PerPixelResidualBlocks}) {
    solo::NormalGuidedOptimizationOptions o;
    o.layout = layout;
    const auto r = solo::optimizeDepthWithNormals(filtered, predicted, {}, labels, cam, o);
    expectFiniteAndNotWorse(r, filtered);
    EXPECT_LE(absRel(r.depth_m, truth), absRel(filtered, truth));
    EXPECT_LT(normalErrorDeg(r.depth_m, true_normals, cam), normalErrorDeg(filtered, true_normals, cam));
  }
}

TEST(NormalGuidedOptimization, LayoutsAndOptimisersAgreeOnTheMinimum) {
  const solo::PinholeCamera cam = camera(24, 18, 30);
  const Plane truth = plane(cam, {-0.4, 0.1, -1}, -5);
  const cv::Mat input = noisy(truth.depth, 0.03, 2);
  solo::NormalGuidedOptimizationOptions lbfgs, per_pixel;
  lbfgs.max_iterations = 500, lbfgs.function_tolerance = 1e-12;
  per_pixel.layout = solo::DepthSolverLayout::PerPixelResidualBlocks;
  per_pixel.max_iterations = 100, per_pixel.function_tolerance = 1e-12;
  const auto a = solo::optimizeDepthWithNormals(input, truth.normals, {}, {}, cam, lbfgs);
  const auto b = solo::optimizeDepthWithNormals(input, truth.normals, {}, {}, cam, per_pixel);
  EXPECT_NEAR(a.final.total, b.final.total, 1e-3 * b.final.total);
  EXPECT_LT(cv::norm(a.depth_m, b.depth_m, cv::NORM_INF), 1e-2);
  solo::AdamOptions adam;
  const auto c = solo::optimizeDepthWithAdam(input, truth.normals, {}, {}, cam, adam);
  EXPECT_LT(c.final.total, c.initial.total);
  EXPECT_LT(a.final.total, c.final.total) << "1000 steps of 2e-4 m do not converge";
}

TEST(NormalGuidedOptimization, AdamsFirstStepMovesEveryPixelByTheLearningRate) {
  const solo::PinholeCamera cam = camera(10, 8, 20);
  const Plane truth = plane(cam, {0.2, 0.1, -1}, -4);
  const cv::Mat input = noisy(truth.depth, 0.05, 3);
  solo::AdamOptions o;
  o.iterations = 1;
  const auto r = solo::optimizeDepthWithAdam(input, truth.normals, {}, {}, cam, o);
  ASSERT_LT(r.final.total, r.initial.total);
  const cv::Mat step = cv::abs(r.depth_m - input);
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 10; ++x) EXPECT_NEAR(step.at<float>(y, x), 2e-4, 1e-6) << "bias-corrected |m / sqrt v| = 1";
}

TEST(NormalGuidedOptimizationStability, GrazingNormals) {
  // Normals perpendicular to each pixel's ray (n . ray = 0) and n_z = 0: no slope information.
  const solo::PinholeCamera cam = camera(16, 12, 20);
  cv::Mat depth(12, 16, CV_32F, cv::Scalar(10)), normals(12, 16, CV_32FC3);
  for (int y = 0; y < 12; ++y)
    for (int x = 0; x < 16; ++x) {
      const cv::Vec3d ray((x - cam.cx) / cam.fx, (y - cam.cy) / cam.fy, 1);
      normals.at<cv::Vec3f>(y, x) = cv::Vec3f(cv::normalize(ray.cross(cv::Vec3d(0, 1, 0)).cross(ray)));
    }
  normals.row(0).setTo(cv::Scalar(1, 0, 0));
  const cv::Mat input = noisy(depth, 0.01, 4);
  for (const auto model : {solo::TangentModel::Perspective, solo::TangentModel::PaperGraph}) {
    solo::NormalGuidedOptimizationOptions o;
    o.objective.tangent_model = model;
    expectFiniteAndNotWorse(solo::optimizeDepthWithNormals(input, normals, {}, {}, cam, o), input);
    solo::AdamOptions a;
    a.objective.tangent_model = model;
    expectFiniteAndNotWorse(solo::optimizeDepthWithAdam(input, normals, {}, {}, cam, a), input);
  }
}

TEST(NormalGuidedOptimizationStability, NormalsPointingAwayFromTheCameraActLikeTheirFlip) {
  const solo::PinholeCamera cam = camera(20, 14, 25);
  const Plane truth = plane(cam, {0.2, 0.3, -1}, -6);
  const cv::Mat input = noisy(truth.depth, 0.02, 5);
  const cv::Mat away = -truth.normals;
  const auto front = solo::optimizeDepthWithNormals(input, truth.normals, {}, {}, cam);
  const auto back = solo::optimizeDepthWithNormals(input, away, {}, {}, cam);
  expectFiniteAndNotWorse(back, input);
  EXPECT_NEAR(back.final.total, front.final.total, 1e-9 * front.initial.total) << "r is odd in n";
}

TEST(NormalGuidedOptimizationStability, InvalidAndSkyPixelsInsideTheStencil) {
  const solo::PinholeCamera cam = camera(30, 20, 30);
  const Plane truth = plane(cam, {0, 0.2, -1}, -9);
  cv::Mat input = noisy(truth.depth, 0.02, 6);
  input.rowRange(0, 5).setTo(0);                 // sky
  input(cv::Rect(10, 10, 1, 1)).setTo(0);        // isolated holes
  input(cv::Rect(20, 12, 1, 1)).setTo(0);
  input.col(15).setTo(0);                        // a split: one-sided differences on both sides
  cv::Mat normals = truth.normals.clone();
  normals(cv::Rect(3, 15, 2, 2)).setTo(cv::Scalar::all(0));  // no normal there
  const auto r = solo::optimizeDepthWithNormals(input, normals, {}, {}, cam);
  expectFiniteAndNotWorse(r, input);
  EXPECT_EQ(cv::countNonZero(r.depth_m.rowRange(0, 5)), 0);
  cv::Mat visible_truth = truth.depth.clone();
  visible_truth.setTo(0, input <= 0);
  EXPECT_LT(rmse(r.depth_m, visible_truth), rmse(input, visible_truth));
  expectFiniteAndNotWorse(solo::optimizeDepthWithAdam(input, normals, {}, {}, cam), input);
}

TEST(NormalGuidedOptimizationStability, DepthsFromHalfAMetreToAKilometre) {
  const solo::PinholeCamera cam = camera(40, 30, 40);
  cv::Mat depth(30, 40, CV_32F), normals(30, 40, CV_32FC3, cv::Scalar(0, 0, -1)), labels(30, 40, CV_32S);
  for (int y = 0; y < 30; ++y)
    for (int x = 0; x < 40; ++x) {
      depth.at<float>(y, x) = x < 20 ? 0.5f : 1000.f;
      labels.at<int>(y, x) = x < 20 ? 24001 : 11;
    }
  const cv::Mat input = noisy(depth, 0.01, 7);
  for (const cv::Mat& segments : {cv::Mat(), labels}) {
    const auto r = solo::optimizeDepthWithNormals(input, normals, {}, segments, cam);
    expectFiniteAndNotWorse(r, input);
    cv::Mat near_part = r.depth_m.colRange(0, 20), far_part = r.depth_m.colRange(20, 40);
    double lo, hi;
    cv::minMaxLoc(near_part, &lo, &hi);
    EXPECT_GT(lo, 0.0);
    cv::minMaxLoc(far_part, &lo, &hi);
    EXPECT_LT(hi, 2000.0);
  }
  expectFiniteAndNotWorse(solo::optimizeDepthWithAdam(input, normals, {}, labels, cam), input);
}

TEST(NormalGuidedOptimizationStability, ASingleValidPixel) {
  const solo::PinholeCamera cam = camera(5, 5, 10);
  cv::Mat depth(5, 5, CV_32F, cv::Scalar(0));
  depth.at<float>(2, 3) = 4;
  const cv::Mat normals(5, 5, CV_32FC3, cv::Scalar(0, 0, -1));
  for (const auto layout : {solo::DepthSolverLayout::WholeImageLbfgs, solo::DepthSolverLayout::PerPixelResidualBlocks}) {
    solo::NormalGuidedOptimizationOptions o;
    o.layout = layout;
    const auto r = solo::optimizeDepthWithNormals(depth, normals, {}, {}, cam, o);
    expectFiniteAndNotWorse(r, depth);
    EXPECT_FLOAT_EQ(r.depth_m.at<float>(2, 3), 4.f) << "no neighbour: only the data term";
  }
  const auto a = solo::optimizeDepthWithAdam(depth, normals, {}, {}, cam);
  EXPECT_FLOAT_EQ(a.depth_m.at<float>(2, 3), 4.f);
  const auto none = solo::optimizeDepthWithNormals(cv::Mat(3, 3, CV_32F, cv::Scalar(0)), cv::Mat(3, 3, CV_32FC3), {}, {}, cam);
  EXPECT_EQ(cv::countNonZero(none.depth_m), 0);
}

TEST(NormalGuidedOptimizationStability, AllPixelsUncertainLeavesTheFilteredDepth) {
  const solo::PinholeCamera cam = camera(12, 9, 15);
  const Plane truth = plane(cam, {0.1, 0.1, -1}, -3);
  const cv::Mat input = noisy(truth.depth, 0.02, 8);
  const cv::Mat uncertain(9, 12, CV_8U, cv::Scalar(255));
  const auto r = solo::optimizeDepthWithNormals(input, truth.normals, uncertain, {}, cam);
  expectFiniteAndNotWorse(r, input);
  EXPECT_EQ(r.initial.total, 0);
  EXPECT_LT(cv::norm(r.depth_m, input, cv::NORM_INF), 1e-6);
}

TEST(NormalGuidedOptimizationStability, AnImageOnePixelWide) {
  const solo::PinholeCamera cam = camera(1, 40, 30);
  const Plane truth = plane(cam, {0, 0.5, -1}, -6);
  const cv::Mat input = noisy(truth.depth, 0.02, 9);
  for (const auto layout : {solo::DepthSolverLayout::WholeImageLbfgs, solo::DepthSolverLayout::PerPixelResidualBlocks}) {
    solo::NormalGuidedOptimizationOptions o;
    o.layout = layout;
    const auto r = solo::optimizeDepthWithNormals(input, truth.normals, {}, {}, cam, o);
    expectFiniteAndNotWorse(r, input);
    EXPECT_LT(rmse(r.depth_m, truth.depth), rmse(input, truth.depth));
  }
  expectFiniteAndNotWorse(solo::optimizeDepthWithAdam(input, truth.normals, {}, {}, cam), input);
}

}  // namespace

// The robust tangent losses (Huber, Cauchy): exact gradients, the same minimum in both layouts,
// and a patch of wrong normals bends the depth less than with the squared loss.
TEST(NormalGuidedOptimization, RobustTangentLossesAgreeAcrossLayoutsAndResistWrongNormals) {
  const solo::PinholeCamera cam = camera(24, 18, 30);
  const Plane truth = plane(cam, {-0.3, 0.2, -1}, -6);
  const cv::Mat input = noisy(truth.depth, 0.02, 4);
  cv::Mat normals = truth.normals.clone();
  normals(cv::Rect(8, 6, 6, 5)).setTo(cv::Vec3f(cv::normalize(cv::Vec3f(0.8f, 0, -1))));  // ~40 deg off
  solo::NormalGuidedOptimizationOptions squared;
  squared.objective = solo::NormalGuidedObjectiveOptions::paper();
  squared.objective.tangent_loss_scale = 0.1;
  squared.max_iterations = 500, squared.function_tolerance = 1e-12;
  double squared_rmse = 0;
  {
    const auto r = solo::optimizeDepthWithNormals(input, normals, {}, {}, cam, squared);
    squared_rmse = rmse(r.depth_m, truth.depth);
  }
  for (const auto loss : {solo::TangentLoss::Huber, solo::TangentLoss::Cauchy}) {
    solo::NormalGuidedOptimizationOptions lbfgs = squared, per_pixel = squared;
    lbfgs.objective.tangent_loss = per_pixel.objective.tangent_loss = loss;
    per_pixel.layout = solo::DepthSolverLayout::PerPixelResidualBlocks;
    per_pixel.max_iterations = 100;
    const solo::NormalGuidedObjective objective(input, normals, {}, cam, lbfgs.objective);
    std::vector<double> z = objective.filteredDepths(), gradient(z.size());
    solo::ObjectiveValue value;
    ASSERT_TRUE(objective.evaluate(z.data(), value, gradient.data()));
    for (std::size_t i = 0; i < z.size(); i += 7) {
      const double h = 1e-6 * z[i];
      std::vector<double> plus = z, minus = z;
      plus[i] += h, minus[i] -= h;
      solo::ObjectiveValue vp, vm;
      objective.evaluate(plus.data(), vp), objective.evaluate(minus.data(), vm);
      EXPECT_NEAR(gradient[i], (vp.total - vm.total) / (2 * h), 1e-6 * (1 + std::abs(gradient[i]))) << i;
    }
    const auto a = solo::optimizeDepthWithNormals(input, normals, {}, {}, cam, lbfgs);
    const auto b = solo::optimizeDepthWithNormals(input, normals, {}, {}, cam, per_pixel);
    expectFiniteAndNotWorse(a, input);
    EXPECT_NEAR(a.final.total, b.final.total, 1e-3 * b.final.total);
    EXPECT_LT(rmse(a.depth_m, truth.depth), squared_rmse) << "the wrong patch pulls less";
  }
}
