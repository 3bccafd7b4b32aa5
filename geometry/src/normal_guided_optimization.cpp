#include "solo/geometry/normal_guided_optimization.h"

#include <ceres/ceres.h>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <memory>

namespace solo {
namespace {

const char* tangentLossName(TangentLoss loss) {
  switch (loss) {
    case TangentLoss::Squared: return "squared";
    case TangentLoss::Huber: return "huber";
    case TangentLoss::Cauchy: return "cauchy";
    case TangentLoss::DeadZone: return "dead_zone";
  }
  return "unknown";
}

// ---- pyramid for the coarse-to-fine start ----

struct Level {
  cv::Mat depth_m, normals, uncertain, instances;
  PinholeCamera camera;
};

// Valid-weighted area average to `size`; valid where at least half the area was.
cv::Mat halveDepth(const cv::Mat& depth_m, cv::Size size) {
  cv::Mat valid_f, sum, weight;
  cv::Mat(depth_m > 0).convertTo(valid_f, CV_32F, 1.0 / 255);
  cv::resize(depth_m, sum, size, 0, 0, cv::INTER_AREA);
  cv::resize(valid_f, weight, size, 0, 0, cv::INTER_AREA);
  cv::Mat out(size, CV_32F, cv::Scalar(0));
  out.forEach<float>([&](float& v, const int* p) {
    const float w = weight.at<float>(p[0], p[1]);
    if (w >= 0.5f) v = sum.at<float>(p[0], p[1]) / w;
  });
  return out;
}

Level halve(const Level& fine) {
  const cv::Size size(std::max(1, fine.depth_m.cols / 2), std::max(1, fine.depth_m.rows / 2));
  Level coarse;
  coarse.depth_m = halveDepth(fine.depth_m, size);
  if (!fine.normals.empty()) {
    cv::Mat sum;
    cv::resize(fine.normals, sum, size, 0, 0, cv::INTER_AREA);  // invalid normals are (0,0,0)
    coarse.normals = cv::Mat(size, CV_32FC3, cv::Scalar::all(0));
    coarse.normals.forEach<cv::Vec3f>([&](cv::Vec3f& n, const int* p) {
      const cv::Vec3f s = sum.at<cv::Vec3f>(p[0], p[1]);
      const float length = std::sqrt(s.dot(s));
      if (length > 0.25f) n = s / length;  // mostly valid and mostly agreeing
    });
  }
  if (!fine.uncertain.empty()) {
    cv::resize(fine.uncertain, coarse.uncertain, size, 0, 0, cv::INTER_AREA);
    coarse.uncertain = coarse.uncertain > 0;
  }
  if (!fine.instances.empty()) cv::resize(fine.instances, coarse.instances, size, 0, 0, cv::INTER_NEAREST);
  coarse.camera = fine.camera.scaledTo(size.width, size.height);
  return coarse;
}

// Correction z - d~ of a level (0 where invalid), valid-weighted bilinearly to `size`.
cv::Mat upsampleCorrection(const cv::Mat& correction, const cv::Mat& valid, cv::Size size) {
  cv::Mat valid_f, sum, weight;
  valid.convertTo(valid_f, CV_32F, 1.0 / 255);
  cv::resize(correction, sum, size, 0, 0, cv::INTER_LINEAR);
  cv::resize(valid_f, weight, size, 0, 0, cv::INTER_LINEAR);
  cv::Mat out(size, CV_32F, cv::Scalar(0));
  out.forEach<float>([&](float& v, const int* p) {
    const float w = weight.at<float>(p[0], p[1]);
    if (w > 1e-3f) v = sum.at<float>(p[0], p[1]) / w;
  });
  return out;
}

// ---- whole-image L-BFGS ----

// L(z0 + s w) as a function of w, for ceres::GradientProblem.
class ScaledObjective final : public ceres::FirstOrderFunction {
 public:
  ScaledObjective(const NormalGuidedObjective& objective, std::vector<double> start, std::vector<double> scale)
      : objective_(objective), start_(std::move(start)), scale_(std::move(scale)), z_(start_.size()) {}

  bool Evaluate(const double* w, double* cost, double* gradient) const override {
    depths(w, z_.data());
    ObjectiveValue value;
    if (!objective_.evaluate(z_.data(), value, gradient)) return false;
    *cost = value.total;
    if (gradient)
      for (std::size_t i = 0; i < z_.size(); ++i) gradient[i] *= scale_[i];
    return true;
  }
  int NumParameters() const override { return static_cast<int>(start_.size()); }

  void depths(const double* w, double* z) const {
    for (std::size_t i = 0; i < start_.size(); ++i) z[i] = start_[i] + scale_[i] * w[i];
  }

