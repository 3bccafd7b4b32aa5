#include "solo/geometry/depth_completion.h"

#include "solo/geometry/depth_mesh.h"

#include <opencv2/core/utility.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <unordered_map>
#include <vector>

namespace solo {
namespace {

// One pull step: each coarse pixel holds the weighted mean of its (up to) 2x2 children and the
// sum of their weights, capped at 1.
void pullLevel(const cv::Mat& value, const cv::Mat& weight, cv::Mat& coarse_value, cv::Mat& coarse_weight) {
  const int w = (value.cols + 1) / 2, h = (value.rows + 1) / 2;
  coarse_value.create(h, w, CV_32F);
  coarse_weight.create(h, w, CV_32F);
  for (int y = 0; y < h; ++y) {
    const int y0 = 2 * y, y1 = std::min(2 * y + 1, value.rows - 1);
    float* cv_row = coarse_value.ptr<float>(y);
    float* cw_row = coarse_weight.ptr<float>(y);
    for (int x = 0; x < w; ++x) {
      const int x0 = 2 * x, x1 = std::min(2 * x + 1, value.cols - 1);
      double sum_w = 0, sum_wv = 0;
      for (int yy = y0; yy <= y1; ++yy)
        for (int xx = x0; xx <= x1; ++xx) {
          const float wt = weight.at<float>(yy, xx);
          sum_w += wt;
          sum_wv += wt * value.at<float>(yy, xx);
        }
      cv_row[x] = sum_w > 0 ? static_cast<float>(sum_wv / sum_w) : 0.f;
      cw_row[x] = static_cast<float>(std::min(1.0, sum_w));
    }
  }
}

// One push step: the holes (weight < 1) of a level take the bilinearly sampled coarser level,
// blended by their own weight.
void pushLevel(cv::Mat& value, const cv::Mat& weight, const cv::Mat& coarse) {
  const int cw = coarse.cols, ch = coarse.rows;
  for (int y = 0; y < value.rows; ++y) {
    float* v_row = value.ptr<float>(y);
    const float* w_row = weight.ptr<float>(y);
    const float cy = std::clamp((y + 0.5f) * 0.5f - 0.5f, 0.f, static_cast<float>(ch - 1));
    const int y0 = static_cast<int>(cy), y1 = std::min(y0 + 1, ch - 1);
    const float fy = cy - static_cast<float>(y0);
    for (int x = 0; x < value.cols; ++x) {
      const float wt = w_row[x];
      if (wt >= 1.f) continue;
      const float cx = std::clamp((x + 0.5f) * 0.5f - 0.5f, 0.f, static_cast<float>(cw - 1));
      const int x0 = static_cast<int>(cx), x1 = std::min(x0 + 1, cw - 1);
      const float fx = cx - static_cast<float>(x0);
      const float top = coarse.at<float>(y0, x0) * (1 - fx) + coarse.at<float>(y0, x1) * fx;
      const float bottom = coarse.at<float>(y1, x0) * (1 - fx) + coarse.at<float>(y1, x1) * fx;
      const float parent = top * (1 - fy) + bottom * fy;
      v_row[x] = wt * v_row[x] + (1 - wt) * parent;
    }
  }
}

struct Segment {
  int x0 = std::numeric_limits<int>::max(), y0 = std::numeric_limits<int>::max(), x1 = -1, y1 = -1;
  std::int64_t valid = 0, holes = 0;
  void include(int x, int y) {
    x0 = std::min(x0, x), y0 = std::min(y0, y), x1 = std::max(x1, x), y1 = std::max(y1, y);
  }
};

// The sky: labelIds == 23, or without labels the invalid pixels above the first depth of every
// column within +-sky_column_window (a LiDAR's columns between returns are not sky).
cv::Mat skyMask(const cv::Mat& depth_m, const cv::Mat& labels, int window_px) {
  if (!labels.empty()) return labels == kSkyClassId;
  std::vector<int> first_row(static_cast<std::size_t>(depth_m.cols), depth_m.rows);
  for (int x = 0; x < depth_m.cols; ++x)
    for (int y = 0; y < depth_m.rows; ++y)
      if (depth_m.at<float>(y, x) > 0) {
        first_row[static_cast<std::size_t>(x)] = y;
        break;
      }
  cv::Mat sky(depth_m.size(), CV_8U, cv::Scalar(0));
  for (int x = 0; x < depth_m.cols; ++x) {
    int top = depth_m.rows;
    for (int k = std::max(0, x - window_px); k <= std::min(depth_m.cols - 1, x + window_px); ++k)
      top = std::min(top, first_row[static_cast<std::size_t>(k)]);
    for (int y = 0; y < top; ++y) sky.at<std::uint8_t>(y, x) = 255;
  }
  return sky;
}

// An inverse-depth plane q = a x + b y + c (pixels), the trend of a planar segment.
struct InversePlane {
  double a = 0, b = 0, c = 0;
  double at(int x, int y) const { return a * x + b * y + c; }
};

struct CompletionState {
  cv::Mat inverse_depth;  // CV_32F 1/z where valid or filled, 0 elsewhere
  cv::Mat valid, sky;     // CV_8U
  cv::Mat segments;       // CV_32S
  cv::Mat hole;           // CV_8U: invalid and not sky
  cv::Mat extended;       // CV_8U: holes above their column's first depth, given the depth below them
  cv::Mat segment_free;   // CV_8U: the pixel's segment has no valid pixel (filled across borders)
  std::unordered_map<int, InversePlane> planes;  // the planar segments' trends
};

std::unordered_map<int, Segment> describeSegments(const CompletionState& s) {
  std::unordered_map<int, Segment> segments;
  for (int y = 0; y < s.segments.rows; ++y) {
    const int* id = s.segments.ptr<int>(y);
    const std::uint8_t* valid = s.valid.ptr<std::uint8_t>(y);
    const std::uint8_t* hole = s.hole.ptr<std::uint8_t>(y);
    const std::uint8_t* extended = s.extended.ptr<std::uint8_t>(y);
    Segment* cached = nullptr;
    int cached_id = 0;
    for (int x = 0; x < s.segments.cols; ++x) {
      if (!cached || id[x] != cached_id) cached = &segments[id[x]], cached_id = id[x];
      if (!valid[x] && !hole[x]) continue;  // sky
      cached->include(x, y);
      cached->valid += valid[x] || extended[x] ? 1 : 0;
      cached->holes += hole[x] && !extended[x] ? 1 : 0;
    }
  }
  return segments;
}

// Step 2: a hole above the first depth of its column takes the nearest depth below it of its own
// segment; in a column where its segment has no depth below it, it is left to step 3 when the
// segment has depth elsewhere (the rest of a facade says more than the car or pole below it) and
// takes the nearest depth below it when the segment has none: a vertical surface (a facade, a
// vehicle's back) keeps its depth along an image column, and nothing above says otherwise.
// Only with labels (`sky_by_labels`): without them the sky is what lies above the first depth of
// the columns around, so the holes above a column's own first depth lie between the rows of a
// sparse sensor (a LiDAR's columns between returns); extended, every column would carry its
// first return up as a streak, so they are interpolated (step 3). Returns the pixels extended.
std::int64_t extendColumnsUpward(CompletionState& s, bool sky_by_labels) {
  const int w = s.hole.cols, h = s.hole.rows;
  s.extended = cv::Mat(s.hole.size(), CV_8U, cv::Scalar(0));
  std::int64_t extended = 0;
  if (!sky_by_labels) return extended;
  const std::unordered_map<int, Segment> segments = describeSegments(s);  // nothing extended yet
  const auto has_depth = [&segments](int id) {
    const auto it = segments.find(id);
    return it != segments.end() && it->second.valid > 0;
  };
  std::vector<std::pair<int, float>> below_by_segment;  // nearest depth below, per segment
  for (int x = 0; x < w; ++x) {
    int first = h;
    for (int y = 0; y < h && first == h; ++y)
      if (s.valid.at<std::uint8_t>(y, x)) first = y;
    if (first == 0 || first == h) continue;
    below_by_segment.clear();
    float below_any = 0;
    for (int y = h - 1; y >= 0; --y) {
      const int id = s.segments.at<int>(y, x);
      if (s.valid.at<std::uint8_t>(y, x)) {
        const float q = s.inverse_depth.at<float>(y, x);
        below_any = q;
        const auto it = std::find_if(below_by_segment.begin(), below_by_segment.end(),
                                     [id](const auto& e) { return e.first == id; });
        if (it != below_by_segment.end()) it->second = q;
        else below_by_segment.emplace_back(id, q);
        continue;
      }
      if (y >= first || !s.hole.at<std::uint8_t>(y, x)) continue;
      const auto it = std::find_if(below_by_segment.begin(), below_by_segment.end(),
                                   [id](const auto& e) { return e.first == id; });
      if (it == below_by_segment.end() && has_depth(id)) continue;
      s.inverse_depth.at<float>(y, x) = it != below_by_segment.end() ? it->second : below_any;
      s.extended.at<std::uint8_t>(y, x) = 255;
      ++extended;
    }
  }
  return extended;
}

// Least squares of q = a x + b y + c over `samples` (x, y, q), weighted.
bool fitPlane(const std::vector<cv::Vec3d>& samples, const std::vector<double>& weights, InversePlane& plane) {
  cv::Matx33d normal = cv::Matx33d::zeros();
  cv::Vec3d rhs(0, 0, 0);
  for (std::size_t i = 0; i < samples.size(); ++i) {
    const cv::Vec3d row(samples[i][0], samples[i][1], 1);
    normal += weights[i] * row * row.t();
    rhs += weights[i] * samples[i][2] * row;
  }
  cv::Vec3d coefficients;
  if (!cv::solve(normal, rhs, coefficients, cv::DECOMP_CHOLESKY)) return false;
  plane = {coefficients[0], coefficients[1], coefficients[2]};
  return std::isfinite(plane.a) && std::isfinite(plane.b) && std::isfinite(plane.c);
}

// A segment's inverse-depth plane when its depth is one (median residual below
// planar_tolerance of its median inverse depth, after one reweighting that drops outliers
// beyond 3 median residuals): the road, a facade. Up to ~20000 samples.
bool segmentPlane(const CompletionState& s, int id, const cv::Rect& rect, double planar_tolerance, InversePlane& plane) {
  std::vector<cv::Vec3d> samples;
  const std::int64_t area = static_cast<std::int64_t>(rect.area());
  const int stride = std::max(1, static_cast<int>(std::sqrt(static_cast<double>(area) / 20000.0)));
  for (int y = rect.y; y < rect.y + rect.height; y += stride)
    for (int x = rect.x; x < rect.x + rect.width; x += stride)
      if (s.valid.at<std::uint8_t>(y, x) && s.segments.at<int>(y, x) == id)
        samples.emplace_back(x, y, s.inverse_depth.at<float>(y, x));
  if (samples.size() < 50) return false;
  std::vector<double> weights(samples.size(), 1.0), residuals(samples.size()), values(samples.size());
  for (int pass = 0; pass < 2; ++pass) {
    if (!fitPlane(samples, weights, plane)) return false;
    for (std::size_t i = 0; i < samples.size(); ++i) {
      residuals[i] = std::abs(samples[i][2] - plane.at(static_cast<int>(samples[i][0]), static_cast<int>(samples[i][1])));
      values[i] = samples[i][2];
    }
    std::vector<double> sorted = residuals;
    std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 2), sorted.end());
    const double median_residual = sorted[sorted.size() / 2];
    for (std::size_t i = 0; i < samples.size(); ++i) weights[i] = residuals[i] <= 3 * median_residual + 1e-12 ? 1 : 0;
    if (pass == 1) {
      std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2), values.end());
      return median_residual <= planar_tolerance * values[values.size() / 2];
    }
  }
  return false;
}

