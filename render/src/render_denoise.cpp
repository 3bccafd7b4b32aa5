// Edge-aware, AOV-guided filtering of a path-traced render (render_denoise.h).

#include "solo/render/render_denoise.h"

#include "map_checks.h"

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace solo {

namespace {

// The 5-tap cubic B-spline of the a-trous transform.
constexpr std::array<float, 5> kSpline = {1.f / 16, 1.f / 4, 3.f / 8, 1.f / 4, 1.f / 16};

// What the weights read, per pixel.
struct Guides {
  cv::Mat filtered;    // CV_8U: 1 = filtered and used as a neighbour
  cv::Mat point_m;     // CV_32FC3 first-hit point, camera frame, metres
  cv::Mat normal;      // CV_32FC3 unit normal
  cv::Mat depth_m;     // CV_32F z-depth, metres
  cv::Mat log_albedo;  // CV_32F ln of the demodulation albedo's Y (filled by demodulationAlbedo)
};

// The irradiance being filtered and the variance of its Y (empty: no luminance weight).
struct Estimate {
  cv::Mat irradiance;  // CV_32FC3
  cv::Mat variance;    // CV_32F
};

struct PixelCounts {
  std::int64_t filtered = 0, emitter = 0, no_surface = 0;
};

void validate(const RenderOutput& r, const PinholeCamera& camera, const RenderDenoiseOptions& o) {
  if (r.radiance.empty() || r.radiance.type() != CV_32FC3)
    throw std::invalid_argument("denoiseRender: the render's radiance must be a non-empty CV_32FC3 image");
  if (r.depth_m.empty() || r.normal.empty())
    throw std::invalid_argument("denoiseRender: the render needs its depth_m and normal AOVs");
  const cv::Size size = r.radiance.size();
  requireEmptyOrSized({{&r.albedo, CV_32FC3, "the render's albedo AOV"},
                       {&r.normal, CV_32FC3, "the render's normal AOV"},
                       {&r.depth_m, CV_32F, "the render's depth_m AOV"},
                       {&r.std_error, CV_32F, "the render's std_error AOV"},
                       {&r.light_id, CV_32S, "the render's light_id AOV"},
                       {&r.emitter_coverage, CV_32F, "the render's emitter_coverage AOV"}},
                      size, "denoiseRender");
  if (camera.width != size.width || camera.height != size.height)
    throw std::invalid_argument("denoiseRender: the camera is " + std::to_string(camera.width) + "x" +
                                std::to_string(camera.height) + ", the render " + std::to_string(size.width) + "x" +
                                std::to_string(size.height));
  if (o.iterations < 1 || o.iterations > 10)
    throw std::invalid_argument("denoiseRender: iterations must be 1 to 10, got " + std::to_string(o.iterations));
  if (o.fine_passes < 0 || o.fine_passes > 10)
    throw std::invalid_argument("denoiseRender: fine_passes must be 0 to 10, got " + std::to_string(o.fine_passes));
  if (!(o.albedo_floor > 0) || !(o.normal_exponent >= 0) || !(o.albedo_sigma >= 0) || !(o.plane_tolerance > 0) ||
      !(o.luminance_sigma > 0) || !(o.firefly_sigma >= 0) || !std::isfinite(o.firefly_sigma))
    throw std::invalid_argument(
        "denoiseRender: albedo_floor, plane_tolerance and luminance_sigma must be > 0, "
        "normal_exponent, albedo_sigma and firefly_sigma >= 0 (firefly_sigma finite)");
  if (!(o.firefly_spread_px >= 0) || !std::isfinite(o.firefly_spread_px))
    throw std::invalid_argument("denoiseRender: firefly_spread_px must be finite and >= 0");
  if (o.firefly_radius_px < 1)
    throw std::invalid_argument("denoiseRender: firefly_radius_px must be >= 1, got " +
                                std::to_string(o.firefly_radius_px));
}

bool isEmitter(const RenderOutput& r, int y, int x) {
  return (!r.light_id.empty() && r.light_id.at<int>(y, x) != 0) ||
         (!r.emitter_coverage.empty() && r.emitter_coverage.at<float>(y, x) > 0.f);
}

// Row y of the guides (which pixels to filter, the geometry of their first hits), counted.
void guideRow(const RenderOutput& r, const PinholeCamera& camera, int y, Guides& g, PixelCounts& counts) {
  for (int x = 0; x < r.radiance.cols; ++x) {
    const float z = r.depth_m.at<float>(y, x);
    const cv::Vec3f n = r.normal.at<cv::Vec3f>(y, x);
    const cv::Vec3f radiance = r.radiance.at<cv::Vec3f>(y, x);
    const float n_length = std::sqrt(n.dot(n));
    if (isEmitter(r, y, x)) {
      ++counts.emitter;
      continue;
    }
    const bool finite_radiance = std::isfinite(radiance[0]) && std::isfinite(radiance[1]) && std::isfinite(radiance[2]);
    if (!(std::isfinite(z) && z > 0.f && std::isfinite(n_length) && n_length > 1e-3f && finite_radiance)) {
      ++counts.no_surface;
      continue;
    }
    ++counts.filtered;
    g.filtered.at<std::uint8_t>(y, x) = 1;
    const Eigen::Vector3d p = camera.backproject(x, y, z);
    g.point_m.at<cv::Vec3f>(y, x) = {static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z())};
    g.normal.at<cv::Vec3f>(y, x) = n / n_length;
    g.depth_m.at<float>(y, x) = z;
  }
}

// The pixels to filter and the geometry of their first hits (rows in parallel, counted per row
// and summed in row order).
Guides makeGuides(const RenderOutput& r, const PinholeCamera& camera, PixelCounts& counts) {
  Guides g;
  g.filtered = cv::Mat::zeros(r.radiance.size(), CV_8U);
  g.point_m = cv::Mat::zeros(r.radiance.size(), CV_32FC3);
  g.normal = cv::Mat::zeros(r.radiance.size(), CV_32FC3);
  g.depth_m = cv::Mat::zeros(r.radiance.size(), CV_32F);
  std::vector<PixelCounts> row_counts(static_cast<std::size_t>(r.radiance.rows));
  cv::parallel_for_(cv::Range(0, r.radiance.rows), [&](const cv::Range& rows) {
    for (int y = rows.start; y < rows.end; ++y) guideRow(r, camera, y, g, row_counts[static_cast<std::size_t>(y)]);
  });
  for (const PixelCounts& row : row_counts) {
    counts.filtered += row.filtered;
    counts.emitter += row.emitter;
    counts.no_surface += row.no_surface;
  }
  return g;
}

// max(albedo, floor) per channel where filtered, 1 elsewhere (and everywhere without albedo).
cv::Mat demodulationAlbedo(const RenderOutput& r, Guides& g, float albedo_floor) {
  cv::Mat a(r.radiance.size(), CV_32FC3, cv::Scalar::all(1));
  g.log_albedo = cv::Mat::zeros(r.radiance.size(), CV_32F);
  if (r.albedo.empty()) return a;
  cv::parallel_for_(cv::Range(0, a.rows), [&](const cv::Range& rows) {
    for (int y = rows.start; y < rows.end; ++y)
      for (int x = 0; x < a.cols; ++x) {
        if (!g.filtered.at<std::uint8_t>(y, x)) continue;
        const cv::Vec3f albedo = r.albedo.at<cv::Vec3f>(y, x);
        for (int c = 0; c < 3; ++c)
          a.at<cv::Vec3f>(y, x)[c] = std::isfinite(albedo[c]) ? std::max(albedo[c], albedo_floor) : albedo_floor;
        g.log_albedo.at<float>(y, x) = std::log(a.at<cv::Vec3f>(y, x)[1]);
      }
  });
  return a;
}

// Variance of the irradiance's Y: (std_error / albedo Y)^2, averaged over the filtered pixels
// of a 3x3 Gaussian window (one pixel's estimate has few degrees of freedom). Empty without
// std_error.
cv::Mat initialVariance(const RenderOutput& r, const Guides& g, const cv::Mat& albedo) {
  if (r.std_error.empty()) return {};
  cv::Mat variance = cv::Mat::zeros(r.radiance.size(), CV_32F);
  cv::parallel_for_(cv::Range(0, variance.rows), [&](const cv::Range& rows) {
    for (int y = rows.start; y < rows.end; ++y)
      for (int x = 0; x < variance.cols; ++x) {
        const float e = r.std_error.at<float>(y, x) / albedo.at<cv::Vec3f>(y, x)[1];
        if (g.filtered.at<std::uint8_t>(y, x) && std::isfinite(e)) variance.at<float>(y, x) = e * e;
      }
  });
  cv::Mat weight, blurred, blurred_weight;
  g.filtered.convertTo(weight, CV_32F);
  cv::GaussianBlur(variance, blurred, cv::Size(3, 3), 0);
  cv::GaussianBlur(weight, blurred_weight, cv::Size(3, 3), 0);
  cv::Mat out = cv::Mat::zeros(variance.size(), CV_32F);
  cv::divide(blurred, blurred_weight, out);
  out.setTo(0, g.filtered == 0);
  return out;
}

// A firefly's own standard error is at least this share of its value: one rare sample carries
// most of it (one bright sample of four: about 0.87); a steady highlight's is far below.
constexpr float kFireflyMinRelativeError = 0.25f;

// What the firefly clamp did: pixels scaled down and the share of the filtered pixels' light (Y)
// above their bounds.
struct FireflyClamp {
  std::int64_t pixels = 0;
  double excess_share = 0;
};

// A wide Gaussian blur of `image` (sigma_px) through a pyramid: down by area to a fraction of
// the size, blurred there, up again (the wide kernel at full size would cost seconds at 1080p).
cv::Mat wideBlur(const cv::Mat& image, float sigma_px) {
  const int factor = std::max(1, std::min(8, static_cast<int>(sigma_px / 4)));
  cv::Mat small, blurred, out;
  cv::resize(image, small, cv::Size((image.cols + factor - 1) / factor, (image.rows + factor - 1) / factor), 0, 0,
             cv::INTER_AREA);
  cv::GaussianBlur(small, blurred, cv::Size(0, 0), sigma_px / factor, sigma_px / factor, cv::BORDER_CONSTANT);
  cv::resize(blurred, out, image.size(), 0, 0, cv::INTER_LINEAR);
  return out;
}

// Adds `excess_radiance` (CV_32FC3) back as irradiance spread over the filtered pixels: each
// source pixel p's light goes to pixel q in proportion to G(q - p) x albedo(q), so that the
// radiance added is the radiance taken: blur(excess / blur(albedo)).
void spreadExcess(const Guides& g, const cv::Mat& albedo, const cv::Mat& excess_radiance, float sigma_px,
                  cv::Mat& irradiance) {
  cv::Mat mask, weight, mask3;
  g.filtered.convertTo(mask, CV_32F);
  cv::merge(std::vector<cv::Mat>{mask, mask, mask}, mask3);
  cv::multiply(albedo, mask3, weight);
  const cv::Mat reach = wideBlur(weight, sigma_px);  // sum over q of G(q - p) albedo(q), per source p
  cv::Mat per_reach = cv::Mat::zeros(excess_radiance.size(), CV_32FC3);
  for (int y = 0; y < per_reach.rows; ++y)
    for (int x = 0; x < per_reach.cols; ++x)
      for (int c = 0; c < 3; ++c) {
        const float e = excess_radiance.at<cv::Vec3f>(y, x)[c], w = reach.at<cv::Vec3f>(y, x)[c];
        if (e > 0.f && w > 1e-12f) per_reach.at<cv::Vec3f>(y, x)[c] = e / w;
      }
  const cv::Mat added = wideBlur(per_reach, sigma_px);
  cv::Mat added_masked;
  cv::multiply(added, mask3, added_masked);
  irradiance += added_masked;
}

// Scales down the fireflies of `irradiance` (see RenderDenoiseOptions::firefly_sigma) and
// spreads the light above their bounds: the window's sums of Y and Y^2 over the filtered
// pixels, without the pixel itself, give each pixel's bound.
FireflyClamp clampFireflies(const RenderOutput& r, const Guides& g, const cv::Mat& albedo, cv::Mat& irradiance,
                            const RenderDenoiseOptions& o) {
  FireflyClamp result;
  if (r.std_error.empty() || o.firefly_sigma <= 0) return result;
  cv::Mat y, mask;
  cv::extractChannel(irradiance, y, 1);
  g.filtered.convertTo(mask, CV_32F);
  y = y.mul(mask);
  const cv::Size window(2 * o.firefly_radius_px + 1, 2 * o.firefly_radius_px + 1);
  cv::Mat y64, sum_y, sum_y2, count;
  y.convertTo(y64, CV_64F);  // squares in double: a render may hold values whose square overflows a float
  cv::boxFilter(y64, sum_y, CV_64F, window, cv::Point(-1, -1), false, cv::BORDER_CONSTANT);
  cv::boxFilter(y64.mul(y64), sum_y2, CV_64F, window, cv::Point(-1, -1), false, cv::BORDER_CONSTANT);
  cv::boxFilter(mask, count, CV_64F, window, cv::Point(-1, -1), false, cv::BORDER_CONSTANT);
  cv::Mat excess = cv::Mat::zeros(irradiance.size(), CV_32FC3);  // radiance above the bounds
  double total = 0, above = 0;
  for (int row = 0; row < irradiance.rows; ++row)
    for (int x = 0; x < irradiance.cols; ++x) {
      if (!g.filtered.at<std::uint8_t>(row, x)) continue;
      const double value = y.at<float>(row, x), albedo_y = albedo.at<cv::Vec3f>(row, x)[1];
      total += value * albedo_y;
      const double n = count.at<double>(row, x) - 1;
      if (n < 2 || !(value > 0)) continue;
      const double mean = (sum_y.at<double>(row, x) - value) / n;
      const double spread = std::sqrt(std::max(0.0, (sum_y2.at<double>(row, x) - value * value) / n - mean * mean));
      const double bound = mean + o.firefly_sigma * spread;
      const double own_error = r.std_error.at<float>(row, x) / albedo_y;
      if (!std::isfinite(bound) || value <= bound || !(own_error >= kFireflyMinRelativeError * value)) continue;
      cv::Vec3f& pixel = irradiance.at<cv::Vec3f>(row, x);
      const cv::Vec3f kept = pixel * static_cast<float>(bound / value);
      excess.at<cv::Vec3f>(row, x) = (pixel - kept).mul(albedo.at<cv::Vec3f>(row, x));
      pixel = kept;
      above += (value - bound) * albedo_y;
      ++result.pixels;
    }
  result.excess_share = total > 0 ? above / total : 0;
  if (result.pixels > 0 && o.firefly_spread_px > 0) spreadExcess(g, albedo, excess, o.firefly_spread_px, irradiance);
  return result;
}

// What the weights of a pixel's neighbours read of the pixel itself.
struct Centre {
  cv::Vec3f point_m, normal;
  float inverse_tolerance, log_albedo, luminance, variance;
};

// Below this ln weight of its geometry a neighbour is left out (weight < 2e-9).
constexpr float kNegligibleLogWeight = -20.f;

// A pixel's 25 taps, gathered so that the transcendental functions of their weights run as
// Eigen's vectorised array functions (one call each for the 25, not one per tap).
constexpr int kTaps = 25;
using TapArray = Eigen::Array<float, kTaps, 1>;

struct Taps {
  TapArray log_w;      // ln weight without the normal and luminance terms
  TapArray cos_n;      // n_p . n_q (1 where the normal term does not apply)
  TapArray luminance;  // |Y_p - Y_q|
  TapArray spread;     // luminance_sigma x sqrt(v_p + v_q)
  TapArray spline;     // the kernel's weight; 0 for a tap left out
  std::array<const cv::Vec3f*, kTaps> irradiance;  // set where spline != 0
  std::array<float, kTaps> variance_q;             // set where spline != 0
};

// ln of neighbour q's tangent-plane and albedo weight for pixel `c`, and whether q counts at
// all (its normal faces p's side when the normal weight is on); the normal term is added later.
bool geometryLogWeight(const Centre& c, const Guides& g, int yq, int xq, const RenderDenoiseOptions& o,
                       float& cos_n, float& log_w) {
  cos_n = c.normal.dot(g.normal.at<cv::Vec3f>(yq, xq));
  if (o.normal_exponent > 0 && cos_n <= 0.f) return false;
  log_w = -std::abs(c.normal.dot(g.point_m.at<cv::Vec3f>(yq, xq) - c.point_m)) * c.inverse_tolerance;
  if (o.albedo_sigma > 0) log_w -= std::abs(c.log_albedo - g.log_albedo.at<float>(yq, xq)) / o.albedo_sigma;
  if (o.normal_exponent <= 0 || cos_n > 1.f) cos_n = 1.f;
  return log_w > kNegligibleLogWeight;
}

// Fills `t` with the taps of pixel (x, y) at spacing `step`: those off the image, not filtered
// or of negligible geometric weight get a zero kernel weight (and nothing else is read of them).
void gatherTaps(const Guides& g, const Estimate& in, int step, const RenderDenoiseOptions& o, const Centre& c, int x,
                int y, Taps& t) {
  t.spline.setZero();
  t.log_w.setZero();
  t.cos_n.setOnes();
  t.luminance.setZero();
  t.spread.setOnes();
  const bool luminance = !in.variance.empty();
  for (int j = 0; j < 5; ++j) {
    const int yq = y + (j - 2) * step;
    if (yq < 0 || yq >= g.filtered.rows) continue;
    for (int i = 0; i < 5; ++i) {
      const int xq = x + (i - 2) * step, k = 5 * j + i;
      if (xq < 0 || xq >= g.filtered.cols || !g.filtered.at<std::uint8_t>(yq, xq)) continue;
      float cos_n = 1.f, log_w = 0.f;
      if (!geometryLogWeight(c, g, yq, xq, o, cos_n, log_w)) continue;
      t.irradiance[k] = &in.irradiance.at<cv::Vec3f>(yq, xq);
      t.variance_q[k] = luminance ? in.variance.at<float>(yq, xq) : 0.f;
      t.spline(k) = kSpline[static_cast<std::size_t>(i)] * kSpline[static_cast<std::size_t>(j)];
      t.log_w(k) = log_w;
      t.cos_n(k) = cos_n;
      t.luminance(k) = std::abs(c.luminance - (*t.irradiance[k])[1]);
      t.spread(k) = o.luminance_sigma * std::sqrt(c.variance + t.variance_q[k]);
    }
  }
}

// Pixel (x, y)'s filtered irradiance and its variance: the weighted mean over its 5x5 taps.
void filterPixel(const Guides& g, const Estimate& in, int step, const RenderDenoiseOptions& o, int x, int y,
                 Estimate& out) {
  const bool luminance = !in.variance.empty();
  const Centre c{g.point_m.at<cv::Vec3f>(y, x),
                 g.normal.at<cv::Vec3f>(y, x),
                 1.f / (o.plane_tolerance * g.depth_m.at<float>(y, x)),
                 g.log_albedo.at<float>(y, x),
                 in.irradiance.at<cv::Vec3f>(y, x)[1],
                 luminance ? in.variance.at<float>(y, x) : 0.f};
  Taps t;
  gatherTaps(g, in, step, o, c, x, y, t);
  TapArray log_w = t.log_w;
  if (o.normal_exponent > 0) log_w += o.normal_exponent * t.cos_n.log();
  if (luminance) log_w -= t.luminance / (t.spread + 1e-30f);
  const TapArray w = t.spline * log_w.exp();
  float sum_w = 0, sum_w2v = 0;
  cv::Vec3f sum{0, 0, 0};
  for (int k = 0; k < kTaps; ++k) {
    if (t.spline(k) == 0.f) continue;
    sum_w += w(k);
    sum += w(k) * *t.irradiance[static_cast<std::size_t>(k)];
    sum_w2v += w(k) * w(k) * t.variance_q[static_cast<std::size_t>(k)];
  }
  // sum_w > 0: the pixel itself weighs (3/8)^2.
  out.irradiance.at<cv::Vec3f>(y, x) = sum / sum_w;
  if (luminance) out.variance.at<float>(y, x) = sum_w2v / (sum_w * sum_w);
}

// One a-trous pass with taps `step` px apart over rows [row_begin, row_end).
void atrousRows(const Guides& g, const Estimate& in, int step, const RenderDenoiseOptions& o, Estimate& out,
                int row_begin, int row_end) {
  for (int y = row_begin; y < row_end; ++y)
    for (int x = 0; x < g.filtered.cols; ++x) {
      if (g.filtered.at<std::uint8_t>(y, x))
        filterPixel(g, in, step, o, x, y, out);
      else
        out.irradiance.at<cv::Vec3f>(y, x) = in.irradiance.at<cv::Vec3f>(y, x);
    }
}

Estimate atrousPass(const Guides& g, const Estimate& in, int step, const RenderDenoiseOptions& o) {
  Estimate out;
  out.irradiance.create(in.irradiance.size(), CV_32FC3);
  if (!in.variance.empty()) out.variance = in.variance.clone();
  cv::parallel_for_(cv::Range(0, g.filtered.rows),
                    [&](const cv::Range& rows) { atrousRows(g, in, step, o, out, rows.start, rows.end); });
  return out;
}

// The taps' spacing of each pass, px: 1, 2, ..., 2^(iterations - 1), then the fine passes
// 2^(fine_passes - 1), ..., 2, 1.
std::vector<int> passSteps(const RenderDenoiseOptions& o) {
  std::vector<int> steps;
  for (int pass = 0; pass < o.iterations; ++pass) steps.push_back(1 << pass);
  for (int pass = o.fine_passes - 1; pass >= 0; --pass) steps.push_back(1 << pass);
  return steps;
}

StageReport skippedReport() {
  StageReport report;
  report.name = "denoise";
  report.skipped = true;
  report.skip_reason = "render denoising switched off";
  return report;
}

}  // namespace

