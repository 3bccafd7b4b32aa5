#include <solo/post/chromatic_adaptation.h>
#include <solo/post/colour_encoding.h>

#include <solo/core/srgb.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <stdexcept>
#include <string>

namespace solo {

namespace {

cv::Matx33d linearSrgbToXyzMatrix() {
  // Columns: XYZ of each primary from its chromaticity, scaled so they sum to the white.
  const double primaries[3][2] = {{0.64, 0.33}, {0.30, 0.60}, {0.15, 0.06}};
  cv::Matx33d unscaled;
  for (int c = 0; c < 3; ++c) {
    const double x = primaries[c][0], y = primaries[c][1];
    unscaled(0, c) = x / y;
    unscaled(1, c) = 1.0;
    unscaled(2, c) = (1.0 - x - y) / y;
  }
  const cv::Vec3d scale = unscaled.inv() * kWhitePointD65;
  cv::Matx33d m;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) m(r, c) = unscaled(r, c) * scale[c];
  return m;
}

}  // namespace

cv::Matx33d xyzToLinearSrgbMatrix() { return linearSrgbToXyzMatrix().inv(); }

cv::Vec3d linearSrgbLuminanceWeights() {
  const cv::Matx33d m = linearSrgbToXyzMatrix();
  return {m(1, 0), m(1, 1), m(1, 2)};
}

float encodeTransfer(float linear, TransferCurve curve) {
  const float v = std::clamp(linear, 0.f, 1.f);
  if (v == 1.f) return 1.f;  // exact white, whatever the curve's rounding
  switch (curve) {
    case TransferCurve::Gamma22: return std::pow(v, 1.f / 2.2f);
    case TransferCurve::Srgb: return linearToSrgb(v);
    case TransferCurve::Linear: return v;
  }
  return v;
}

float decodeTransfer(float encoded, TransferCurve curve) {
  const float v = std::clamp(encoded, 0.f, 1.f);
  switch (curve) {
    case TransferCurve::Gamma22: return std::pow(v, 2.2f);
    case TransferCurve::Srgb: return srgbToLinear(v);
    case TransferCurve::Linear: return v;
  }
  return v;
}

namespace {

void checkKnee(double knee) {
  if (!(knee >= 0 && knee <= 1))
    throw std::invalid_argument("highlight knee must be in [0, 1], got " + std::to_string(knee));
}

/// The shoulder s(u): identity up to the knee, then an exponential approach to 1 whose slope
/// at the knee is 1 (continuous first derivative). knee = 1: min(u, 1).
double shoulder(double u, double knee) {
  if (u <= knee) return u;
  if (knee >= 1) return 1;
  const double room = 1 - knee;
  return knee + room * -std::expm1(-(u - knee) / room);
}

/// desaturateHighlight without the knee check; `changed` tells whether the colour moved.
cv::Vec3f desaturate(const cv::Vec3f& c, double knee, const cv::Vec3d& w, bool* changed) {
  const double luminance = w[0] * c[0] + w[1] * c[1] + w[2] * c[2];
  *changed = true;
  if (luminance >= 1) return {1.f, 1.f, 1.f};
  const double spread = std::max({c[0], c[1], c[2]}) - luminance;
  const double headroom_share = spread / (1 - luminance);
  if (!(headroom_share > knee)) {
    *changed = false;
    return c;
  }
  // Every colour grey + t (c - grey) has luminance Y and c's HSV hue.
  const double t = shoulder(headroom_share, knee) / headroom_share;
  cv::Vec3f out;
  for (int k = 0; k < 3; ++k)
    out[k] = static_cast<float>(std::clamp(luminance + t * (c[k] - luminance), 0.0, 1.0));
  return out;
}

void checkRolloff(double white_clip, double knee_point) {
  if (!(white_clip >= 1 && std::isfinite(white_clip)))
    throw std::invalid_argument("white clip must be a finite linear level >= 1, got " + std::to_string(white_clip));
  if (!(knee_point > 0 && knee_point < 1))
    throw std::invalid_argument("knee point must be in (0, 1), got " + std::to_string(knee_point));
}

/// luminanceRolloff without the checks.
double rolloff(double y, double white_clip, double knee_point) {
  if (white_clip <= 1 || !(y > 0)) return y;
  const double e = std::pow(y, 1 / 2.2);
  if (e <= knee_point) return y;
  const double slope = (1 - knee_point) / (std::pow(white_clip, 1 / 2.2) - knee_point);
  return std::pow(std::min(1.0, knee_point + (e - knee_point) * slope), 2.2);
}

struct GamutCounts {
  std::int64_t out_of_gamut = 0, negative_luminance = 0, over_range = 0;
};

/// Handles negative channels in place (NegativeHandling) and counts what it met.
GamutCounts handleNegatives(cv::Mat& linear_rgb, NegativeHandling handling) {
  const cv::Vec3d w = linearSrgbLuminanceWeights();
  const float wr = static_cast<float>(w[0]), wg = static_cast<float>(w[1]), wb = static_cast<float>(w[2]);
  std::atomic<std::int64_t> out_of_gamut{0}, black_from_negative_luminance{0}, over_range{0};
  const bool desaturate = handling == NegativeHandling::Desaturate;
  cv::parallel_for_(cv::Range(0, linear_rgb.rows), [&](const cv::Range& rows) {
    std::int64_t local_gamut = 0, local_black = 0, local_over = 0;
    for (int y = rows.start; y < rows.end; ++y) {
      cv::Vec3f* p = linear_rgb.ptr<cv::Vec3f>(y);
      for (int x = 0; x < linear_rgb.cols; ++x) {
        cv::Vec3f& c = p[x];
        const float lowest = std::min({c[0], c[1], c[2]});
        if (lowest < 0) {
          ++local_gamut;
          if (desaturate) {
            const float luminance = wr * c[0] + wg * c[1] + wb * c[2];
            if (luminance <= 0) {
              ++local_black;
              c = {0, 0, 0};
            } else {
              // Mix with grey of the same luminance: grey + t (c - grey) has luminance Y for
              // every t; t = Y / (Y - lowest) puts the lowest channel exactly at 0.
              const float t = luminance / (luminance - lowest);
              for (int k = 0; k < 3; ++k) c[k] = std::max(0.f, luminance + t * (c[k] - luminance));
            }
          } else {
            for (int k = 0; k < 3; ++k) c[k] = std::max(0.f, c[k]);
          }
        }
        if (std::max({c[0], c[1], c[2]}) > 1.f) ++local_over;
      }
    }
    out_of_gamut += local_gamut;
    black_from_negative_luminance += local_black;
    over_range += local_over;
  });
  return {out_of_gamut.load(), black_from_negative_luminance.load(), over_range.load()};
}

/// The encoded image: highlight handling, then the transfer curve per channel. Returns the
/// number of pixels the highlight handling changed.
std::int64_t encodeLinear(const cv::Mat& linear_rgb, const ColourEncodingOptions& options, cv::Mat& encoded) {
  encoded.create(linear_rgb.size(), CV_32FC3);
  const cv::Vec3d w = linearSrgbLuminanceWeights();
  const bool desaturate_highlights = options.highlights == HighlightHandling::Desaturate;
  const bool rolled = options.white_clip > 1;
  std::atomic<std::int64_t> desaturated{0};
  cv::parallel_for_(cv::Range(0, linear_rgb.rows), [&](const cv::Range& rows) {
    std::int64_t local = 0;
    for (int y = rows.start; y < rows.end; ++y) {
      const cv::Vec3f* src = linear_rgb.ptr<cv::Vec3f>(y);
      cv::Vec3f* dst = encoded.ptr<cv::Vec3f>(y);
      for (int x = 0; x < linear_rgb.cols; ++x) {
        cv::Vec3f c = src[x];
        if (rolled) {
          const double y = w[0] * c[0] + w[1] * c[1] + w[2] * c[2];
          if (y > 0) c *= static_cast<float>(rolloff(y, options.white_clip, options.knee_point) / y);
        }
        bool changed = false;
        if (desaturate_highlights) c = desaturate(c, options.highlight_knee, w, &changed);
        local += changed;
        for (int k = 0; k < 3; ++k) dst[x][k] = encodeTransfer(c[k], options.curve);
      }
    }
    desaturated += local;
  });
  return desaturated.load();
}

}  // namespace