 private:
  const NormalGuidedObjective& objective_;
  std::vector<double> start_, scale_;
  mutable std::vector<double> z_;
};

// Calls `on_iteration` with the current unknowns (update_state_every_iteration is on).
class IterationHook final : public ceres::IterationCallback {
 public:
  explicit IterationHook(std::function<void(const ceres::IterationSummary&)> on_iteration)
      : on_iteration_(std::move(on_iteration)) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& summary) override {
    on_iteration_(summary);
    return ceres::SOLVER_CONTINUE;
  }

 private:
  std::function<void(const ceres::IterationSummary&)> on_iteration_;
};

struct SolveClock {
  Stopwatch wall;
  double excluded = 0;  // observer time
  double seconds() const { return wall.seconds() - excluded; }
};

// Minimises `objective` from `start` with Ceres L-BFGS; returns the depths.
std::vector<double> solveLbfgs(const NormalGuidedObjective& objective, const std::vector<double>& start,
                               const NormalGuidedOptimizationOptions& options, int max_iterations, int level,
                               SolveClock& clock, std::vector<OptimizationIteration>& trace,
                               const OptimizationObserver& observer, std::string* termination) {
  const int m = objective.unknowns();
  std::vector<double> scale(m, 1.0);
  if (options.jacobi_scaling) {
    const std::vector<double> diagonal = objective.gaussNewtonDiagonal(start.data());
    for (int i = 0; i < m; ++i) scale[i] = diagonal[i] > 0 ? 1.0 / std::sqrt(diagonal[i]) : 1.0;
  }
  auto* function = new ScaledObjective(objective, start, scale);
  ceres::GradientProblem problem(function);  // takes ownership
  std::vector<double> w(m, 0.0), z(m);
  IterationHook hook([&](const ceres::IterationSummary& summary) {
    OptimizationIteration record;
    record.level = level, record.iteration = summary.iteration;
    record.seconds = clock.seconds();
    record.value.total = summary.cost;  // the parts only when someone looks
    if (observer && level == 0) {
      Stopwatch parts_clock;
      function->depths(w.data(), z.data());
      objective.evaluate(z.data(), record.value);
      clock.excluded += parts_clock.seconds();
    }
    trace.push_back(record);
    if (observer && level == 0) {
      Stopwatch observer_clock;
      observer(record, objective.toImage(z.data()));
      clock.excluded += observer_clock.seconds();
    }
  });
  ceres::GradientProblemSolver::Options solver;
  solver.line_search_direction_type = ceres::LBFGS;
  solver.max_lbfgs_rank = std::max(1, options.lbfgs_rank);
  solver.max_num_iterations = std::max(0, max_iterations);
  solver.function_tolerance = options.function_tolerance;
  solver.gradient_tolerance = 0;
  solver.parameter_tolerance = 0;
  solver.use_approximate_eigenvalue_bfgs_scaling = true;
  solver.logging_type = ceres::SILENT;
  solver.update_state_every_iteration = true;
  solver.callbacks.push_back(&hook);
  ceres::GradientProblemSolver::Summary summary;
  if (max_iterations > 0) ceres::Solve(solver, problem, w.data(), &summary);
  else {
    ceres::IterationSummary at_start;
    ObjectiveValue value;
    objective.evaluate(start.data(), value);
    at_start.cost = value.total;
    hook(at_start);
  }
  if (termination) *termination = max_iterations > 0 ? summary.message : "no iterations requested";
  function->depths(w.data(), z.data());
  return z;
}

// ---- per-pixel residual blocks, Levenberg-Marquardt ----

class PixelTangentCost final : public ceres::CostFunction {
 public:
  static constexpr int kResiduals = NormalGuidedObjective::kMaxResiduals;
  PixelTangentCost(const NormalGuidedObjective& objective, int pixel, int blocks) : objective_(objective), pixel_(pixel) {
    set_num_residuals(kResiduals);
    for (int k = 0; k < blocks; ++k) mutable_parameter_block_sizes()->push_back(1);
  }
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    const int blocks = static_cast<int>(parameter_block_sizes().size());
    double z[5] = {}, r[kResiduals] = {}, j[kResiduals][5] = {};
    for (int k = 0; k < blocks; ++k) {
      z[k] = parameters[k][0];
      if (!(z[k] > 0)) return false;
    }
    objective_.tangentResiduals(pixel_, z, r, j);
    // Ceres minimises 1/2 sum r^2; the objective is sum w r^2.
    for (int row = 0; row < kResiduals; ++row) residuals[row] = std::sqrt(2.0) * r[row];
    if (jacobians)
      for (int k = 0; k < blocks; ++k)
        if (jacobians[k])
          for (int row = 0; row < kResiduals; ++row) jacobians[k][row] = std::sqrt(2.0) * j[row][k];
    return true;
  }

 private:
  const NormalGuidedObjective& objective_;
  int pixel_;
};