// Step 3: a segment's holes from the segment's own valid pixels, within its bounding box: the
// residual from the segment's plane (planar segments) or the inverse depth itself, pull-pushed.
void fillWithinSegment(CompletionState& s, int id, const Segment& box, double planar_tolerance) {
  const cv::Rect rect(box.x0, box.y0, box.x1 - box.x0 + 1, box.y1 - box.y0 + 1);
  const cv::Mat ids = s.segments(rect), valid = s.valid(rect) | s.extended(rect), hole = s.hole(rect) & ~s.extended(rect);
  InversePlane plane;
  const bool planar = segmentPlane(s, id, rect, planar_tolerance, plane);
  if (planar) s.planes[id] = plane;
  const auto trend = [&](int x, int y) { return planar ? plane.at(x + rect.x, y + rect.y) : 0.0; };
  cv::Mat weight(rect.size(), CV_32F, cv::Scalar(0)), value(rect.size(), CV_32F, cv::Scalar(0));
  for (int y = 0; y < rect.height; ++y)
    for (int x = 0; x < rect.width; ++x)
      if (valid.at<std::uint8_t>(y, x) && ids.at<int>(y, x) == id) {
        weight.at<float>(y, x) = 1;
        value.at<float>(y, x) = static_cast<float>(s.inverse_depth(rect).at<float>(y, x) - trend(x, y));
      }
  const cv::Mat dense = pullPushInterpolate(value, weight);
  cv::Mat out = s.inverse_depth(rect);
  for (int y = 0; y < rect.height; ++y)
    for (int x = 0; x < rect.width; ++x)
      if (hole.at<std::uint8_t>(y, x) && ids.at<int>(y, x) == id)
        out.at<float>(y, x) = static_cast<float>(dense.at<float>(y, x) + trend(x, y));
}

