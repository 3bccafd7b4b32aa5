#include <solo/post/fog_glare.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>
#include <utility>
#include <vector>

namespace solo {

namespace {

// Cost model, nanoseconds on one core of the development machine (measured with
// tests/benchmarks/bench_post, see docs/post-processing.md). Only their ratio matters.
constexpr double kDirectNsPerTap = 0.35;          // one kernel tap added to 3 channels
constexpr double kFftNsPerPointLog2 = 0.55;       // one real FFT point times log2(points)
constexpr int kTransformsPerRegion = 7;           // 3 forward, 3 inverse, 1 kernel

const double kPi = std::acos(-1.0);

struct BrightPixel {
  int y, x;
  cv::Vec3f value;
};

struct Box {  // inclusive bounds; empty when y1 < y0
  int y0 = 1 << 30, x0 = 1 << 30, y1 = -1, x1 = -1;
  bool empty() const { return y1 < y0; }
  void include(int y, int x) {
    y0 = std::min(y0, y);
    x0 = std::min(x0, x);
    y1 = std::max(y1, y);
    x1 = std::max(x1, x);
  }
  cv::Rect rect() const { return {x0, y0, x1 - x0 + 1, y1 - y0 + 1}; }
};

/// FFT size along one axis so that a circular convolution of the inputs in [b0, b1] with a
/// kernel of radius r is exact on the outputs in [o0, o1]: a wrapped contribution lands at
/// distance >= N - r, so N - r must exceed every |output - input| distance.
int fftLength(int b0, int b1, int o0, int o1, int r) {
  const int farthest = std::max(o1 - b0, b1 - o0);
  return cv::getOptimalDFTSize(r + 1 + farthest);
}

struct FftPlan {
  cv::Rect bright, output;
  int rows = 0, cols = 0;
};

FftPlan planRegion(const Box& bright, const cv::Size& image, int r) {
  FftPlan plan;
  plan.bright = bright.rect();
  const int oy0 = std::max(0, bright.y0 - r), oy1 = std::min(image.height - 1, bright.y1 + r);
  const int ox0 = std::max(0, bright.x0 - r), ox1 = std::min(image.width - 1, bright.x1 + r);
  plan.output = {ox0, oy0, ox1 - ox0 + 1, oy1 - oy0 + 1};
  plan.rows = fftLength(bright.y0, bright.y1, oy0, oy1, r);
  plan.cols = fftLength(bright.x0, bright.x1, ox0, ox1, r);
  return plan;
}

double fftCostNs(const FftPlan& plan) {
  const double points = static_cast<double>(plan.rows) * plan.cols;
  return kTransformsPerRegion * kFftNsPerPointLog2 * points * std::log2(std::max(points, 2.0));
}

/// Spectra (CCS packed) of the kernel wrapped around the origin, by FFT size.
class KernelSpectra {
 public:
  explicit KernelSpectra(const cv::Mat& kernel) : kernel_(kernel) {}
  const cv::Mat& get(int rows, int cols) {
    auto found = cache_.find({rows, cols});
    if (found != cache_.end()) return found->second;
    const int centre = kernel_.rows / 2;
    cv::Mat wrapped = cv::Mat::zeros(rows, cols, CV_32F);
    for (int ky = 1; ky < kernel_.rows; ++ky) {
      const int wy = ((ky - centre) % rows + rows) % rows;
      const float* k = kernel_.ptr<float>(ky);
      float* w = wrapped.ptr<float>(wy);
      for (int kx = 1; kx < kernel_.cols; ++kx) w[((kx - centre) % cols + cols) % cols] += k[kx];
    }
    cv::Mat spectrum;
    cv::dft(wrapped, spectrum);
    return cache_.emplace(std::make_pair(rows, cols), spectrum).first->second;
  }