// The tangent loss in Ceres' convention: its cost is 1/2 rho_c(|f|^2) with f = sqrt(2 w) (the weighted residuals),
// and the objective's is w rho(s), s = |f|^2 / (2 w): rho_c(t) = 2 w rho(t / (2 w)).
class PixelTangentLoss final : public ceres::LossFunction {
 public:
  PixelTangentLoss(TangentLoss loss, double scale, double weight) : loss_(loss), scale_(scale), weight_(weight) {}
  void Evaluate(double t, double rho[3]) const override {
    const double s = t / (2 * weight_);
    rho[0] = 2 * weight_ * tangentLoss(loss_, scale_, s, &rho[1], &rho[2]);
    rho[2] /= 2 * weight_;
    // The dead zone is convex (rho'' >= 0) with rho' = 0 inside: Ceres' curvature correction
    // divides by rho', so it gets the Gauss-Newton model of the scaled residuals instead.
    if (loss_ == TangentLoss::DeadZone) rho[2] = 0;
  }

 private:
  TangentLoss loss_;
  double scale_, weight_;
};

class PixelDataCost final : public ceres::SizedCostFunction<1, 1> {
 public:
  PixelDataCost(double filtered_m, double weight) : filtered_m_(filtered_m), scale_(std::sqrt(2 * weight)) {}
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    residuals[0] = scale_ * (parameters[0][0] - filtered_m_);
    if (jacobians && jacobians[0]) jacobians[0][0] = scale_;
    return true;
  }

 private:
  double filtered_m_, scale_;
};

std::vector<double> solvePerPixel(const NormalGuidedObjective& objective, const NormalGuidedOptimizationOptions& options,
                                  SolveClock& clock, std::vector<OptimizationIteration>& trace,
                                  const OptimizationObserver& observer, std::string* termination) {
  std::vector<double> z = objective.filteredDepths();
  ceres::Problem problem;
  for (int i = 0; i < objective.unknowns(); ++i) {
    problem.AddResidualBlock(new PixelDataCost(z[i], objective.dataWeight(i)), nullptr, &z[i]);
    const NormalGuidedObjective::PixelStencil s = objective.stencil(i);
    if (s.count == 0) continue;
    std::vector<double*> blocks;
    for (int k = 0; k < s.count; ++k) blocks.push_back(&z[s.unknown[k]]);
    ceres::LossFunction* loss =
        objective.loss() == TangentLoss::Squared
            ? nullptr
            : new PixelTangentLoss(objective.loss(), objective.lossScale(), objective.tangentWeight(i));
    problem.AddResidualBlock(new PixelTangentCost(objective, i, s.count), loss, blocks);
  }
  IterationHook hook([&](const ceres::IterationSummary& summary) {
    OptimizationIteration record;
    record.iteration = summary.iteration;
    objective.evaluate(z.data(), record.value);
    record.seconds = clock.seconds();
    trace.push_back(record);
    if (observer) {
      Stopwatch observer_clock;
      observer(record, objective.toImage(z.data()));
      clock.excluded += observer_clock.seconds();
    }
  });
  ceres::Solver::Options solver;
  solver.linear_solver_type = ceres::CGNR;
  solver.preconditioner_type = ceres::JACOBI;
  solver.max_num_iterations = std::max(0, options.max_iterations);
  solver.function_tolerance = options.function_tolerance;
  solver.gradient_tolerance = 0;
  solver.parameter_tolerance = 0;
  solver.num_threads = std::max(1, options.threads);
  solver.logging_type = ceres::SILENT;
  solver.update_state_every_iteration = true;
  solver.callbacks.push_back(&hook);
  ceres::Solver::Summary summary;
  if (options.max_iterations > 0 && objective.unknowns() > 0) ceres::Solve(solver, &problem, &summary);
  else hook(ceres::IterationSummary());
  if (termination) *termination = summary.message;
  return z;
}

}  // namespace