// Step 4: the holes of segments without depth, from every pixel that has a depth after step 3.
void fillAcrossSegments(CompletionState& s) {
  cv::Mat weight(s.inverse_depth.size(), CV_32F, cv::Scalar(0));
  for (int y = 0; y < weight.rows; ++y)
    for (int x = 0; x < weight.cols; ++x)
      if (s.inverse_depth.at<float>(y, x) > 0 && !s.segment_free.at<std::uint8_t>(y, x)) weight.at<float>(y, x) = 1;
  const cv::Mat dense = pullPushInterpolate(s.inverse_depth, weight);
  for (int y = 0; y < weight.rows; ++y)
    for (int x = 0; x < weight.cols; ++x)
      if (s.segment_free.at<std::uint8_t>(y, x) && s.hole.at<std::uint8_t>(y, x) && !s.extended.at<std::uint8_t>(y, x))
        s.inverse_depth.at<float>(y, x) = dense.at<float>(y, x);
}

// A filled pixel's neighbours in the relaxation and their edge weights.
struct RelaxNode {
  int index = 0;
  std::array<int, 4> neighbour{};
  std::array<float, 4> weight{};
  std::array<float, 4> shift{};  // the plane trend's step to the neighbour, subtracted from its value
};

// The nodes of row y, in pixel order.
void relaxationRow(const CompletionState& s, const cv::Mat& image, float inv_two_sigma2, int y,
                   std::vector<RelaxNode>& nodes) {
  const int w = s.hole.cols, h = s.hole.rows;
  constexpr int kDx[4] = {1, -1, 0, 0}, kDy[4] = {0, 0, 1, -1};
  for (int x = 0; x < w; ++x) {
    if (!s.hole.at<std::uint8_t>(y, x) || s.extended.at<std::uint8_t>(y, x)) continue;
    RelaxNode node;
    node.index = y * w + x;
    const int id = s.segments.at<int>(y, x);
    const bool free = s.segment_free.at<std::uint8_t>(y, x) != 0;
    const auto plane = free ? s.planes.end() : s.planes.find(id);
    for (int k = 0; k < 4; ++k) {
      const int nx = x + kDx[k], ny = y + kDy[k];
      node.neighbour[k] = node.index;
      if (nx < 0 || ny < 0 || nx >= w || ny >= h || s.sky.at<std::uint8_t>(ny, nx)) continue;
      if (!free && s.segments.at<int>(ny, nx) != id) continue;
      float wt = 1;
      if (!image.empty()) {
        const cv::Vec3f d = image.at<cv::Vec3f>(y, x) - image.at<cv::Vec3f>(ny, nx);
        wt = std::exp(-d.dot(d) * inv_two_sigma2);
      }
      node.neighbour[k] = ny * w + nx;
      node.weight[k] = std::max(wt, 1e-6f);
      if (plane != s.planes.end())
        node.shift[k] = static_cast<float>(-(plane->second.a * kDx[k] + plane->second.b * kDy[k]));
    }
    nodes.push_back(node);
  }
}

