#include <solo/render/sensor_noise.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <random>
#include <stdexcept>
#include <string>

namespace solo {

const std::vector<NoiseCalibration>& referenceNoiseCalibration() {
  static const std::vector<NoiseCalibration> table = {
      {100, 0.141, -8.8},    {200, 0.2835, -17.9},   {400, 0.5615, -35.5},
      {800, 1.1175, -69.6},  {1600, 2.225, -132.8},  {3200, 4.245, -231.0},
  };
  return table;
}

NoiseCalibration noiseCalibrationAtIso(double iso) {
  const auto& table = referenceNoiseCalibration();
  if (!(iso >= table.front().iso && iso <= table.back().iso))
    throw std::invalid_argument("ISO " + std::to_string(iso) + " is outside the calibrated range " +
                                std::to_string(static_cast<int>(table.front().iso)) + " to " +
                                std::to_string(static_cast<int>(table.back().iso)));
  std::size_t i = 1;
  while (i + 1 < table.size() && table[i].iso < iso) ++i;
  const NoiseCalibration& a = table[i - 1];
  const NoiseCalibration& b = table[i];
  const double t = (iso - a.iso) / (b.iso - a.iso);
  return {iso, a.beta1 + t * (b.beta1 - a.beta1), a.beta2 + t * (b.beta2 - a.beta2)};
}

namespace {

void validate(const SensorNoiseOptions& o) {
  if (!(o.black_level >= 0 && o.white_level > o.black_level))
    throw std::invalid_argument("sensor levels need 0 <= black level < white level");
  if (!(o.std_scale >= 0 && std::isfinite(o.std_scale)))
    throw std::invalid_argument("noise scale must be non-negative");
}

double varianceWithoutRounding(double raw_counts, const NoiseCalibration& c, const SensorNoiseOptions& o) {
  const double level = std::clamp(raw_counts, 0.0, static_cast<double>(o.white_level));
  return o.std_scale * o.std_scale * std::max(0.0, c.beta1 * level + c.beta2);
}

}  // namespace

double noiseVarianceCounts(double raw_counts, const SensorNoiseOptions& options) {
  validate(options);
  return varianceWithoutRounding(raw_counts, noiseCalibrationAtIso(options.iso), options) +
         (options.quantise ? 1.0 / 12.0 : 0.0);
}

double noiseVarianceRenderUnits(double render_value, double exposure_scale, const SensorNoiseOptions& options) {
  validate(options);
  const double range = options.white_level - options.black_level;
  const double counts = options.black_level + render_value * exposure_scale * range;
  const double per_count = 1.0 / (range * exposure_scale);
  return varianceWithoutRounding(counts, noiseCalibrationAtIso(options.iso), options) * per_count * per_count;
}

cv::Mat noiseVarianceRenderUnits(const cv::Mat& render, double exposure_scale, const SensorNoiseOptions& options) {
  CV_Assert(render.depth() == CV_32F);
  validate(options);
  const NoiseCalibration c = noiseCalibrationAtIso(options.iso);
  const double range = options.white_level - options.black_level;
  const double per_count = 1.0 / (range * exposure_scale);
  cv::Mat variance(render.size(), render.type());
  for (int y = 0; y < render.rows; ++y) {
    const float* src = render.ptr<float>(y);
    float* dst = variance.ptr<float>(y);
    for (int i = 0; i < render.cols * render.channels(); ++i) {
      const double counts = options.black_level + src[i] * exposure_scale * range;
      dst[i] = static_cast<float>(varianceWithoutRounding(counts, c, options) * per_count * per_count);
    }
  }
  return variance;
}

std::function<double(double)> sensorNoiseSigma(double render_to_input, double exposure_scale,
                                               const SensorNoiseOptions& options) {
  validate(options);
  if (!(render_to_input > 0 && std::isfinite(render_to_input) && exposure_scale > 0 && std::isfinite(exposure_scale)))
    throw std::invalid_argument("noise sigma needs positive, finite render and exposure scales");
  const NoiseCalibration c = noiseCalibrationAtIso(options.iso);
  const double range = options.white_level - options.black_level;
  const double per_count = 1.0 / (range * exposure_scale * render_to_input);
  return [=](double y) {
    const double counts = options.black_level + y * render_to_input * exposure_scale * range;
    return std::sqrt(varianceWithoutRounding(counts, c, options)) * per_count;
  };
}

StageReport applySensorNoise(cv::Mat& exposed_linear, const SensorNoiseOptions& options) {
  Stopwatch clock;
  CV_Assert(exposed_linear.type() == CV_32FC3);
  validate(options);
  StageReport report;
  report.name = "noise";
  const NoiseCalibration c = noiseCalibrationAtIso(options.iso);
  const double black = options.black_level, white = options.white_level, range = white - black;
  std::atomic<std::int64_t> clipped_low{0}, clipped_high{0};
  cv::parallel_for_(cv::Range(0, exposed_linear.rows), [&](const cv::Range& rows) {
    std::int64_t low = 0, high = 0;
    for (int y = rows.start; y < rows.end; ++y) {
      // One generator per row, seeded by (seed, row): results do not depend on threading.
      std::seed_seq seq{static_cast<std::uint32_t>(options.seed), static_cast<std::uint32_t>(options.seed >> 32),
                        static_cast<std::uint32_t>(y)};
      std::mt19937_64 engine(seq);
      std::normal_distribution<double> gauss(0.0, 1.0);
      float* p = exposed_linear.ptr<float>(y);
      for (int i = 0; i < exposed_linear.cols * 3; ++i) {
        const double level = black + p[i] * range;
        double noisy = level + std::sqrt(varianceWithoutRounding(level, c, options)) * gauss(engine);
        if (options.quantise) noisy = std::round(noisy);
        if (options.clip) {
          if (noisy < 0) noisy = 0, ++low;
          else if (noisy > white) noisy = white, ++high;
        }
        p[i] = static_cast<float>((noisy - black) / range);
      }
    }
    clipped_low += low;
    clipped_high += high;
  });
  SensorNoiseOptions no_rounding = options;
  no_rounding.quantise = false;
  report.add("iso", options.iso);
  report.add("beta1", c.beta1);
  report.add("beta2", c.beta2);
  report.add("std_scale", options.std_scale);
  report.add("seed", static_cast<std::int64_t>(options.seed));
  report.add("std_at_black_level", std::sqrt(noiseVarianceCounts(black, no_rounding)), "counts");
  report.add("std_at_mid_grey", std::sqrt(noiseVarianceCounts(black + 0.18 * range, no_rounding)), "counts");
  const std::int64_t low_count = clipped_low.load(), high_count = clipped_high.load();
  report.add("clipped_at_zero", low_count);
  report.add("clipped_at_white", high_count);
  report.seconds = clock.seconds();
  return report;
}

}  // namespace solo
