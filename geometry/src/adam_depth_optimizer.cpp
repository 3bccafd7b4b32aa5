#include "solo/geometry/adam_depth_optimizer.h"

#include <algorithm>
#include <cmath>

namespace solo {

NormalGuidedOptimizationResult optimizeDepthWithAdam(const cv::Mat& filtered_depth_m, const cv::Mat& normals,
                                                     const cv::Mat& uncertain, const cv::Mat& instances,
                                                     const PinholeCamera& camera,
                                                     const AdamOptions& options, const OptimizationObserver& observer) {
  Stopwatch clock;
  double excluded = 0;
  NormalGuidedOptimizationResult result;
  result.report.name = "optimize";
  const NormalGuidedObjective objective(filtered_depth_m, normals, uncertain, camera, options.objective,
                                        options.stencil_within_instances ? instances : cv::Mat());
  const int m = objective.unknowns();
  std::vector<double> z = objective.filteredDepths(), best = z, gradient(m), first(m, 0.0), second(m, 0.0);
  ObjectiveValue value, best_value;
  objective.evaluate(z.data(), value, gradient.data());
  result.initial = best_value = value;
  double beta1_power = 1, beta2_power = 1;
  for (int iteration = 0; m > 0; ++iteration) {
    OptimizationIteration record;
    record.iteration = iteration, record.value = value, record.seconds = clock.seconds() - excluded;
    result.trace.push_back(record);
    if (observer) {
      Stopwatch observer_clock;
      observer(record, objective.toImage(z.data()));
      excluded += observer_clock.seconds();
    }
    if (iteration == options.iterations) break;
    beta1_power *= options.beta1, beta2_power *= options.beta2;
    const double step = options.learning_rate_m * std::sqrt(1 - beta2_power) / (1 - beta1_power);
    for (int i = 0; i < m; ++i) {
      first[i] = options.beta1 * first[i] + (1 - options.beta1) * gradient[i];
      second[i] = options.beta2 * second[i] + (1 - options.beta2) * gradient[i] * gradient[i];
      const double next = z[i] - step * first[i] / (std::sqrt(second[i]) + options.epsilon);
      z[i] = next > 0 ? next : 0.5 * z[i];  // the objective is undefined at z <= 0
    }
    objective.evaluate(z.data(), value, gradient.data());
    if (value.total < best_value.total) best_value = value, best = z;
  }
  result.final = best_value;
  result.depth_m = objective.toImage(best.data());
  result.termination = "fixed iteration count";
  double change = 0;
  for (int i = 0; i < m; ++i) change += std::abs(best[i] - objective.filteredDepths()[i]);
  StageReport& r = result.report;
  r.add("layout", std::string("adam"));
  r.add("unknowns", std::int64_t{m});
  r.add("tangent_pixels", std::int64_t{objective.tangentPixels()});
  r.add("iterations", std::int64_t{options.iterations});
  r.add("learning_rate", options.learning_rate_m, "m");
  r.add("objective_initial", result.initial.total).add("objective_final", result.final.total);
  r.add("tangent_term_initial", result.initial.tangent).add("tangent_term_final", result.final.tangent);
  r.add("data_term_final", result.final.data, "m^2");
  r.add("mean_abs_change", m ? change / m : 0.0, "m");
  r.seconds = clock.seconds() - excluded;
  return result;
}

}  // namespace solo