// Every filled pixel's node, in pixel order (rows built in parallel, joined in order).
std::vector<RelaxNode> relaxationNodes(const CompletionState& s, const cv::Mat& image, double sigma_color) {
  const float inv_two_sigma2 = static_cast<float>(1.0 / (2 * sigma_color * sigma_color));
  std::vector<std::vector<RelaxNode>> rows(static_cast<std::size_t>(s.hole.rows));
  cv::parallel_for_(cv::Range(0, s.hole.rows), [&](const cv::Range& range) {
    for (int y = range.start; y < range.end; ++y)
      relaxationRow(s, image, inv_two_sigma2, y, rows[static_cast<std::size_t>(y)]);
  });
  std::size_t count = 0;
  for (const auto& row : rows) count += row.size();
  std::vector<RelaxNode> nodes;
  nodes.reserve(count);
  for (const auto& row : rows) nodes.insert(nodes.end(), row.begin(), row.end());
  return nodes;
}

// Step 5: red-black successive over-relaxation of the edge-weighted membrane over the filled
// pixels (a 4-neighbour's parity differs from its centre's, so each half-sweep is parallel).
void relax(CompletionState& s, const cv::Mat& image, const DepthCompletionOptions& options) {
  if (options.relax_iterations <= 0) return;
  std::vector<RelaxNode> nodes = relaxationNodes(s, image, options.sigma_color);
  if (nodes.empty()) return;
  const int width = s.hole.cols;
  const auto parity = [width](const RelaxNode& n) { return (n.index / width + n.index % width) % 2; };
  const auto middle = std::stable_partition(nodes.begin(), nodes.end(), [&](const RelaxNode& n) { return parity(n) == 0; });
  const int split = static_cast<int>(middle - nodes.begin());
  float* q = s.inverse_depth.ptr<float>();
  const float omega = static_cast<float>(options.over_relaxation);
  const auto half_sweep = [&](int begin, int end) {
    cv::parallel_for_(cv::Range(begin, end), [&](const cv::Range& range) {
      for (int i = range.start; i < range.end; ++i) {
        const RelaxNode& n = nodes[static_cast<std::size_t>(i)];
        float sum_w = 0, sum_wv = 0;
        for (int k = 0; k < 4; ++k) sum_w += n.weight[k], sum_wv += n.weight[k] * (q[n.neighbour[k]] + n.shift[k]);
        if (sum_w > 0) q[n.index] = (1 - omega) * q[n.index] + omega * sum_wv / sum_w;
      }
    });
  };
  for (int it = 0; it < options.relax_iterations; ++it) {
    half_sweep(0, split);
    half_sweep(split, static_cast<int>(nodes.size()));
  }
}