StageReport denoiseRender(RenderOutput& render, const PinholeCamera& camera, const RenderDenoiseOptions& options) {
  if (!options.enabled) return skippedReport();
  const Stopwatch clock;
  validate(render, camera, options);
  PixelCounts counts;
  Guides guides = makeGuides(render, camera, counts);
  const cv::Mat albedo = demodulationAlbedo(render, guides, options.albedo_floor);

  Estimate estimate;
  cv::divide(render.radiance, albedo, estimate.irradiance);
  const FireflyClamp fireflies = clampFireflies(render, guides, albedo, estimate.irradiance, options);
  estimate.variance = initialVariance(render, guides, albedo);
  std::int64_t footprint_radius_px = 0;  // each pass reaches two taps further
  for (const int step : passSteps(options)) {
    estimate = atrousPass(guides, estimate, step, options);
    footprint_radius_px += 2 * step;
  }

  cv::Mat filtered;
  cv::multiply(estimate.irradiance, albedo, filtered);
  const double y_before = cv::mean(render.radiance, guides.filtered)[1];
  filtered.copyTo(render.radiance, guides.filtered);  // emitters and sky keep their values bit for bit
  const double y_after = cv::mean(render.radiance, guides.filtered)[1];

  StageReport report;
  report.name = "denoise";
  report.add("pixels_filtered", counts.filtered)
      .add("pixels_kept_emitter", counts.emitter)
      .add("pixels_kept_no_surface", counts.no_surface)
      .add("iterations", static_cast<std::int64_t>(options.iterations))
      .add("fine_passes", static_cast<std::int64_t>(options.fine_passes))
      .add("footprint_radius", footprint_radius_px, "px")
      .add("luminance_weight", !render.std_error.empty())
      .add("luminance_ratio", y_before > 0 ? y_after / y_before : 1.0)
      .add("fireflies_clamped", fireflies.pixels)
      .add(options.firefly_spread_px > 0 ? "firefly_light_spread" : "firefly_light_removed", fireflies.excess_share);
  report.notes.push_back(
      "a-trous filter of the albedo-demodulated radiance, guided by normal, tangent plane and "
      "luminance against the standard error; emitter and sky pixels kept exact");
  report.seconds = clock.seconds();
  return report;
}

}  // namespace solo