NormalGuidedOptimizationResult optimizeDepthWithNormals(const cv::Mat& filtered_depth_m, const cv::Mat& normals,
                                                        const cv::Mat& uncertain, const cv::Mat& instances,
                                                        const PinholeCamera& camera,
                                                        const NormalGuidedOptimizationOptions& options,
                                                        const OptimizationObserver& observer) {
  CV_Assert(filtered_depth_m.type() == CV_32F && filtered_depth_m.isContinuous());
  SolveClock clock;
  NormalGuidedOptimizationResult result;
  result.report.name = "optimize";
  const bool lbfgs = options.layout == DepthSolverLayout::WholeImageLbfgs;

  const cv::Mat segments = options.stencil_within_instances ? instances : cv::Mat();
  const NormalGuidedObjective objective(filtered_depth_m, normals, uncertain, camera, options.objective, segments);
  const std::vector<double>& filtered = objective.filteredDepths();
  objective.evaluate(filtered.data(), result.initial);

  std::vector<double> z;
  if (objective.unknowns() == 0) {
    z = filtered;
    result.termination = "no valid depth";
  } else if (!lbfgs) {
    z = solvePerPixel(objective, options, clock, result.trace, observer, &result.termination);
  } else {
    // Coarse-to-fine start: levels of half resolution while at least 16 px remain.
    std::vector<Level> levels{{filtered_depth_m, normals, uncertain, segments, camera}};
    while (static_cast<int>(levels.size()) <= options.coarse_levels &&
           std::min(levels.back().depth_m.cols, levels.back().depth_m.rows) >= 32)
      levels.push_back(halve(levels.back()));
    cv::Mat correction;  // z - d~ at the level below, 0 = none
    for (int level = static_cast<int>(levels.size()) - 1; level >= 1; --level) {
      const Level& l = levels[level];
      const NormalGuidedObjective coarse(l.depth_m, l.normals, l.uncertain, l.camera, options.objective, l.instances);
      if (coarse.unknowns() == 0) continue;
      const cv::Mat start_image =
          correction.empty() ? l.depth_m : cv::Mat(l.depth_m + upsampleCorrection(correction, levels[level + 1].depth_m > 0, l.depth_m.size()));
      std::vector<double> start = coarse.fromImage(start_image);
      for (int i = 0; i < coarse.unknowns(); ++i)
        if (!(start[i] > 0.1 * coarse.filteredDepths()[i])) start[i] = coarse.filteredDepths()[i];
      const std::vector<double> solved =
          solveLbfgs(coarse, start, options, options.coarse_max_iterations, level, clock, result.trace, {}, nullptr);
      correction = coarse.toImage(solved.data()) - l.depth_m;
      correction.setTo(0, l.depth_m <= 0);
    }
    std::vector<double> start = filtered;
    if (!correction.empty()) {
      const cv::Mat up = upsampleCorrection(correction, levels[1].depth_m > 0, filtered_depth_m.size());
      std::vector<double> candidate = objective.fromImage(cv::Mat(filtered_depth_m + up));
      for (int i = 0; i < objective.unknowns(); ++i)
        if (!(candidate[i] > 0.1 * filtered[i])) candidate[i] = filtered[i];
      ObjectiveValue candidate_value;
      if (objective.evaluate(candidate.data(), candidate_value) && candidate_value.total < result.initial.total)
        start = std::move(candidate);
      else
        result.report.notes.push_back("the coarse-to-fine start was not better than d~: started from d~");
    }
    z = solveLbfgs(objective, start, options, options.max_iterations, 0, clock, result.trace, observer,
                   &result.termination);
  }
  if (!objective.evaluate(z.data(), result.final) || result.final.total > result.initial.total) {
    z = filtered;  // never worse than the input
    result.final = result.initial;
    result.report.notes.push_back("the solver did not improve on d~: kept d~");
  }
  result.depth_m = objective.toImage(z.data());

  double change = 0;
  for (int i = 0; i < objective.unknowns(); ++i) change += std::abs(z[i] - filtered[i]);
  int full_iterations = 0;
  for (const OptimizationIteration& it : result.trace)
    if (it.level == 0) full_iterations = std::max(full_iterations, it.iteration);
  StageReport& r = result.report;
  r.add("layout", std::string(lbfgs ? "whole_image_lbfgs" : "per_pixel_residual_blocks"));
  r.add("tangent_model",
        std::string(options.objective.tangent_model == TangentModel::Perspective ? "perspective" : "paper_graph"));
  r.add("tangent_stencil",
        std::string(options.objective.tangent_stencil == TangentStencil::OneSided ? "one_sided" : "central"));
  r.add("tangent_loss", std::string(tangentLossName(options.objective.tangent_loss)));
  r.add("data_weight", options.objective.data_weight);
  r.add("data_units", std::string(options.objective.data_units == DataUnits::Footprints ? "footprints" : "metres"));
  r.add("unknowns", std::int64_t{objective.unknowns()});
  r.add("tangent_pixels", std::int64_t{objective.tangentPixels()});
  r.add("iterations", std::int64_t{full_iterations});
  r.add("objective_initial", result.initial.total).add("objective_final", result.final.total);
  r.add("tangent_term_initial", result.initial.tangent).add("tangent_term_final", result.final.tangent);
  r.add("data_term_final", result.final.data,
        options.objective.data_units == DataUnits::Footprints ? "footprint^2" : "m^2");
  r.add("mean_abs_change", objective.unknowns() ? change / objective.unknowns() : 0.0, "m");
  r.add("termination", result.termination);
  r.seconds = clock.seconds();
  return result;
}

}  // namespace solo