CompletionState initialState(const cv::Mat& depth_m, const cv::Mat& labels, const cv::Mat& instances,
                             const DepthCompletionOptions& options) {
  CompletionState s;
  s.valid = depth_m > 0;
  const int window_px = std::max(1, static_cast<int>(std::lround(options.sky_column_window * depth_m.cols)));
  s.sky = skyMask(depth_m, labels, window_px);
  s.hole = ~s.valid & ~s.sky;
  s.segments = !instances.empty() ? instances.clone()
               : !labels.empty()  ? labels.clone()
                                  : cv::Mat(depth_m.size(), CV_32S, cv::Scalar(0));
  s.inverse_depth = cv::Mat(depth_m.size(), CV_32F, cv::Scalar(0));
  for (int y = 0; y < depth_m.rows; ++y)
    for (int x = 0; x < depth_m.cols; ++x) {
      const float d = depth_m.at<float>(y, x);
      if (d > 0) s.inverse_depth.at<float>(y, x) = 1.f / d;
    }
  s.segment_free = cv::Mat(depth_m.size(), CV_8U, cv::Scalar(0));
  return s;
}

}  // namespace

cv::Mat pullPushInterpolate(const cv::Mat& value, const cv::Mat& weight) {
  CV_Assert(value.type() == CV_32F && weight.type() == CV_32F && value.size() == weight.size());
  std::vector<cv::Mat> values{value.clone()}, weights{weight.clone()};
  while (values.back().cols > 1 || values.back().rows > 1) {
    cv::Mat v, w;
    pullLevel(values.back(), weights.back(), v, w);
    values.push_back(v), weights.push_back(w);
  }
  if (!(weights.back().at<float>(0, 0) > 0)) return cv::Mat(value.size(), CV_32F, cv::Scalar(0));
  for (int level = static_cast<int>(values.size()) - 2; level >= 0; --level)
    pushLevel(values[static_cast<std::size_t>(level)], weights[static_cast<std::size_t>(level)],
              values[static_cast<std::size_t>(level) + 1]);
  return values.front();
}

