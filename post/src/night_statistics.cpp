#include <solo/post/night_statistics.h>

#include <solo/core/quantile.h>

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace solo {
namespace {

/// Fractional bits of Pillow's fixed-point resampling weights (8-bit images).
constexpr int kWeightBits = 22;

/// One output sample of a separable resampling pass: the first input index and the weights,
/// fixed point with kWeightBits fractional bits.
struct FilterTaps {
  int first = 0;
  std::vector<std::int64_t> weights;
};

/// Pillow's bilinear filter along one axis: a triangle of support 1 stretched by the shrink
/// factor (at least 1), centred on the output pixel's centre in input coordinates.
std::vector<FilterTaps> triangleTaps(int in_size, int out_size) {
  const double scale = static_cast<double>(in_size) / out_size;
  const double filter_scale = std::max(scale, 1.0);
  const double support = filter_scale;
  std::vector<FilterTaps> taps(static_cast<std::size_t>(out_size));
  for (int o = 0; o < out_size; ++o) {
    const double centre = (o + 0.5) * scale;
    FilterTaps& t = taps[static_cast<std::size_t>(o)];
    // (int)(x + 0.5), as Pillow takes its window (the statistics must match Pillow's resize);
    // where x + 0.5 is negative the clamp to 0 decides, so it rounds like lround.
    t.first = std::max(0, static_cast<int>(centre - support + 0.5));     // NOLINT(bugprone-incorrect-roundings)
    const int end = std::min(in_size, static_cast<int>(centre + support + 0.5));  // NOLINT(bugprone-incorrect-roundings)
    std::vector<double> weights;
    double total = 0;
    for (int i = t.first; i < end; ++i) {
      weights.push_back(std::max(0.0, 1.0 - std::abs((i - centre + 0.5) / filter_scale)));
      total += weights.back();
    }
    for (const double w : weights) t.weights.push_back(std::llround(w / total * (1 << kWeightBits)));
  }
  return taps;
}

/// A fixed-point sum rounded half up and clamped to an 8-bit code.
uchar toCode(std::int64_t sum) {
  return static_cast<uchar>(std::clamp<std::int64_t>((sum + (1 << (kWeightBits - 1))) >> kWeightBits, 0, 255));
}

/// Resamples every row of a CV_8UC3 image to `out_width` columns.
cv::Mat resampleRows(const cv::Mat& in, int out_width) {
  const std::vector<FilterTaps> taps = triangleTaps(in.cols, out_width);
  cv::Mat out(in.rows, out_width, CV_8UC3);
  for (int y = 0; y < in.rows; ++y) {
    const cv::Vec3b* src = in.ptr<cv::Vec3b>(y);
    cv::Vec3b* dst = out.ptr<cv::Vec3b>(y);
    for (int x = 0; x < out_width; ++x) {
      const FilterTaps& t = taps[static_cast<std::size_t>(x)];
      std::int64_t sum[3] = {0, 0, 0};
      for (std::size_t j = 0; j < t.weights.size(); ++j)
        for (int c = 0; c < 3; ++c) sum[c] += t.weights[j] * src[t.first + static_cast<int>(j)][c];
      dst[x] = cv::Vec3b(toCode(sum[0]), toCode(sum[1]), toCode(sum[2]));
    }
  }
  return out;
}

/// Any accepted input as CV_8UC3 RGB codes.
cv::Mat toRgb8(const cv::Mat& image, ChannelOrder order) {
  if (image.empty() || image.channels() != 3)
    throw std::invalid_argument("night statistics: needs a 3-channel image");
  cv::Mat codes;
  switch (image.depth()) {
    case CV_8U: codes = image; break;
    case CV_16U: image.convertTo(codes, CV_8U, 255.0 / 65535.0); break;
    case CV_32F:
    case CV_64F: image.convertTo(codes, CV_8U, 255.0); break;
    default: throw std::invalid_argument("night statistics: the image must be 8-bit, 16-bit or float");
  }
  cv::Mat rgb;
  if (order == ChannelOrder::Bgr) cv::cvtColor(codes, rgb, cv::COLOR_BGR2RGB);
  else rgb = codes;
  return rgb;
}

/// The luma and the two colour-difference planes (CV_64F) of 8-bit RGB codes.
struct LumaPlanes {
  cv::Mat luma, cb, cr;
};

LumaPlanes lumaPlanes(const cv::Mat& rgb8) {
  LumaPlanes p{cv::Mat(rgb8.size(), CV_64F), cv::Mat(rgb8.size(), CV_64F), cv::Mat(rgb8.size(), CV_64F)};
  for (int y = 0; y < rgb8.rows; ++y) {
    const cv::Vec3b* src = rgb8.ptr<cv::Vec3b>(y);
    double* luma = p.luma.ptr<double>(y);
    double* cb = p.cb.ptr<double>(y);
    double* cr = p.cr.ptr<double>(y);
    for (int x = 0; x < rgb8.cols; ++x) {
      const double r = src[x][0], g = src[x][1], b = src[x][2];
      luma[x] = 0.299 * r + 0.587 * g + 0.114 * b;
      cb[x] = b - luma[x];
      cr[x] = r - luma[x];
    }
  }
  return p;
}

std::vector<double> valuesWhere(const cv::Mat& values, const cv::Mat& mask) {
  std::vector<double> out;
  out.reserve(static_cast<std::size_t>(cv::countNonZero(mask)));
  for (int y = 0; y < values.rows; ++y) {
    const double* v = values.ptr<double>(y);
    const uchar* m = mask.ptr<uchar>(y);
    for (int x = 0; x < values.cols; ++x)
      if (m[x]) out.push_back(v[x]);
  }
  return out;
}

/// The high-pass x minus the mean of its 4 neighbours, divided by sqrt(1.25) (white noise of
/// sigma s gives s), at the interior pixels set in `interior_mask` ((rows - 2) x (cols - 2),
/// element (r, c) = pixel (r + 1, c + 1)).
std::vector<double> highPassWhere(const cv::Mat& plane, const cv::Mat& interior_mask) {
  const double norm = 1.0 / std::sqrt(1.25);
  std::vector<double> out;
  out.reserve(static_cast<std::size_t>(cv::countNonZero(interior_mask)));
  for (int r = 1; r + 1 < plane.rows; ++r) {
    const double* up = plane.ptr<double>(r - 1);
    const double* row = plane.ptr<double>(r);
    const double* down = plane.ptr<double>(r + 1);
    const uchar* m = interior_mask.ptr<uchar>(r - 1);
    for (int c = 1; c + 1 < plane.cols; ++c)
      if (m[c - 1]) out.push_back((row[c] - 0.25 * (up[c] + down[c] + row[c - 1] + row[c + 1])) * norm);
  }
  return out;
}

/// The interior pixels whose noise is measured: 5 < Y < 250 and a flatness at or below the
/// median flatness of those pixels. Flatness at interior pixel (r, c): the gradient magnitude
/// of the 5x5 box-smoothed luma S (edges replicated) by forward differences at (r - 1, c - 1),
/// hypot(S(r, c-1) - S(r-1, c-1), S(r-1, c) - S(r-1, c-1)), as nightstats.py aligns it.
cv::Mat flatMidTones(const cv::Mat& luma) {
  cv::Mat smooth;
  cv::boxFilter(luma, smooth, CV_64F, cv::Size(5, 5), cv::Point(-1, -1), true, cv::BORDER_REPLICATE);
  const cv::Size inner(luma.cols - 2, luma.rows - 2);
  const cv::Mat base = smooth(cv::Rect({0, 0}, inner));
  const cv::Mat dy = smooth(cv::Rect({0, 1}, inner)) - base;
  const cv::Mat dx = smooth(cv::Rect({1, 0}, inner)) - base;
  cv::Mat gradient;
  cv::magnitude(dx, dy, gradient);
  const cv::Mat inner_luma = luma(cv::Rect({1, 1}, inner));
  cv::Mat mid_tones = (inner_luma > 5) & (inner_luma < 250);
  std::vector<double> candidates = valuesWhere(gradient, mid_tones);
  if (candidates.empty()) return mid_tones;  // all zero
  const double threshold = sampleQuantile(candidates, 0.5);
  return mid_tones & (gradient <= threshold);
}

/// 1.4826 x the median absolute deviation from the median; none for no value.
std::optional<double> robustSigma(std::vector<double> values) {
  if (values.empty()) return std::nullopt;
  const double median = sampleQuantile(values, 0.5);
  for (double& v : values) v = std::abs(v - median);
  return 1.4826 * sampleQuantile(values, 0.5);
}

std::optional<double> meanWhere(const cv::Mat& values, const cv::Mat& mask) {
  if (cv::countNonZero(mask) == 0) return std::nullopt;
  return cv::mean(values, mask)[0];
}

/// Adds the luma of row y's pixels x0..x1 (clipped to the image) to sum and count.
void addRowSpan(const cv::Mat& luma, int y, int x0, int x1, double& sum, std::int64_t& count) {
  x0 = std::max(x0, 0);
  x1 = std::min(x1, luma.cols - 1);
  const double* row = luma.ptr<double>(y);
  for (int x = x0; x <= x1; ++x) sum += row[x];
  count += std::max(0, x1 - x0 + 1);
}

/// Mean luma of ring k around `centre`: the pixels at distance d with k - 0.5 <= d < k + 0.5
/// (d < 0.5 for k = 0), walked row by row as the spans between the two circles; none when
/// the ring has no pixel inside the image.
std::optional<double> ringMean(const cv::Mat& luma, cv::Point2d centre, int k) {
  const double outer = k + 0.5, inner = k - 0.5;
  double sum = 0;
  std::int64_t count = 0;
  const int y0 = std::max(0, static_cast<int>(std::floor(centre.y - outer)));
  const int y1 = std::min(luma.rows - 1, static_cast<int>(std::ceil(centre.y + outer)));
  for (int y = y0; y <= y1; ++y) {
    const double dy2 = (y - centre.y) * (y - centre.y);
    if (dy2 >= outer * outer) continue;
    // Pixels x with (x - cx)^2 + dy^2 < outer^2, minus those with (x - cx)^2 + dy^2 < inner^2.
    const double half_outer = std::sqrt(outer * outer - dy2);
    const int left = static_cast<int>(std::floor(centre.x - half_outer)) + 1;
    const int right = static_cast<int>(std::ceil(centre.x + half_outer)) - 1;
    if (k == 0 || dy2 >= inner * inner) {
      addRowSpan(luma, y, left, right, sum, count);
      continue;
    }
    const double half_inner = std::sqrt(inner * inner - dy2);
    const int hole_left = static_cast<int>(std::floor(centre.x - half_inner)) + 1;
    const int hole_right = static_cast<int>(std::ceil(centre.x + half_inner)) - 1;
    addRowSpan(luma, y, left, std::min(right, hole_left - 1), sum, count);
    addRowSpan(luma, y, std::max(left, hole_right + 1), right, sum, count);
  }
  if (count == 0) return std::nullopt;
  return sum / static_cast<double>(count);
}

/// The halo radii of the clipped blobs of at least options.halo_min_blob_px pixels.
std::vector<double> haloRadii(const cv::Mat& luma, double background_luma, const NightStatisticsOptions& options) {
  const cv::Mat clipped = luma >= options.clipped_luma;
  cv::Mat labels, stats, centroids;
  const int count = cv::connectedComponentsWithStats(clipped, labels, stats, centroids, 8, CV_32S);
  const double edge_luma = background_luma + options.halo_headroom_fraction * (255.0 - background_luma);
  std::vector<double> radii;
  for (int blob = 1; blob < count; ++blob) {
    if (stats.at<int>(blob, cv::CC_STAT_AREA) < options.halo_min_blob_px) continue;
    const cv::Point2d centre(centroids.at<double>(blob, 0), centroids.at<double>(blob, 1));
    radii.push_back(haloRadiusPx(luma, centre, edge_luma, options.halo_max_radius_px));
  }
  return radii;
}

}  // namespace

cv::Mat resizeBilinearLikePil(const cv::Mat& rgb8, cv::Size size) {
  if (rgb8.empty() || rgb8.type() != CV_8UC3) throw std::invalid_argument("PIL-like resize: needs a CV_8UC3 image");
  if (size.width <= 0 || size.height <= 0) throw std::invalid_argument("PIL-like resize: empty output size");
  const cv::Mat rows = resampleRows(rgb8, size.width);
  cv::Mat transposed, resampled, out;
  cv::transpose(rows, transposed);
  resampled = resampleRows(transposed, size.height);
  cv::transpose(resampled, out);
  return out;
}

double haloRadiusPx(const cv::Mat& luma, cv::Point2d centre, double edge_luma, int max_radius_px) {
  if (luma.type() != CV_64F) throw std::invalid_argument("halo radius: luma must be CV_64F");
  std::optional<std::pair<double, double>> previous;  // (ring, mean) of the last non-empty ring
  for (int k = 0; k <= max_radius_px; ++k) {
    const std::optional<double> mean = ringMean(luma, centre, k);
    if (!mean) continue;
    if (*mean <= edge_luma) {
      if (!previous) return k;
      const auto [previous_ring, previous_mean] = *previous;
      return previous_ring + (previous_mean - edge_luma) / (previous_mean - *mean) * (k - previous_ring);
    }
    previous = {k, *mean};
  }
  return max_radius_px;
}

NightStatistics computeNightStatistics(const cv::Mat& image, ChannelOrder order, const NightStatisticsOptions& options) {
  NightStatistics s;
  cv::Mat rgb8 = toRgb8(image, order);
  s.source_width_px = rgb8.cols;
  s.source_height_px = rgb8.rows;
  if (rgb8.cols != options.analysis_width_px) {
    // Python's round(): half to even, as nightstats.py computes the height.
    const double height = std::nearbyint(static_cast<double>(rgb8.rows) * options.analysis_width_px / rgb8.cols);
    rgb8 = resizeBilinearLikePil(rgb8, {options.analysis_width_px, std::max(1, static_cast<int>(height))});
  }
  s.analysis_width_px = rgb8.cols;
  s.analysis_height_px = rgb8.rows;
  if (rgb8.cols < 3 || rgb8.rows < 3) throw std::invalid_argument("night statistics: image smaller than 3x3");

  const LumaPlanes planes = lumaPlanes(rgb8);
  const double pixels = static_cast<double>(rgb8.total());
  std::vector<double> luma(planes.luma.begin<double>(), planes.luma.end<double>());
  s.mean_luma = cv::mean(planes.luma)[0];
  s.p50_luma = sampleQuantile(luma, 0.50);
  s.p90_luma = sampleQuantile(luma, 0.90);
  s.p99_luma = sampleQuantile(luma, 0.99);
  s.clipped_share = cv::countNonZero(planes.luma >= options.clipped_luma) / pixels;
  s.bright_share = cv::countNonZero(planes.luma >= options.bright_luma) / pixels;

  const cv::Mat flat = flatMidTones(planes.luma);
  s.noise_luma = robustSigma(highPassWhere(planes.luma, flat));
  const std::optional<double> noise_cb = robustSigma(highPassWhere(planes.cb, flat));
  const std::optional<double> noise_cr = robustSigma(highPassWhere(planes.cr, flat));
  if (noise_cb && noise_cr) s.chroma_noise = 0.5 * (*noise_cb + *noise_cr);

  const cv::Mat dim = (planes.luma > 20) & (planes.luma < 80);
  s.cast_cb = meanWhere(planes.cb, dim);
  s.cast_cr = meanWhere(planes.cr, dim);

  std::vector<double> radii = haloRadii(planes.luma, s.p50_luma, options);
  s.halo_blobs = static_cast<std::int64_t>(radii.size());
  if (!radii.empty()) s.halo_radius_px = sampleQuantile(radii, 0.5);
  return s;
}

std::vector<NamedNightStatistic> namedNightStatistics(const NightStatistics& s) {
  return {{"mean", s.mean_luma, ""},
          {"p50", s.p50_luma, ""},
          {"p90", s.p90_luma, ""},
          {"p99", s.p99_luma, ""},
          {"clipped", s.clipped_share, ""},
          {"bright", s.bright_share, ""},
          {"noise", s.noise_luma, ""},
          {"chroma_noise", s.chroma_noise, ""},
          {"cast_cb", s.cast_cb, ""},
          {"cast_cr", s.cast_cr, ""},
          {"halo_radius_px", s.halo_radius_px, "px"},
          {"halo_blobs", static_cast<double>(s.halo_blobs), ""}};
}

StageReport nightStatisticsReport(const NightStatistics& s, double seconds) {
  StageReport report;
  report.name = "realism";
  report.seconds = seconds;
  const std::vector<NamedNightStatistic> named = namedNightStatistics(s);
  const auto add = [&report](const NamedNightStatistic& n) {
    if (n.key == "halo_blobs") report.add(n.key, static_cast<std::int64_t>(*n.value));
    else if (n.value) report.add(n.key, *n.value, n.unit);
    else report.notes.push_back(n.key + ": none");
  };
  const std::vector<std::string> headline = {"mean", "clipped", "bright", "noise", "chroma_noise", "halo_radius_px"};
  for (const std::string& key : headline)
    for (const NamedNightStatistic& n : named)
      if (n.key == key) add(n);
  for (const NamedNightStatistic& n : named)
    if (std::find(headline.begin(), headline.end(), n.key) == headline.end()) add(n);
  return report;
}

}  // namespace solo
