#include "solo/geometry/normal_guided_objective.h"

#include <opencv2/core/utility.hpp>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>

namespace solo {
namespace {

constexpr int kChunks = 64;  // fixed partition: sums are added in the same order on any thread count

template <typename Body>
void forChunks(int n, Body body) {
  cv::parallel_for_(cv::Range(0, kChunks), [&](const cv::Range& range) {
    for (int c = range.start; c < range.end; ++c) {
      const int begin = static_cast<int>(static_cast<std::int64_t>(n) * c / kChunks);
      const int end = static_cast<int>(static_cast<std::int64_t>(n) * (c + 1) / kChunks);
      body(c, begin, end);
    }
  });
}

}  // namespace

double tangentLoss(TangentLoss loss, double c, double s, double* first, double* second) {
  const double c2 = c * c;
  double value = s, d1 = 1, d2 = 0;
  if (loss == TangentLoss::Huber && s > c2) {
    const double root = std::sqrt(s);
    value = 2 * c * root - c2, d1 = c / root, d2 = -0.5 * d1 / s;
  } else if (loss == TangentLoss::Cauchy) {
    const double t = 1 + s / c2;
    value = c2 * std::log(t), d1 = 1 / t, d2 = -d1 * d1 / c2;
  } else if (loss == TangentLoss::DeadZone) {
    const double root = std::sqrt(s);
    value = d1 = d2 = 0;
    if (root > c) value = (root - c) * (root - c), d1 = 1 - c / root, d2 = 0.5 * c / (root * s);
  }
  if (first) *first = d1;
  if (second) *second = d2;
  return value;
}

NormalGuidedObjectiveOptions NormalGuidedObjectiveOptions::paper() {
  NormalGuidedObjectiveOptions o;
  o.tangent_weight = 50, o.data_weight = 1;
  o.tangent_loss = TangentLoss::Squared;
  o.tangent_stencil = TangentStencil::Central;
  o.data_units = DataUnits::Metres;
  return o;
}

int NormalGuidedObjective::differences(const Axis& a, Difference out[2]) const {
  if (a.before >= 0 && a.after >= 0) {
    if (stencil_ == TangentStencil::Central) {
      out[0] = {0.5, 0, -0.5, 1};
      return 1;
    }
    out[0] = {1, -1, 0, 0.5};
    out[1] = {0, 1, -1, 0.5};
    return 2;
  }
  if (a.after >= 0) {
    out[0] = {1, -1, 0, 1};
    return 1;
  }
  if (a.before >= 0) {
    out[0] = {0, 1, -1, 1};
    return 1;
  }
  return 0;
}

NormalGuidedObjective::NormalGuidedObjective(const cv::Mat& filtered_depth_m, const cv::Mat& normals,
                                             const cv::Mat& uncertain, const PinholeCamera& camera,
                                             const NormalGuidedObjectiveOptions& options, const cv::Mat& segments)
    : size_(filtered_depth_m.size()) {
  CV_Assert(segments.empty() || (segments.type() == CV_32S && segments.size() == size_));
  CV_Assert(filtered_depth_m.type() == CV_32F);
  CV_Assert(normals.empty() || (normals.type() == CV_32FC3 && normals.size() == size_));
  CV_Assert(uncertain.empty() || (uncertain.type() == CV_8U && uncertain.size() == size_));
  const int w = size_.width, h = size_.height;
  std::vector<int> unknown_of(static_cast<std::size_t>(w) * h, -1);
  for (int y = 0; y < h; ++y) {
    const float* d = filtered_depth_m.ptr<float>(y);
    for (int x = 0; x < w; ++x)
      if (d[x] > 0 && std::isfinite(d[x])) {
        unknown_of[static_cast<std::size_t>(y) * w + x] = static_cast<int>(pixel_.size());
        pixel_.push_back(y * w + x);
        filtered_.push_back(d[x]);
      }
  }
  const int m = unknowns();
  const double f = std::sqrt(camera.fx * camera.fy);
  data_weight_.resize(m);
  for (int i = 0; i < m; ++i) {
    const double footprints_per_m = options.data_units == DataUnits::Footprints ? f / filtered_[i] : 1.0;
    data_weight_[i] = options.data_weight / m * footprints_per_m * footprints_per_m;
  }
  stencil_ = options.tangent_stencil;
  loss_ = options.tangent_loss;
  loss_scale_ = options.tangent_loss_scale > 0 ? options.tangent_loss_scale : 1;
  u_.resize(m), v_.resize(m), tangent_weight_.assign(m, 0.0);
  to_after_u_.resize(m), to_before_u_.resize(m), to_after_v_.resize(m), to_before_v_.resize(m), own_.resize(m);
  for (int i = 0; i < m; ++i) {
    const int x = pixel_[i] % w, y = pixel_[i] / w;
    const auto at = [&](int xx, int yy) {
      if (xx < 0 || yy < 0 || xx >= w || yy >= h) return -1;
      if (!segments.empty() && segments.at<int>(yy, xx) != segments.at<int>(y, x)) return -1;
      return unknown_of[static_cast<std::size_t>(yy) * w + xx];
    };
    u_[i].before = at(x - 1, y), u_[i].after = at(x + 1, y);
    v_[i].before = at(x, y - 1), v_[i].after = at(x, y + 1);
    if (normals.empty()) continue;
    cv::Vec3d n = normals.at<cv::Vec3f>(y, x);
    const double length = std::sqrt(n.dot(n));
    if (!std::isfinite(length) || length < 1e-9) continue;
    n /= length;
    const double c = options.tangent_model == TangentModel::Perspective
                         ? n.dot(cv::Vec3d((x - camera.cx) / camera.fx, (y - camera.cy) / camera.fy, 1.0))
                         : n[2];
    u_[i].offset = static_cast<float>(n[0]), u_[i].slope_factor = static_cast<float>(c * camera.fx);
    v_[i].offset = static_cast<float>(n[1]), v_[i].slope_factor = static_cast<float>(c * camera.fy);
    const bool uncertain_here = !uncertain.empty() && uncertain.at<uchar>(y, x) != 0;
    const bool has_residual = u_[i].before >= 0 || u_[i].after >= 0 || v_[i].before >= 0 || v_[i].after >= 0;
    if (!uncertain_here && has_residual && m > 0) {
      tangent_weight_[i] = static_cast<float>(options.tangent_weight / m);
      ++tangent_pixels_;
    }
  }
}

bool NormalGuidedObjective::evaluate(const double* z, ObjectiveValue& value, double* gradient) const {
  const int m = unknowns();
  std::array<double, kChunks> tangent_sums{}, data_sums{};
  std::atomic<bool> ok{true};
  // Pass 1: residuals and value; per unknown the gradient of its own residuals with respect
  // to its neighbours' depths (to_*) and to its own (own_).
  forChunks(m, [&](int chunk, int begin, int end) {
    double tangent_sum = 0, data_sum = 0;
    for (int i = begin; i < end; ++i) {
      const double zi = z[i];
      if (!(zi > 0) || !std::isfinite(zi)) {
        ok = false;
        return;
      }
      const double e = zi - filtered_[i];
      data_sum += data_weight_[i] * e * e;
      to_after_u_[i] = to_before_u_[i] = to_after_v_[i] = to_before_v_[i] = 0;
      own_[i] = 0;
      const double wt = tangent_weight_[i];
      if (wt == 0) continue;
      // Every difference's residual first: the loss weighs them by rho'(s), s their weighted sum of squares.
      Difference diff[2][2];
      int count[2] = {0, 0};
      double d[2][2] = {}, r[2][2] = {}, s = 0;
      for (int axis = 0; axis < 2; ++axis) {
        const Axis& a = axis == 0 ? u_[i] : v_[i];
        count[axis] = differences(a, diff[axis]);
        for (int k = 0; k < count[axis]; ++k) {
          const Difference& c = diff[axis][k];
          d[axis][k] = c.after * (a.after >= 0 ? z[a.after] : 0.0) + c.self * zi +
                       c.before * (a.before >= 0 ? z[a.before] : 0.0);
          r[axis][k] = a.offset + a.slope_factor * d[axis][k] / zi;
          s += c.weight * r[axis][k] * r[axis][k];
        }
      }
      double weight = wt;  // wt rho'(s): the squared loss's weight scaled by the loss's slope
      if (loss_ == TangentLoss::Squared) {
        tangent_sum += wt * s;
      } else {
        double slope_of_loss = 1;
        tangent_sum += wt * tangentLoss(loss_, loss_scale_, s, &slope_of_loss);
        weight = wt * slope_of_loss;
      }
      double own = 0;
      for (int axis = 0; axis < 2; ++axis) {
        const Axis& a = axis == 0 ? u_[i] : v_[i];
        double to_after = 0, to_before = 0;
        for (int k = 0; k < count[axis]; ++k) {
          const Difference& c = diff[axis][k];
          const double slope = 2 * weight * c.weight * r[axis][k] * a.slope_factor / zi;  // d(w rho) / dD
          to_after += slope * c.after, to_before += slope * c.before;
          own += slope * (c.self - d[axis][k] / zi);
        }
        (axis == 0 ? to_after_u_ : to_after_v_)[i] = static_cast<float>(to_after);
        (axis == 0 ? to_before_u_ : to_before_v_)[i] = static_cast<float>(to_before);
      }
      own_[i] = own;
    }
    tangent_sums[chunk] = tangent_sum;
    data_sums[chunk] = data_sum;
  });
  if (!ok) {
    value.total = value.tangent = value.data = std::numeric_limits<double>::infinity();
    return false;
  }
  value.tangent = value.data = 0;
  for (int c = 0; c < kChunks; ++c) value.tangent += tangent_sums[c], value.data += data_sums[c];
  value.total = value.tangent + value.data;
  if (!gradient) return true;
  // Pass 2: gather what the neighbours' residuals send to each unknown.
  forChunks(m, [&](int, int begin, int end) {
    for (int i = begin; i < end; ++i) {
      double g = own_[i] + 2 * data_weight_[i] * (z[i] - filtered_[i]);
      if (u_[i].before >= 0) g += to_after_u_[u_[i].before];  // i is the "after" of its left neighbour
      if (u_[i].after >= 0) g += to_before_u_[u_[i].after];
      if (v_[i].before >= 0) g += to_after_v_[v_[i].before];
      if (v_[i].after >= 0) g += to_before_v_[v_[i].after];
      gradient[i] = g;
    }
  });
  return true;
}

std::vector<double> NormalGuidedObjective::gaussNewtonDiagonal(const double* z) const {
  const int m = unknowns();
  std::vector<double> diagonal(m, 0.0);
  // to_*: the curvature 2 w (f c / z)^2 (dD/dz_neighbour)^2 each residual gives its neighbours.
  forChunks(m, [&](int, int begin, int end) {
    for (int i = begin; i < end; ++i) {
      const double wt = tangent_weight_[i], zi = z[i];
      double own = 0;
      to_after_u_[i] = to_before_u_[i] = to_after_v_[i] = to_before_v_[i] = 0;
      for (int axis = 0; axis < 2; ++axis) {
        const Axis& a = axis == 0 ? u_[i] : v_[i];
        Difference diff[2];
        const int count = wt == 0 ? 0 : differences(a, diff);
        double to_after = 0, to_before = 0;
        for (int k = 0; k < count; ++k) {
          const Difference& c = diff[k];
          const double d = c.after * (a.after >= 0 ? z[a.after] : 0.0) + c.self * zi +
                           c.before * (a.before >= 0 ? z[a.before] : 0.0);
          const double slope = a.slope_factor / zi;
          const double curvature = 2 * wt * c.weight * slope * slope;
          to_after += curvature * c.after * c.after, to_before += curvature * c.before * c.before;
          own += curvature * (c.self - d / zi) * (c.self - d / zi);
        }
        (axis == 0 ? to_after_u_ : to_after_v_)[i] = static_cast<float>(to_after);
        (axis == 0 ? to_before_u_ : to_before_v_)[i] = static_cast<float>(to_before);
      }
      own_[i] = own;
    }
  });
  forChunks(m, [&](int, int begin, int end) {
    for (int i = begin; i < end; ++i) {
      double h = own_[i] + 2 * data_weight_[i];
      if (u_[i].before >= 0) h += to_after_u_[u_[i].before];
      if (u_[i].after >= 0) h += to_before_u_[u_[i].after];
      if (v_[i].before >= 0) h += to_after_v_[v_[i].before];
      if (v_[i].after >= 0) h += to_before_v_[v_[i].after];
      diagonal[i] = h;
    }
  });
  return diagonal;
}

cv::Mat NormalGuidedObjective::toImage(const double* z) const {
  cv::Mat image(size_, CV_32F, cv::Scalar(0));
  auto* out = image.ptr<float>();
  for (int i = 0; i < unknowns(); ++i) out[pixel_[i]] = static_cast<float>(z[i]);
  return image;
}

std::vector<double> NormalGuidedObjective::fromImage(const cv::Mat& depth_m) const {
  CV_Assert(depth_m.type() == CV_32F && depth_m.size() == size_ && depth_m.isContinuous());
  std::vector<double> z(filtered_);
  const auto* in = depth_m.ptr<float>();
  for (int i = 0; i < unknowns(); ++i)
    if (in[pixel_[i]] > 0 && std::isfinite(in[pixel_[i]])) z[i] = in[pixel_[i]];
  return z;
}

NormalGuidedObjective::PixelStencil NormalGuidedObjective::stencil(int i) const {
  PixelStencil s;
  if (tangent_weight_[i] == 0) return s;
  s.unknown[s.count++] = i;
  for (const int j : {u_[i].before, u_[i].after, v_[i].before, v_[i].after})
    if (j >= 0) s.unknown[s.count++] = j;
  return s;
}

void NormalGuidedObjective::tangentResiduals(int i, const double* z_stencil, double residuals[kMaxResiduals],
                                             double jacobian[kMaxResiduals][5]) const {
  const PixelStencil s = stencil(i);
  const double zi = z_stencil[0];
  for (int k = 0; k < kMaxResiduals; ++k) {
    residuals[k] = 0;
    for (int j = 0; j < 5; ++j) jacobian[k][j] = 0;
  }
  for (int axis = 0; axis < 2; ++axis) {
    const Axis& a = axis == 0 ? u_[i] : v_[i];
    int slot_before = -1, slot_after = -1;
    for (int k = 1; k < s.count; ++k) {
      if (s.unknown[k] == a.after) slot_after = k;
      if (s.unknown[k] == a.before) slot_before = k;
    }
    Difference diff[2];
    const int count = differences(a, diff);
    for (int k = 0; k < count; ++k) {
      const Difference& c = diff[k];
      double d = c.self * zi;
      if (slot_after > 0) d += c.after * z_stencil[slot_after];
      if (slot_before > 0) d += c.before * z_stencil[slot_before];
      const double scale = std::sqrt(tangent_weight_[i] * c.weight), slope = a.slope_factor / zi;
      const int row = 2 * axis + k;
      residuals[row] = scale * (a.offset + slope * d);
      jacobian[row][0] = scale * slope * (c.self - d / zi);
      if (slot_after > 0) jacobian[row][slot_after] = scale * slope * c.after;
      if (slot_before > 0) jacobian[row][slot_before] = scale * slope * c.before;
    }
  }
}

}  // namespace solo