double luminanceRolloff(double y, double white_clip, double knee_point) {
  checkRolloff(white_clip, knee_point);
  return rolloff(y, white_clip, knee_point);
}

cv::Vec3f desaturateHighlight(const cv::Vec3f& linear_rgb, double knee) {
  checkKnee(knee);
  bool changed = false;
  return desaturate(linear_rgb, knee, linearSrgbLuminanceWeights(), &changed);
}

ColourEncodingResult encodeXyzToSrgb(const cv::Mat& xyz_d65, const ColourEncodingOptions& options) {
  Stopwatch clock;
  CV_Assert(xyz_d65.type() == CV_32FC3);
  checkKnee(options.highlight_knee);
  checkRolloff(options.white_clip, options.knee_point);
  ColourEncodingResult result;
  result.report.name = "colour";
  cv::transform(xyz_d65, result.linear_rgb, cv::Matx33f(xyzToLinearSrgbMatrix()));
  const GamutCounts counts = handleNegatives(result.linear_rgb, options.negatives);
  const std::int64_t desaturated = encodeLinear(result.linear_rgb, options, result.encoded);

  const double pixels = static_cast<double>(result.linear_rgb.total());
  const char* curve_name = options.curve == TransferCurve::Gamma22 ? "gamma 2.2"
                           : options.curve == TransferCurve::Srgb  ? "sRGB piecewise"
                                                                   : "linear";
  const bool desaturate_highlights = options.highlights == HighlightHandling::Desaturate;
  result.report.add("transfer_curve", std::string(curve_name))
      .add("negative_handling", std::string(options.negatives == NegativeHandling::Desaturate ? "desaturate" : "clip"))
      .add("highlight_handling", std::string(desaturate_highlights ? "desaturate" : "clip"))
      .add("out_of_gamut_pixels", counts.out_of_gamut)
      .add("out_of_gamut_fraction", pixels > 0 ? counts.out_of_gamut / pixels : 0.0)
      .add("negative_luminance_pixels", counts.negative_luminance)
      .add("over_range_pixels", counts.over_range)
      .add("over_range_fraction", pixels > 0 ? counts.over_range / pixels : 0.0);
  if (options.white_clip > 1)
    result.report.add("white_clip", options.white_clip).add("knee_point", options.knee_point);
  if (desaturate_highlights)
    result.report.add("highlight_knee", options.highlight_knee)
        .add("desaturated_highlight_pixels", desaturated)
        .add("desaturated_highlight_fraction", pixels > 0 ? desaturated / pixels : 0.0);
  result.report.seconds = clock.seconds();
  return result;
}

cv::Mat quantiseEncoded(const cv::Mat& encoded, int bits) {
  CV_Assert(encoded.depth() == CV_32F);
  if (bits != 8 && bits != 16) throw std::invalid_argument("output bit depth must be 8 or 16");
  const double max_code = bits == 8 ? 255.0 : 65535.0;
  cv::Mat codes;
  // convertTo rounds to nearest and saturates.
  encoded.convertTo(codes, CV_MAKETYPE(bits == 8 ? CV_8U : CV_16U, encoded.channels()), max_code);
  return codes;
}

}  // namespace solo