DepthCompletionResult completeDepth(const cv::Mat& depth_m, const cv::Mat& image, const cv::Mat& labels,
                                    const cv::Mat& instances, const DepthCompletionOptions& options) {
  CV_Assert(depth_m.type() == CV_32F);
  CV_Assert(image.empty() || (image.type() == CV_32FC3 && image.size() == depth_m.size()));
  CV_Assert(labels.empty() || (labels.type() == CV_32S && labels.size() == depth_m.size()));
  CV_Assert(instances.empty() || (instances.type() == CV_32S && instances.size() == depth_m.size()));
  const Stopwatch clock;
  DepthCompletionResult result;
  StageReport& report = result.report;
  report.name = "complete";
  CompletionState s = initialState(depth_m, labels, instances, options);
  result.sky = s.sky;
  const std::int64_t holes = cv::countNonZero(s.hole), valid = cv::countNonZero(s.valid);
  report.add("sky_rule", std::string(labels.empty() ? "no depth above (no labels)" : "labels (class 23)"));
  report.add("sky_pixels", static_cast<std::int64_t>(cv::countNonZero(s.sky)));
  if (holes == 0 || valid == 0) {
    result.depth_m = depth_m.clone();
    result.filled = cv::Mat(depth_m.size(), CV_8U, cv::Scalar(0));
    report.add("filled_pixels", std::int64_t{0}).add("filled_share", 0.0, "%");
    if (valid == 0) report.notes.push_back("no valid depth: nothing to complete from");
    report.seconds = clock.seconds();
    return result;
  }

  // Steps 2 to 4.
  const std::int64_t extended = extendColumnsUpward(s, !labels.empty());
  std::int64_t within = 0, across_segments = 0, across_pixels = 0;
  for (const auto& [id, segment] : describeSegments(s)) {
    if (segment.holes == 0) continue;
    if (segment.valid > 0) {
      fillWithinSegment(s, id, segment, options.planar_tolerance);
      ++within;
      continue;
    }
    ++across_segments, across_pixels += segment.holes;
    s.segment_free.setTo(255, s.segments == id);
  }
  if (across_segments > 0) fillAcrossSegments(s);
  relax(s, image, options);

  // Back to depth, clamped to the valid depths' range; valid pixels unchanged.
  double min_depth = 0, max_depth = 0;
  cv::minMaxLoc(depth_m, &min_depth, &max_depth, nullptr, nullptr, s.valid);
  result.depth_m = depth_m.clone();
  for (int y = 0; y < depth_m.rows; ++y)
    for (int x = 0; x < depth_m.cols; ++x) {
      if (!s.hole.at<std::uint8_t>(y, x)) continue;
      const float q = s.inverse_depth.at<float>(y, x);
      const double d = q > 0 && std::isfinite(q) ? 1.0 / q : max_depth;
      result.depth_m.at<float>(y, x) = static_cast<float>(std::clamp(d, min_depth, max_depth));
    }
  result.filled = s.hole.clone();

  const double non_sky = static_cast<double>(valid + holes);
  report.add("filled_pixels", holes).add("filled_share", 100.0 * static_cast<double>(holes) / non_sky, "%");
  report.add("extended_upward_pixels", extended);
  report.add("planar_segments", static_cast<std::int64_t>(s.planes.size()));
  report.add("segments_filled_within", within).add("segments_without_depth", across_segments);
  report.add("pixels_filled_across_segments", across_pixels);
  report.add("relax_iterations", static_cast<std::int64_t>(options.relax_iterations));
  report.seconds = clock.seconds();
  return result;
}

}  // namespace solo