 private:
  cv::Mat kernel_;
  std::map<std::pair<int, int>, cv::Mat> cache_;
};

/// Convolves the bright pixels inside plan.bright with the kernel and adds the result to
/// the image over plan.output.
void convolveRegion(const cv::Mat& bright, const FftPlan& plan, KernelSpectra& spectra, cv::Mat& image) {
  const cv::Mat& spectrum = spectra.get(plan.rows, plan.cols);
  const int offset_y = plan.bright.y - plan.output.y, offset_x = plan.bright.x - plan.output.x;
  cv::parallel_for_(cv::Range(0, 3), [&](const cv::Range& channels) {
    for (int c = channels.start; c < channels.end; ++c) {
      cv::Mat buffer = cv::Mat::zeros(plan.rows, plan.cols, CV_32F);
      for (int y = 0; y < plan.bright.height; ++y) {
        const cv::Vec3f* src = bright.ptr<cv::Vec3f>(plan.bright.y + y) + plan.bright.x;
        float* dst = buffer.ptr<float>(offset_y + y) + offset_x;
        for (int x = 0; x < plan.bright.width; ++x) dst[x] = src[x][c];
      }
      cv::dft(buffer, buffer, 0, offset_y + plan.bright.height);
      cv::mulSpectrums(buffer, spectrum, buffer, 0);
      cv::dft(buffer, buffer, cv::DFT_INVERSE | cv::DFT_SCALE | cv::DFT_REAL_OUTPUT, plan.output.height);
      for (int y = 0; y < plan.output.height; ++y) {
        const float* src = buffer.ptr<float>(y);
        cv::Vec3f* dst = image.ptr<cv::Vec3f>(plan.output.y + y) + plan.output.x;
        for (int x = 0; x < plan.output.width; ++x) dst[x][c] += src[x];
      }
    }
  });
}

/// Adds kernel * value around every listed pixel; parallel over output rows.
void splatDirect(const std::vector<BrightPixel>& pixels, const cv::Mat& kernel, cv::Mat& image) {
  const int centre = kernel.rows / 2, r = centre - 1;
  cv::parallel_for_(cv::Range(0, image.rows), [&](const cv::Range& rows) {
    for (const BrightPixel& p : pixels) {
      const int y0 = std::max(rows.start, p.y - r), y1 = std::min(rows.end - 1, p.y + r);
      const int x0 = std::max(0, p.x - r), x1 = std::min(image.cols - 1, p.x + r);
      for (int y = y0; y <= y1; ++y) {
        const float* k = kernel.ptr<float>(y - p.y + centre) + (centre - p.x);
        cv::Vec3f* out = image.ptr<cv::Vec3f>(y);
        for (int x = x0; x <= x1; ++x) {
          const float w = k[x];
          out[x][0] += w * p.value[0];
          out[x][1] += w * p.value[1];
          out[x][2] += w * p.value[2];
        }
      }
    }
  });
}

const char* methodName(GlareMethod m) {
  switch (m) {
    case GlareMethod::Automatic: return "automatic";
    case GlareMethod::Direct: return "direct";
    case GlareMethod::Fft: return "fft";
    case GlareMethod::TiledFft: return "tiled-fft";
  }
  return "?";
}

/// The share of a bright pixel that the glare spreads: scatter x its luminance above the
/// threshold, in the pixel's colour.
struct Contribution {
  float threshold, scatter;
  cv::Vec3f operator()(const cv::Vec3f& p) const { return p * (scatter * (p[1] - threshold) / p[1]); }
};

/// Where the pixels brighter than the threshold lie: per row their count and luminance above
/// the threshold, per tile (side = kernel size) and over the whole image their extent.
struct BrightSurvey {
  std::vector<int> row_count;
  std::vector<double> row_energy;
  std::vector<Box> tiles;  // row-major, tiles_x per row
  Box all;
  std::int64_t count = 0;
  double bright_energy = 0;
};

BrightSurvey surveyBrightPixels(const cv::Mat& linear_xyz, float threshold, int tile) {
  BrightSurvey survey;
  // First pass, parallel over rows: per row the bright pixel count, its luminance above
  // the threshold, and per tile column the x extent.
  const int tiles_y = (linear_xyz.rows + tile - 1) / tile, tiles_x = (linear_xyz.cols + tile - 1) / tile;
  std::vector<int>& row_count = survey.row_count;
  std::vector<double>& row_energy = survey.row_energy;
  row_count.assign(linear_xyz.rows, 0);
  row_energy.assign(linear_xyz.rows, 0.0);
  std::vector<int> row_tile_x0(static_cast<std::size_t>(linear_xyz.rows) * tiles_x, 1 << 30);
  std::vector<int> row_tile_x1(static_cast<std::size_t>(linear_xyz.rows) * tiles_x, -1);
  cv::parallel_for_(cv::Range(0, linear_xyz.rows), [&](const cv::Range& rows) {
    for (int y = rows.start; y < rows.end; ++y) {
      const cv::Vec3f* src = linear_xyz.ptr<cv::Vec3f>(y);
      int* x0 = &row_tile_x0[static_cast<std::size_t>(y) * tiles_x];
      int* x1 = &row_tile_x1[static_cast<std::size_t>(y) * tiles_x];
      for (int x = 0; x < linear_xyz.cols; ++x) {
        if (!(src[x][1] > threshold)) continue;
        ++row_count[y];
        row_energy[y] += src[x][1] - threshold;
        const int t = x / tile;
        x0[t] = std::min(x0[t], x);
        x1[t] = std::max(x1[t], x);
      }
    }
  });
  // Second pass: the rows' extents gathered into the tiles' boxes and the whole image's.
  survey.tiles.resize(static_cast<std::size_t>(tiles_y) * tiles_x);
  for (int y = 0; y < linear_xyz.rows; ++y) {
    if (row_count[y] == 0) continue;
    survey.count += row_count[y];
    survey.bright_energy += row_energy[y];
    for (int t = 0; t < tiles_x; ++t) {
      const std::size_t i = static_cast<std::size_t>(y) * tiles_x + t;
      if (row_tile_x1[i] < 0) continue;
      for (const int x : {row_tile_x0[i], row_tile_x1[i]}) {
        survey.tiles[static_cast<std::size_t>(y / tile) * tiles_x + t].include(y, x);
        survey.all.include(y, x);
      }
    }
  }
  return survey;
}

/// The estimated costs of the three ways, their FFT plans, and the way chosen.
struct GlarePlan {
  double direct_ns = 0, fft_ns = 0, tiled_ns = 0;
  FftPlan whole;
  std::vector<FftPlan> tiled;
  GlareMethod method = GlareMethod::Automatic;
};

/// Costs of the three ways; Automatic takes the cheapest.
GlarePlan planGlare(const BrightSurvey& survey, const cv::Size& image, int r, GlareMethod requested) {
  GlarePlan plan;
  const double taps = static_cast<double>(std::min(2 * r + 1, image.height)) * std::min(2 * r + 1, image.width);
  plan.direct_ns = kDirectNsPerTap * taps * static_cast<double>(survey.count);
  plan.whole = planRegion(survey.all, image, r);
  plan.fft_ns = fftCostNs(plan.whole);
  for (const Box& b : survey.tiles)
    if (!b.empty()) {
      plan.tiled.push_back(planRegion(b, image, r));
      plan.tiled_ns += fftCostNs(plan.tiled.back());
    }
  plan.method = requested;
  if (plan.method == GlareMethod::Automatic) {
    plan.method = GlareMethod::Fft;
    double best = plan.fft_ns;
    if (plan.tiled.size() > 1 && plan.tiled_ns < best) plan.method = GlareMethod::TiledFft, best = plan.tiled_ns;
    if (plan.direct_ns < best) plan.method = GlareMethod::Direct;
  }
  return plan;
}

/// The bright pixels' contributions as an image (zero elsewhere), for the FFT ways.
cv::Mat brightContributions(const cv::Mat& linear_xyz, const BrightSurvey& survey, const Contribution& contribution) {
  cv::Mat bright = cv::Mat::zeros(linear_xyz.size(), CV_32FC3);
  cv::parallel_for_(cv::Range(0, linear_xyz.rows), [&](const cv::Range& rows) {
    for (int y = rows.start; y < rows.end; ++y) {
      if (survey.row_count[y] == 0) continue;
      const cv::Vec3f* src = linear_xyz.ptr<cv::Vec3f>(y);
      cv::Vec3f* dst = bright.ptr<cv::Vec3f>(y);
      for (int x = survey.all.x0; x <= survey.all.x1; ++x)
        if (src[x][1] > contribution.threshold) dst[x] = contribution(src[x]);
    }
  });
  return bright;
}

/// The bright pixels' contributions as a list, for the direct way.
std::vector<BrightPixel> listBrightPixels(const cv::Mat& linear_xyz, const BrightSurvey& survey,
                                          const Contribution& contribution) {
  std::vector<BrightPixel> listed;
  listed.reserve(static_cast<std::size_t>(survey.count));
  for (int y = survey.all.y0; y <= survey.all.y1; ++y) {
    if (survey.row_count[y] == 0) continue;
    const cv::Vec3f* src = linear_xyz.ptr<cv::Vec3f>(y);
    for (int x = survey.all.x0; x <= survey.all.x1; ++x)
      if (src[x][1] > contribution.threshold) listed.push_back({y, x, contribution(src[x])});
  }
  return listed;
}

}  // namespace

cv::Mat fogGlowKernel(int size) {
  if (size < 2 || size > 11) throw std::invalid_argument("glare size must be between 2 and 11");
  const int n = 1 << size;
  const double scale = n / 4.0;
  cv::Mat kernel(n, n, CV_32F);
  std::vector<double> u(n), hann(n);
  for (int i = 0; i < n; ++i) {
    u[i] = 2.0 * i / n - 1.0;
    hann[i] = 0.5 + 0.5 * std::cos(kPi * u[i]);
  }
  double sum = 0;
  cv::Mat_<double> values(n, n);
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      const double rr = (u[x] * u[x] + u[y] * u[y]) * scale;
      values(y, x) = std::exp(-9.0 * std::pow(rr, 0.125)) * hann[x] * hann[y];
      sum += values(y, x);
    }
  values.convertTo(kernel, CV_32F, 1.0 / sum);
  return kernel;
}

