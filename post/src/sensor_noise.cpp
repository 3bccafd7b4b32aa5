#include <solo/post/chromatic_adaptation.h>
#include <solo/post/sensor_noise.h>

#include <solo/core/srgb.h>

#include <opencv2/imgproc.hpp>

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
  if (!(o.chroma_denoise_sigma_px >= 0 && o.chroma_denoise_sigma_px <= 100))
    throw std::invalid_argument("chroma denoise sigma must be in [0, 100] px");
  if (!(o.chroma_denoise_strength >= 0 && o.chroma_denoise_strength <= 1))
    throw std::invalid_argument("chroma denoise strength must be in [0, 1]");
}

double varianceWithoutRounding(double raw_counts, const NoiseCalibration& c, const SensorNoiseOptions& o) {
  const double level = std::clamp(raw_counts, 0.0, static_cast<double>(o.white_level));
  return o.std_scale * o.std_scale * std::max(0.0, c.beta1 * level + c.beta2);
}

/// RGGB: the colour (0 R, 1 G, 2 B) of the photosite at (row, col); (0, 0) is red.
int bayerChannel(int row, int col) { return (row & 1) + (col & 1); }

/// Bilinear demosaicking of one colour's sparse plane (zeros between its photosites): green
/// averages its 4 direct neighbours, red and blue their 2 or 4 nearest photosites.
cv::Matx33d demosaicKernel(int channel) {
  if (channel == 1) return {0, 0.25, 0, 0.25, 1, 0.25, 0, 0.25, 0};
  return {0.25, 0.5, 0.25, 0.5, 1, 0.5, 0.25, 0.5, 0.25};
}

/// Whether the pixel at (row, col) holds a sample of `channel` before demosaicking.
bool samples(int row, int col, int channel, bool demosaic) {
  return !demosaic || bayerChannel(row, col) == channel;
}

/// The weights a channel's output at pixel (py, px) of phase 0-1 gives to the samples around
/// it, for a filter `outer` applied after demosaicking: the 5x5 kernel outer * K, with the
/// offsets that hold no sample of the channel zeroed.
double squaredWeightSum(int py, int px, int channel, const cv::Matx33d& outer, const SensorNoiseOptions& o) {
  const cv::Matx33d inner = o.demosaic ? demosaicKernel(channel) : cv::Matx33d(0, 0, 0, 0, 1, 0, 0, 0, 0);
  double sum = 0;
  for (int dy = -2; dy <= 2; ++dy)
    for (int dx = -2; dx <= 2; ++dx) {
      if (!samples(py + dy + 2, px + dx + 2, channel, o.demosaic)) continue;  // +2 keeps the parity
      double weight = 0;
      for (int ay = -1; ay <= 1; ++ay)
        for (int ax = -1; ax <= 1; ++ax) {
          const int by = dy - ay, bx = dx - ax;
          if (std::abs(by) <= 1 && std::abs(bx) <= 1) weight += outer(ay + 1, ax + 1) * inner(by + 1, bx + 1);
        }
      sum += weight * weight;
    }
  return sum;
}

/// Variance of `outer` applied to the luminance noise at a pixel of phase (py, px), per unit
/// photosite variance of a grey image.
double phaseVariance(int py, int px, const cv::Matx33d& outer, const SensorNoiseOptions& o) {
  const cv::Vec3d w = linearSrgbLuminanceWeights();
  double v = 0;
  for (int c = 0; c < 3; ++c) v += w[c] * w[c] * squaredWeightSum(py, px, c, outer, o);
  return v;
}

const cv::Matx33d kIdentity(0, 0, 0, 0, 1, 0, 0, 0, 0);
/// The realism statistic's high-pass: the pixel minus the mean of its 4 neighbours.
const cv::Matx33d kHighPass(0, -0.25, 0, -0.25, 1, -0.25, 0, -0.25, 0);

double transferSlope(double linear, TransferCurve curve) {
  switch (curve) {
    case TransferCurve::Gamma22: return std::pow(linear, 1 / 2.2 - 1) / 2.2;
    case TransferCurve::Srgb: return linearToSrgbSlope(linear);
    case TransferCurve::Linear: return 1;
  }
  return 1;
}

