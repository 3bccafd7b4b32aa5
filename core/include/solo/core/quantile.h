#pragma once
// Sample quantiles for the evaluation metrics, defined as NumPy's default
// (numpy.quantile / numpy.median, "linear" method) so numbers match Python scripts.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

namespace solo {

/// q-quantile (q in [0, 1]) of `values`: sorted values v[0..n-1], position h = q * (n - 1),
/// result v[floor h] + (h - floor h) * (v[floor h + 1] - v[floor h]). The median is q = 0.5
/// (the mean of the two middle values for even n). Reorders `values`; n must be > 0.
inline double sampleQuantile(std::vector<double>& values, double q) {
  const std::size_t n = values.size();
  const double position = std::clamp(q, 0.0, 1.0) * static_cast<double>(n - 1);
  const std::size_t below = static_cast<std::size_t>(std::floor(position));
  const double fraction = position - static_cast<double>(below);
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(below), values.end());
  const double lower = values[below];
  if (fraction == 0.0 || below + 1 >= n) return lower;
  // The next order statistic is the smallest value above position `below`.
  const double upper = *std::min_element(values.begin() + static_cast<std::ptrdiff_t>(below) + 1, values.end());
  return lower + fraction * (upper - lower);
}

}  // namespace solo
