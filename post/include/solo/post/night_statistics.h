#pragma once
// Realism statistics of a night image (docs/evaluation.md, "solo eval night"): luma level and
// percentiles, clipped and bright shares, luma and chroma noise, the colour cast of the dim
// mid-tones and the radius of the halos around clipped lights. Computed on the 8-bit
// sRGB-encoded image resized to 960 px wide, so that images of any size compare.

#include <solo/core/report.h>

#include <opencv2/core.hpp>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace solo {

/// Order of the three colour channels of an image handed to computeNightStatistics. solo's
/// readers give RGB; cv::imread gives BGR.
enum class ChannelOrder { Rgb, Bgr };

struct NightStatisticsOptions {
  int analysis_width_px = 960;         ///< images of another width are resized to it first
  double clipped_luma = 250;           ///< clipped: Y >= this (8-bit code values)
  double bright_luma = 200;            ///< bright: Y >= this
  int halo_min_blob_px = 4;            ///< clipped blobs smaller than this (at analysis size) have no halo
  double halo_headroom_fraction = 0.1;  ///< halo edge: background + this x (255 - background)
  int halo_max_radius_px = 240;        ///< a ring profile not down by this radius is reported as this
};

/// The statistics; luma Y = 0.299 R + 0.587 G + 0.114 B in 8-bit code values (0-255).
struct NightStatistics {
  int source_width_px = 0, source_height_px = 0;      ///< the image handed in
  int analysis_width_px = 0, analysis_height_px = 0;  ///< after the resize
  double mean_luma = 0;                               ///< mean of Y
  double p50_luma = 0, p90_luma = 0, p99_luma = 0;    ///< percentiles of Y (NumPy's linear rule)
  double clipped_share = 0;  ///< share of pixels with Y >= 250
  double bright_share = 0;   ///< share of pixels with Y >= 200
  /// Robust sigma of the luma high-pass over the flattest half of the mid-tone pixels; none
  /// when no pixel has 5 < Y < 250.
  std::optional<double> noise_luma;
  std::optional<double> chroma_noise;          ///< the same sigma of B - Y and R - Y, averaged
  std::optional<double> cast_cb, cast_cr;      ///< mean B - Y and R - Y over 20 < Y < 80; none without such pixels
  std::int64_t halo_blobs = 0;                 ///< clipped blobs of at least halo_min_blob_px pixels
  std::optional<double> halo_radius_px;        ///< median halo radius over them, analysis pixels; none without blob
};

/// image: CV_8UC3, CV_16UC3 or CV_32FC3/CV_64FC3 (sRGB-encoded, [0, 1]), channels in `order`.
/// Quantised to 8-bit codes (round(v x 255), round(v x 255 / 65535) for 16-bit), resized to
/// options.analysis_width_px wide by resizeBilinearLikePil when its width differs, then
/// measured as docs/evaluation.md defines. Throws std::invalid_argument for another type or an
/// image smaller than 3x3 after the resize.
NightStatistics computeNightStatistics(const cv::Mat& image, ChannelOrder order,
                                       const NightStatisticsOptions& options = {});

/// One statistic by name: keys as ../shared/tools/nightstats.py's JSON (mean, p50, p90, p99,
/// clipped, bright, noise, chroma_noise, cast_cb, cast_cr) plus halo_radius_px and
/// halo_blobs; value none where the statistic has none; unit "px" for the halo radius, ""
/// otherwise (luma in 8-bit codes, shares in [0, 1]).
struct NamedNightStatistic {
  std::string key;
  std::optional<double> value;
  std::string unit;
};

/// The statistics of `s` in that fixed order (the columns of `solo eval night`).
std::vector<NamedNightStatistic> namedNightStatistics(const NightStatistics& s);

/// A run-report stage "realism" of `s` taking `seconds`: the headline figures first (mean,
/// clipped, bright, noise, chroma_noise, halo_radius_px), then the rest; a statistic without a
/// value becomes a note "<key>: none".
StageReport nightStatisticsReport(const NightStatistics& s, double seconds);

/// rgb8: CV_8UC3 (any channel order) resized to `size` the way Pillow's Image.resize(...,
/// BILINEAR) does: per axis a triangle filter whose support is widened by the shrink factor
/// (an antialiasing filter when shrinking, plain bilinear when enlarging), pixel centres at
/// (i + 0.5) x scale, weights renormalised at the borders, horizontal pass first, each pass
/// rounded to 8 bits. Throws std::invalid_argument for another type or an empty size.
cv::Mat resizeBilinearLikePil(const cv::Mat& rgb8, cv::Size size);

/// The halo radius around one clipped blob: ring-averaged luma around `centre` (rings of 1 px
/// width, ring k = pixels whose centre lies at distance d with k - 0.5 <= d < k + 0.5) walked
/// outward until its mean falls to `edge_luma`; the radius is interpolated linearly between
/// that ring and the previous non-empty one. luma: CV_64F. Returns max_radius_px when the
/// profile does not fall within it.
double haloRadiusPx(const cv::Mat& luma, cv::Point2d centre, double edge_luma, int max_radius_px);

}  // namespace solo
