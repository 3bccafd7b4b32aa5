// Texture-keeping upsampling of a render made below the image size (render_upsample.h).

#include "solo/render/render_upsample.h"

#include "map_checks.h"

#include <tbb/parallel_for.h>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>

namespace solo {

namespace {

cv::Mat resized(const cv::Mat& m, cv::Size size, int interpolation) {
  if (m.empty() || m.size() == size) return m.clone();
  cv::Mat out;
  cv::resize(m, out, size, 0, 0, interpolation);
  return out;
}

// The four render pixels around a full-size pixel and their bilinear weights (cv::resize's
// convention: pixel centres at half-integers).
struct Bilinear {
  int x[2], y[2];
  float wx[2], wy[2];
};

Bilinear bilinearAt(int x, int y, double scale_x, double scale_y, cv::Size low) {
  Bilinear b;
  const double fx = std::clamp((x + 0.5) / scale_x - 0.5, 0.0, low.width - 1.0);
  const double fy = std::clamp((y + 0.5) / scale_y - 0.5, 0.0, low.height - 1.0);
  b.x[0] = static_cast<int>(fx);
  b.y[0] = static_cast<int>(fy);
  b.x[1] = std::min(b.x[0] + 1, low.width - 1);
  b.y[1] = std::min(b.y[0] + 1, low.height - 1);
  b.wx[1] = static_cast<float>(fx - b.x[0]);
  b.wy[1] = static_cast<float>(fy - b.y[0]);
  b.wx[0] = 1.f - b.wx[1];
  b.wy[0] = 1.f - b.wy[1];
  return b;
}

// Per full-size pixel, the radiance from the render pixels around it (render_upsample.h).
class GuidedUpsampler {
 public:
  GuidedUpsampler(const RenderOutput& low, const UpsampleGuides& guides, const RenderUpsampleOptions& options,
                  cv::Size size)
      : low_(low),
        guides_(guides),
        options_(options),
        albedo_(low.mean_albedo.empty() ? low.albedo : low.mean_albedo),
        scale_x_(static_cast<double>(size.width) / low.radiance.cols),
        scale_y_(static_cast<double>(size.height) / low.radiance.rows) {}

  struct Counts {
    long long textured = 0, lamp = 0;
  };

  // Replaces the bilinear radiance of row y where a guided value applies.
  Counts row(int y, cv::Mat& radiance) const {
    Counts counts;
    for (int x = 0; x < radiance.cols; ++x) {
      const Bilinear b = bilinearAt(x, y, scale_x_, scale_y_, low_.radiance.size());
      cv::Vec3f value;
      const int light = guides_.light_id.empty() ? 0 : guides_.light_id.at<std::int32_t>(y, x);
      if (light != 0) {
        if (!lampAt(b, light, value)) continue;
        ++counts.lamp;
      } else {
        if (!texturedAt(x, y, b, value)) continue;
        ++counts.textured;
      }
      radiance.at<cv::Vec3f>(y, x) = value;
    }
    return counts;
  }

 private:
  bool seesSurface(int x, int y) const {
    if (!guides_.surface.empty() && guides_.surface.at<std::uint8_t>(y, x) == 0) return false;
    const float d = guides_.depth_m.at<float>(y, x);
    return std::isfinite(d) && d > 0.f;
  }

  bool seesEmitter(int u, int v) const {
    if (!low_.light_id.empty() && low_.light_id.at<std::int32_t>(v, u) != 0) return true;
    return !low_.emitter_coverage.empty() && low_.emitter_coverage.at<float>(v, u) > 0.f;
  }

  static bool finite(const cv::Vec3f& c) { return std::isfinite(c[0]) && std::isfinite(c[1]) && std::isfinite(c[2]); }

  // A lamp's pixel: the bilinear mean of the render pixels that see only that lamp.
  bool lampAt(const Bilinear& b, int light, cv::Vec3f& value) const {
    if (low_.light_id.empty() || low_.emitter_coverage.empty()) return false;
    cv::Vec3f sum(0.f, 0.f, 0.f);
    float weight_sum = 0.f;
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i < 2; ++i) {
        const int u = b.x[i], v = b.y[j];
        const float w = b.wx[i] * b.wy[j];
        if (!(w > 0.f) || low_.light_id.at<std::int32_t>(v, u) != light || low_.emitter_coverage.at<float>(v, u) < 1.f)
          continue;
        const cv::Vec3f r = low_.radiance.at<cv::Vec3f>(v, u);
        if (!finite(r)) continue;
        sum += w * r;
        weight_sum += w;
      }
    if (!(weight_sum > 0.f)) return false;
    value = sum / weight_sum;
    return true;
  }