/// 1.4826 x the median of |h| for h a mixture, in equal shares, of zero-mean Gaussians of the
/// given standard deviations (bisection on the mixture's distribution function).
double robustSigma(const std::vector<double>& sigmas) {
  auto below = [&](double m) {
    double share = 0;
    for (double s : sigmas) share += s > 0 ? std::erf(m / (s * std::sqrt(2.0))) : 1.0;
    return share / static_cast<double>(sigmas.size());
  };
  double lo = 0, hi = 10 * *std::max_element(sigmas.begin(), sigmas.end()) + 1e-12;
  for (int i = 0; i < 100; ++i) {
    const double mid = 0.5 * (lo + hi);
    (below(mid) < 0.5 ? lo : hi) = mid;
  }
  return 1.482602218505602 * 0.5 * (lo + hi);
}

}  // namespace

cv::Matx33d cameraRgbFromXyzE() { return xyzToLinearSrgbMatrix() * bradfordAdaptation(kWhitePointE, kWhitePointD65); }

double noiseVarianceCounts(double raw_counts, const SensorNoiseOptions& options) {
  validate(options);
  return varianceWithoutRounding(raw_counts, noiseCalibrationAtIso(options.iso), options) +
         (options.quantise ? 1.0 / 12.0 : 0.0);
}

double lumaVarianceFactor(const SensorNoiseOptions& options) {
  validate(options);
  double sum = 0;
  for (int py = 0; py < 2; ++py)
    for (int px = 0; px < 2; ++px) sum += phaseVariance(py, px, kIdentity, options);
  return sum / 4;
}

double noiseVarianceRenderUnits(double render_value, double exposure_scale, const SensorNoiseOptions& options) {
  const double factor = lumaVarianceFactor(options);
  const double range = options.white_level - options.black_level;
  const double counts = options.black_level + render_value * exposure_scale * range;
  const double per_count = 1.0 / (range * exposure_scale);
  return factor * varianceWithoutRounding(counts, noiseCalibrationAtIso(options.iso), options) * per_count * per_count;
}