StageReport applyFogGlare(cv::Mat& linear_xyz, const FogGlareOptions& options) {
  Stopwatch clock;
  StageReport report;
  report.name = "glare";
  CV_Assert(linear_xyz.type() == CV_32FC3);
  if (!(options.threshold >= 0 && std::isfinite(options.threshold)))
    throw std::invalid_argument("glare threshold must be a finite luminance >= 0");
  if (!(options.scatter_fraction > 0 && options.scatter_fraction <= 1))
    throw std::invalid_argument("glare scatter fraction must be in (0, 1]");
  const cv::Mat kernel = fogGlowKernel(options.size);
  const int n = kernel.rows, r = n / 2 - 1;
  const float threshold = static_cast<float>(options.threshold);
  report.add("kernel_size", static_cast<std::int64_t>(n), "px")
      .add("threshold", options.threshold)
      .add("scatter_fraction", options.scatter_fraction);

  const BrightSurvey survey = surveyBrightPixels(linear_xyz, threshold, n);
  const double pixels = static_cast<double>(linear_xyz.total());
  report.add("bright_pixels", survey.count);
  report.add("bright_fraction", pixels > 0 ? static_cast<double>(survey.count) / pixels : 0.0);
  if (survey.count == 0) {
    report.skipped = true;
    report.skip_reason = "no pixel brighter than the threshold (luminance Y > " + std::to_string(options.threshold) +
                         "): the image is unchanged";
    report.seconds = clock.seconds();
    return report;
  }

  const GlarePlan plan = planGlare(survey, linear_xyz.size(), r, options.method);
  const double energy_before = cv::sum(linear_xyz)[1];
  const Contribution contribution{threshold, static_cast<float>(options.scatter_fraction)};
  KernelSpectra spectra(kernel);
  if (plan.method == GlareMethod::Direct) {
    splatDirect(listBrightPixels(linear_xyz, survey, contribution), kernel, linear_xyz);
  } else if (plan.method == GlareMethod::Fft) {
    convolveRegion(brightContributions(linear_xyz, survey, contribution), plan.whole, spectra, linear_xyz);
    report.add("fft_rows", static_cast<std::int64_t>(plan.whole.rows), "px")
        .add("fft_cols", static_cast<std::int64_t>(plan.whole.cols), "px");
  } else {
    // The contributions add into the image region by region.
    const cv::Mat bright = brightContributions(linear_xyz, survey, contribution);
    for (const FftPlan& region : plan.tiled) convolveRegion(bright, region, spectra, linear_xyz);
    report.add("fft_regions", static_cast<std::int64_t>(plan.tiled.size()));
  }
  const double glow_energy = cv::sum(linear_xyz)[1] - energy_before;
  report.add("method", std::string(methodName(plan.method)));
  report.add("estimated_direct_ms", plan.direct_ns * 1e-6, "ms");
  report.add("estimated_fft_ms", plan.fft_ns * 1e-6, "ms");
  report.add("estimated_tiled_fft_ms", plan.tiled_ns * 1e-6, "ms");
  report.add("glow_in_frame_fraction",
             survey.bright_energy > 0 ? glow_energy / (options.scatter_fraction * survey.bright_energy) : 0.0);
  report.seconds = clock.seconds();
  return report;
}

}  // namespace solo