  // A surface pixel: its reflectance times the depth- and bilinear-weighted irradiance of the
  // render pixels around it that see no emitter.
  bool texturedAt(int x, int y, const Bilinear& b, cv::Vec3f& value) const {
    if (!seesSurface(x, y)) return false;
    const float d = guides_.depth_m.at<float>(y, x);
    cv::Vec3f irradiance(0.f, 0.f, 0.f);
    float weight_sum = 0.f;
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i < 2; ++i) {
        const int u = b.x[i], v = b.y[j];
        if (seesEmitter(u, v)) {
          if (guides_.light_id.empty()) return false;  // no outline of the lamps: keep the mix
          continue;
        }
        const float w_bilinear = b.wx[i] * b.wy[j];
        if (!(w_bilinear > 0.f)) continue;
        const cv::Vec3f a = albedo_.at<cv::Vec3f>(v, u);
        if (!(a[0] >= options_.min_albedo && a[1] >= options_.min_albedo && a[2] >= options_.min_albedo)) continue;
        const cv::Vec3f r = low_.radiance.at<cv::Vec3f>(v, u);
        const float dj = low_.depth_m.at<float>(v, u);
        if (!finite(r) || !(std::isfinite(dj) && dj > 0.f)) continue;
        const float t = (dj - d) / (options_.depth_tolerance * d);
        const float w = w_bilinear * std::exp(-t * t);
        for (int k = 0; k < 3; ++k) irradiance[k] += w * r[k] / a[k];
        weight_sum += w;
      }
    if (!(weight_sum >= kMinWeight)) return false;
    const cv::Vec3f a = guides_.reflectance.at<cv::Vec3f>(y, x);
    for (int k = 0; k < 3; ++k) value[k] = std::max(0.f, a[k]) * irradiance[k] / weight_sum;
    return finite(value);
  }

  // Below this summed weight no render pixel around lies on the pixel's surface.
  static constexpr float kMinWeight = 0.01f;

  const RenderOutput& low_;
  const UpsampleGuides& guides_;
  const RenderUpsampleOptions& options_;
  const cv::Mat& albedo_;
  double scale_x_, scale_y_;
};

}  // namespace

RenderOutput upsampleRender(const RenderOutput& low, cv::Size size, const UpsampleGuides& guides,
                            const RenderUpsampleOptions& options, StageReport* report) {
  if (low.radiance.empty() || size.width <= 0 || size.height <= 0)
    throw std::invalid_argument("upsampleRender: empty render or size");
  if (!(options.min_albedo > 0.f) || !(options.depth_tolerance > 0.f))
    throw std::invalid_argument("upsampleRender: min_albedo and depth_tolerance must be > 0");
  const cv::Size low_size = low.radiance.size();
  requireEmptyOrSized({{&low.radiance, CV_32FC3, "the render's radiance"},
                       {&low.albedo, CV_32FC3, "the render's albedo"},
                       {&low.mean_albedo, CV_32FC3, "the render's mean albedo"},
                       {&low.depth_m, CV_32F, "the render's depth"},
                       {&low.light_id, CV_32S, "the render's light ids"},
                       {&low.emitter_coverage, CV_32F, "the render's emitter coverage"}},
                      low_size, "upsampleRender");
  requireEmptyOrSized({{&guides.reflectance, CV_32FC3, "the reflectance guide"},
                       {&guides.depth_m, CV_32F, "the depth guide"},
                       {&guides.surface, CV_8U, "the surface guide"},
                       {&guides.light_id, CV_32S, "the light-id guide"}},
                      size, "upsampleRender");

  RenderOutput out;
  out.radiance = resized(low.radiance, size, cv::INTER_LINEAR);
  out.albedo = resized(low.albedo, size, cv::INTER_LINEAR);
  out.mean_albedo = resized(low.mean_albedo, size, cv::INTER_LINEAR);
  out.normal = resized(low.normal, size, cv::INTER_LINEAR);
  out.depth_m = resized(low.depth_m, size, cv::INTER_NEAREST);
  out.light_id = resized(low.light_id, size, cv::INTER_NEAREST);
  out.emitter_coverage = resized(low.emitter_coverage, size, cv::INTER_NEAREST);
  out.samples = resized(low.samples, size, cv::INTER_NEAREST);
  out.std_error = resized(low.std_error, size, cv::INTER_NEAREST);
  out.report = low.report;

  std::atomic<long long> textured{0}, lamp{0};
  const bool guided = options.texture && !guides.reflectance.empty() && !guides.depth_m.empty() &&
                      !(low.albedo.empty() && low.mean_albedo.empty()) && !low.depth_m.empty() && size != low_size;
  if (guided) {
    const GuidedUpsampler upsampler(low, guides, options, size);
    tbb::parallel_for(0, size.height, [&](int y) {
      const GuidedUpsampler::Counts counts = upsampler.row(y, out.radiance);
      textured += counts.textured;
      lamp += counts.lamp;
    });
  }
  if (report) {
    const long long pixels = static_cast<long long>(size.width) * size.height;
    report->add("upsampled_textured_pixels", static_cast<std::int64_t>(textured.load()))
        .add("upsampled_lamp_pixels", static_cast<std::int64_t>(lamp.load()))
        .add("upsampled_bilinear_pixels", static_cast<std::int64_t>(pixels - textured.load() - lamp.load()));
  }
  return out;
}

}  // namespace solo