cv::Mat noiseVarianceRenderUnits(const cv::Mat& render, double exposure_scale, const SensorNoiseOptions& options) {
  CV_Assert(render.type() == CV_32FC3);
  validate(options);
  const NoiseCalibration c = noiseCalibrationAtIso(options.iso);
  const double range = options.white_level - options.black_level;
  const double per_count = 1.0 / (range * exposure_scale);
  // Per channel: w_c^2 times the phase-averaged squared demosaicking weights.
  cv::Vec3d channel_factor;
  const cv::Vec3d w = linearSrgbLuminanceWeights();
  for (int ch = 0; ch < 3; ++ch) {
    double sum = 0;
    for (int py = 0; py < 2; ++py)
      for (int px = 0; px < 2; ++px) sum += squaredWeightSum(py, px, ch, kIdentity, options);
    channel_factor[ch] = w[ch] * w[ch] * sum / 4;
  }
  cv::Mat camera;
  cv::transform(render, camera, cv::Matx33f(cameraRgbFromXyzE()));
  cv::Mat variance(render.size(), CV_32FC1);
  for (int y = 0; y < render.rows; ++y) {
    const cv::Vec3f* src = camera.ptr<cv::Vec3f>(y);
    float* dst = variance.ptr<float>(y);
    for (int x = 0; x < render.cols; ++x) {
      double v = 0;
      for (int ch = 0; ch < 3; ++ch)
        v += channel_factor[ch] * varianceWithoutRounding(options.black_level + src[x][ch] * exposure_scale * range, c, options);
      dst[x] = static_cast<float>(v * per_count * per_count);
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
  const double factor = lumaVarianceFactor(options);
  const double range = options.white_level - options.black_level;
  const double per_count = 1.0 / (range * exposure_scale * render_to_input);
  return [=](double y) {
    const double counts = options.black_level + y * render_to_input * exposure_scale * range;
    return std::sqrt(factor * varianceWithoutRounding(counts, c, options)) * per_count;
  };
}

double predictedLumaNoise8Bit(double exposed_linear, const SensorNoiseOptions& options, TransferCurve curve) {
  validate(options);
  if (!(exposed_linear > 0 && exposed_linear < 1))
    throw std::invalid_argument("predicted luma noise needs a linear level in (0, 1)");
  const double range = options.white_level - options.black_level;
  const double site_variance = noiseVarianceCounts(options.black_level + exposed_linear * range, options);
  const double codes_per_count = 255.0 * transferSlope(exposed_linear, curve) / range;
  // 8-bit rounding of R', G', B': variance (0.299^2 + 0.587^2 + 0.114^2) / 12 in Y', and the
  // high-pass multiplies independent per-pixel variance by 1 + 4 / 16.
  const double rounding = 1.25 * (0.299 * 0.299 + 0.587 * 0.587 + 0.114 * 0.114) / 12.0;
  std::vector<double> sigmas;
  for (int py = 0; py < 2; ++py)
    for (int px = 0; px < 2; ++px)
      sigmas.push_back(std::sqrt(phaseVariance(py, px, kHighPass, options) * site_variance *
                                     codes_per_count * codes_per_count + rounding));
  return robustSigma(sigmas) / std::sqrt(1.25);
}

namespace {

struct ClipCounts {
  std::int64_t low = 0, high = 0;
};

/// Raw noise per photosite in counts, one sparse CV_32F plane per camera channel (zero where
/// the mosaic has no photosite of that colour): the noisy, rounded, clipped raw value minus
/// the clean raw level (clipped the same way). One generator per row seeded by (seed, row).
ClipCounts sampleRawNoise(const cv::Mat& xyz_e, const SensorNoiseOptions& o, std::vector<cv::Mat>& planes) {
  const NoiseCalibration c = noiseCalibrationAtIso(o.iso);
  const cv::Matx33d to_camera = cameraRgbFromXyzE();
  const double black = o.black_level, white = o.white_level, range = white - black;
  planes.assign(3, cv::Mat());
  for (cv::Mat& plane : planes) plane = cv::Mat::zeros(xyz_e.size(), CV_32F);
  std::atomic<std::int64_t> clipped_low{0}, clipped_high{0};
  cv::parallel_for_(cv::Range(0, xyz_e.rows), [&](const cv::Range& rows) {
    std::int64_t low = 0, high = 0;
    for (int y = rows.start; y < rows.end; ++y) {
      std::seed_seq seq{static_cast<std::uint32_t>(o.seed), static_cast<std::uint32_t>(o.seed >> 32),
                        static_cast<std::uint32_t>(y)};
      std::mt19937_64 engine(seq);
      std::normal_distribution<double> gauss(0.0, 1.0);
      const cv::Vec3f* p = xyz_e.ptr<cv::Vec3f>(y);
      for (int x = 0; x < xyz_e.cols; ++x)
        for (int ch = 0; ch < 3; ++ch) {
          if (!samples(y, x, ch, o.demosaic)) continue;
          const double camera = to_camera(ch, 0) * p[x][0] + to_camera(ch, 1) * p[x][1] + to_camera(ch, 2) * p[x][2];
          const double level = black + camera * range;
          double noisy = level + std::sqrt(varianceWithoutRounding(level, c, o)) * gauss(engine);
          double clean = level;
          if (o.quantise) noisy = std::round(noisy);
          if (o.clip) {
            clean = std::clamp(level, 0.0, white);
            if (noisy < 0) noisy = 0, ++low;
            else if (noisy > white) noisy = white, ++high;
          }
          planes[ch].ptr<float>(y)[x] = static_cast<float>(noisy - clean);
        }
    }
    clipped_low += low;
    clipped_high += high;
  });
  return {clipped_low.load(), clipped_high.load()};
}

/// Bilinear demosaicking of the three sparse planes, in place (one scratch plane).
void demosaic(std::vector<cv::Mat>& planes) {
  cv::Mat scratch;
  for (int ch = 0; ch < 3; ++ch) {
    cv::filter2D(planes[ch], scratch, CV_32F, cv::Mat(demosaicKernel(ch)), cv::Point(-1, -1), 0,
                 cv::BORDER_REFLECT_101);  // the reflection keeps the mosaic's parity at the borders
    std::swap(planes[ch], scratch);
  }
}

/// R, G, B planes to R - Y, Y, B - Y in place, Y the linear sRGB luminance.
void toColourDifferences(std::vector<cv::Mat>& planes) {
  const cv::Vec3f w = linearSrgbLuminanceWeights();
  cv::parallel_for_(cv::Range(0, planes[0].rows), [&](const cv::Range& rows) {
    for (int y = rows.start; y < rows.end; ++y) {
      float *r = planes[0].ptr<float>(y), *g = planes[1].ptr<float>(y), *b = planes[2].ptr<float>(y);
      for (int x = 0; x < planes[0].cols; ++x) {
        const float luma = w[0] * r[x] + w[1] * g[x] + w[2] * b[x];
        r[x] -= luma;
        g[x] = luma;
        b[x] -= luma;
      }
    }
  });
}

struct NoiseSigmas {
  double luma = 0, chroma_before = 0, chroma_after = 0;
};

double standardDeviation(const cv::Mat& plane) {
  cv::Scalar mean, sd;
  cv::meanStdDev(plane, mean, sd);
  return sd[0];
}

/// The mean standard deviation of the colour differences of (R - Y, Y, B - Y) planes.
double chromaSigma(const std::vector<cv::Mat>& differences) {
  return 0.5 * (standardDeviation(differences[0]) + standardDeviation(differences[2]));
}

/// The chroma noise reduction on (R - Y, Y, B - Y) planes, in place: the colour differences
/// replaced by (1 - strength) x themselves + strength x their Gaussian-smoothed version, Y kept.
void smoothColourDifferences(std::vector<cv::Mat>& differences, const SensorNoiseOptions& o) {
  if (o.chroma_denoise_sigma_px <= 0 || o.chroma_denoise_strength <= 0) return;
  cv::Mat smooth;
  for (const int k : {0, 2}) {
    cv::GaussianBlur(differences[k], smooth, cv::Size(), o.chroma_denoise_sigma_px, o.chroma_denoise_sigma_px,
                     cv::BORDER_REFLECT_101);
    cv::addWeighted(differences[k], 1 - o.chroma_denoise_strength, smooth, o.chroma_denoise_strength, 0, differences[k]);
  }
}

/// The camera's chroma noise reduction of the linear noise. Returns the luminance and
/// colour-difference sigmas, counts.
NoiseSigmas reduceChromaNoise(std::vector<cv::Mat>& differences, const SensorNoiseOptions& o) {
  NoiseSigmas sigmas;
  sigmas.luma = standardDeviation(differences[1]);
  sigmas.chroma_before = chromaSigma(differences);
  smoothColourDifferences(differences, o);
  sigmas.chroma_after = chromaSigma(differences);
  return sigmas;
}

/// Adds the noise given as (R - Y, Y, B - Y) planes in raw counts to the XYZ (white E) image.
void addNoise(cv::Mat& xyz_e, const std::vector<cv::Mat>& differences, double range) {
  const cv::Vec3f w = linearSrgbLuminanceWeights();
  const cv::Matx33f to_xyz = cameraRgbFromXyzE().inv() * (1.0 / range);
  cv::parallel_for_(cv::Range(0, xyz_e.rows), [&](const cv::Range& rows) {
    for (int y = rows.start; y < rows.end; ++y) {
      const float *cr = differences[0].ptr<float>(y), *luma = differences[1].ptr<float>(y),
                  *cb = differences[2].ptr<float>(y);
      cv::Vec3f* p = xyz_e.ptr<cv::Vec3f>(y);
      for (int x = 0; x < xyz_e.cols; ++x) {
        const float r = luma[x] + cr[x], b = luma[x] + cb[x];
        const cv::Vec3f rgb{r, (luma[x] - w[0] * r - w[2] * b) / w[1], b};
        p[x] += to_xyz * rgb;
      }
    }
  });
}

}  // namespace

StageReport applySensorNoise(cv::Mat& exposed_linear, const SensorNoiseOptions& options) {
  Stopwatch clock;
  CV_Assert(exposed_linear.type() == CV_32FC3);
  validate(options);
  StageReport report;
  report.name = "noise";
  std::vector<cv::Mat> planes;
  const ClipCounts clipped = sampleRawNoise(exposed_linear, options, planes);
  if (options.demosaic) demosaic(planes);
  toColourDifferences(planes);
  const NoiseSigmas sigmas = reduceChromaNoise(planes, options);
  const double range = options.white_level - options.black_level;
  addNoise(exposed_linear, planes, range);

  const NoiseCalibration c = noiseCalibrationAtIso(options.iso);
  SensorNoiseOptions no_rounding = options;
  no_rounding.quantise = false;
  const double black = options.black_level, mid_grey = black + 0.18 * range;
  const double luma_factor = lumaVarianceFactor(options);
  report.add("iso", options.iso).add("beta1", c.beta1).add("beta2", c.beta2);
  report.add("std_scale", options.std_scale).add("seed", static_cast<std::int64_t>(options.seed));
  report.add("mosaic", std::string(options.demosaic ? "RGGB, bilinear demosaicking" : "none (R, G, B per pixel)"));
  report.add("chroma_denoise_sigma", options.chroma_denoise_sigma_px, "px");
  report.add("chroma_denoise_strength", options.chroma_denoise_strength);
  report.add("std_at_black_level", std::sqrt(noiseVarianceCounts(black, no_rounding)), "counts");
  report.add("std_at_mid_grey", std::sqrt(noiseVarianceCounts(mid_grey, no_rounding)), "counts");
  report.add("luma_std_at_black_level", std::sqrt(luma_factor * noiseVarianceCounts(black, options)) / range, "linear");
  report.add("luma_std_at_mid_grey", std::sqrt(luma_factor * noiseVarianceCounts(mid_grey, options)) / range, "linear");
  report.add("added_luma_std", sigmas.luma / range, "linear");
  report.add("added_chroma_std", sigmas.chroma_after / range, "linear");
  report.add("added_chroma_std_before_denoise", sigmas.chroma_before / range, "linear");
  report.add("clipped_at_zero", clipped.low);
  report.add("clipped_at_white", clipped.high);
  report.seconds = clock.seconds();
  return report;
}

namespace {

constexpr float kLumaR = 0.299f, kLumaG = 0.587f, kLumaB = 0.114f;  // Y' as JPEG and the realism statistics take it

/// The encoded noise noisy - clean as (R' - Y', Y', B' - Y') planes.
std::vector<cv::Mat> encodedNoiseDifferences(const cv::Mat& noisy_encoded, const cv::Mat& clean_encoded) {
  std::vector<cv::Mat> planes(3);
  for (cv::Mat& plane : planes) plane.create(noisy_encoded.size(), CV_32F);
  cv::parallel_for_(cv::Range(0, noisy_encoded.rows), [&](const cv::Range& rows) {
    for (int y = rows.start; y < rows.end; ++y) {
      const cv::Vec3f *noisy = noisy_encoded.ptr<cv::Vec3f>(y), *clean = clean_encoded.ptr<cv::Vec3f>(y);
      float *cr = planes[0].ptr<float>(y), *luma = planes[1].ptr<float>(y), *cb = planes[2].ptr<float>(y);
      for (int x = 0; x < noisy_encoded.cols; ++x) {
        const cv::Vec3f n = noisy[x] - clean[x];
        luma[x] = kLumaR * n[0] + kLumaG * n[1] + kLumaB * n[2];
        cr[x] = n[0] - luma[x];
        cb[x] = n[2] - luma[x];
      }
    }
  });
  return planes;
}

/// noisy = clean + the noise given as (R' - Y', Y', B' - Y') planes, within [0, 1], where the
/// pixel had noise of its own.
void replaceEncodedNoise(cv::Mat& noisy_encoded, const cv::Mat& clean_encoded, const std::vector<cv::Mat>& planes) {
  cv::parallel_for_(cv::Range(0, noisy_encoded.rows), [&](const cv::Range& rows) {
    for (int y = rows.start; y < rows.end; ++y) {
      const cv::Vec3f* clean = clean_encoded.ptr<cv::Vec3f>(y);
      cv::Vec3f* noisy = noisy_encoded.ptr<cv::Vec3f>(y);
      const float *cr = planes[0].ptr<float>(y), *luma = planes[1].ptr<float>(y), *cb = planes[2].ptr<float>(y);
      for (int x = 0; x < noisy_encoded.cols; ++x) {
        // A pixel without noise of its own (saturated photosites, black clipped) keeps its
        // value: the neighbours' smoothed colour differences would tint a clipped lamp.
        if (noisy[x] == clean[x]) continue;
        const float r = luma[x] + cr[x], b = luma[x] + cb[x];
        const float g = (luma[x] - kLumaR * r - kLumaB * b) / kLumaG;
        const cv::Vec3f reduced = clean[x] + cv::Vec3f(r, g, b);
        for (int k = 0; k < 3; ++k) noisy[x][k] = std::clamp(reduced[k], 0.0f, 1.0f);
      }
    }
  });
}

}  // namespace

StageReport reduceEncodedChromaNoise(cv::Mat& noisy_encoded, const cv::Mat& clean_encoded,
                                     const SensorNoiseOptions& options) {
  Stopwatch clock;
  CV_Assert(noisy_encoded.type() == CV_32FC3 && clean_encoded.type() == CV_32FC3 &&
            noisy_encoded.size() == clean_encoded.size());
  validate(options);
  std::vector<cv::Mat> planes = encodedNoiseDifferences(noisy_encoded, clean_encoded);
  const double before_codes = 255.0 * chromaSigma(planes);
  smoothColourDifferences(planes, options);
  replaceEncodedNoise(noisy_encoded, clean_encoded, planes);
  StageReport report;
  report.name = "chroma";
  report.add("sigma_px", options.chroma_denoise_sigma_px, "px");
  report.add("strength", options.chroma_denoise_strength);
  report.add("noise_chroma_std_before", before_codes, "codes");
  report.add("noise_chroma_std_after", 255.0 * chromaSigma(planes), "codes");
  report.seconds = clock.seconds();
  return report;
}

}  // namespace solo
