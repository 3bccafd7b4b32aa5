#pragma once
// The objective of SOLO's normal-guided depth optimisation (reference.md section 1.4),
// evaluated with its exact gradient over the whole image. Shared by the Ceres solver
// (normal_guided_optimization.h) and the paper's Adam baseline (adam_depth_optimizer.h), so
// both minimise the same function and their values compare directly.
//
//   L(z) = lambda1 / m * sum_p (1 - U(p)) rho(s(p)) + lambda2 / m * sum_p w(p) (d~(p) - z(p))^2
//
// over the m pixels with a filtered depth d~ > 0 (the unknowns), rho the tangent loss
// (TangentLoss; the paper's is rho(s) = s), s(p) = r_u(p)^2 + r_v(p)^2 (with the one-sided
// stencil, the half-weighted squares of both differences of each axis), w(p) = 1 (metres, the
// paper's) or (f / d~(p))^2 (footprints, DataUnits). r_u = n . t_u and
// r_v = n . t_v are the predicted unit normal n against the surface tangents along the image
// axes, each divided by the pixel footprint z / f so that they are (1, 0, dz/dx) and
// (0, 1, dz/dy) at the principal point, with dz/dx = (dz/du) f_x / z:
//   perspective (default): t_u = (1, 0, 0) + g_u (x', y', 1), exact tangents of the pinhole
//     backprojection z (x', y', 1), x' = (u - cx) / fx, y' = (v - cy) / fy;
//   paper graph: t_u = (1, 0, g_u), the paper's tangents of the graph (x, y, z(x, y)), exact
//     only near the principal point;
// g_u = fx D_u z / z, D_u z the differences of TangentStencil, one-sided where a neighbour is
// invalid, no u residual where both are (likewise along v with fy). Pixels without a valid
// normal have no tangent term. Units: z and d~ metres, the tangent term unitless, the data term
// in square metres or square footprints.

#include "solo/core/camera.h"

#include <opencv2/core.hpp>

#include <array>
#include <vector>

namespace solo {

enum class TangentModel { Perspective, PaperGraph };

/// rho(s) applied to each pixel's s = r_u^2 + r_v^2 in the tangent term, c = tangent_loss_scale:
/// Squared: s (the paper); Huber: s for s <= c^2, else 2 c sqrt(s) - c^2; Cauchy: c^2 log(1 + s / c^2);
/// DeadZone: 0 for sqrt(s) <= c, else (sqrt(s) - c)^2: a slope within the predicted normal's
/// tolerance c costs nothing (the data term keeps the depth's own slope there), one beyond it is
/// pulled back to the tolerance. Convex, C1.
enum class TangentLoss { Squared, Huber, Cauchy, DeadZone };

/// rho(s) of `loss` with scale c; its first and second derivatives by s when not null.
double tangentLoss(TangentLoss loss, double c, double s, double* first = nullptr, double* second = nullptr);

/// The difference D z of each axis. Central: the paper's (z(u+1) - z(u-1)) / 2, blind to a depth
/// that alternates between odd and even pixels (that mode is held by the data term only).
/// OneSided: both one-sided differences z(u+1) - z(u) and z(u) - z(u-1) as two residuals of half
/// weight each, which couple every pixel to its neighbours.
enum class TangentStencil { Central, OneSided };

/// Units of the data term's residual z - d~. Metres: the paper's (lambda2 in 1 / m^2 against a
/// unitless tangent term, so how far normal errors integrate grows with the depth). Footprints:
/// (z - d~) / (d~ / f), f = sqrt(fx fy), the residual in pixel footprints at d~, the tangent
/// term's unit: the trade-off is the same at every depth.
enum class DataUnits { Metres, Footprints };

/// Defaults: the objective that improves the normals of the depth without making the depth
/// worse on the synthetic benchmark (docs/depth-refinement.md): one-sided differences, the data
/// term in footprints with lambda2 = 3 (normal information spreads over about
/// sqrt(lambda1 / lambda2) = 4 px), a Cauchy tangent loss of scale 0.2 (a predicted normal more
/// than about 11 deg from the depth's slope counts as an outlier). paper() gives the paper's.
struct NormalGuidedObjectiveOptions {
  double tangent_weight = 50;  ///< lambda1 (reference: 50)
  double data_weight = 3;      ///< lambda2 (reference: 1, in metres)
  TangentModel tangent_model = TangentModel::Perspective;
  TangentLoss tangent_loss = TangentLoss::Cauchy;  ///< (reference: squared)
  double tangent_loss_scale = 0.2;                 ///< c of the robust losses (a residual, unitless)
  TangentStencil tangent_stencil = TangentStencil::OneSided;  ///< (reference: central)
  DataUnits data_units = DataUnits::Footprints;               ///< (reference: metres)

  /// The paper's objective (reference.md section 1.4): lambda1 = 50, lambda2 = 1 on metres,
  /// central differences, squared loss; the perspective tangents.
  static NormalGuidedObjectiveOptions paper();
};

/// The objective's parts: total = tangent + data, each already weighted and divided by m.
struct ObjectiveValue {
  double total = 0;
  double tangent = 0;  ///< lambda1 * L1
  double data = 0;     ///< lambda2 * L2 (square metres or square footprints, DataUnits)
};

class NormalGuidedObjective {
 public:
  /// filtered_depth_m: CV_32F metres (0 = invalid: not an unknown); normals: CV_32FC3 camera
  /// frame of the same size ((0,0,0) or non-finite = none; renormalised; orientation does not
  /// matter, r is odd in n) or empty (no tangent term); uncertain: CV_8U (non-zero = U = 1) or
  /// empty; camera at this resolution. segments: CV_32S instance labels or empty; when given,
  /// differences never pair pixels of two labels (a depth edge has no tangent), which makes
  /// the difference one-sided or absent there.
  NormalGuidedObjective(const cv::Mat& filtered_depth_m, const cv::Mat& normals, const cv::Mat& uncertain,
                        const PinholeCamera& camera, const NormalGuidedObjectiveOptions& options = {},
                        const cv::Mat& segments = {});

  int unknowns() const { return static_cast<int>(pixel_.size()); }
  /// Unknowns with at least one tangent residual.
  int tangentPixels() const { return tangent_pixels_; }
  /// d~ at the unknowns, in row-major pixel order: the start of every solver.
  const std::vector<double>& filteredDepths() const { return filtered_; }

  /// Value (and, when `gradient` is not null, dL/dz) at depths z (metres, one per unknown).
  /// Returns false, with an infinite value, when some z is not finite and positive.
  /// Not thread-safe (it uses scratch buffers); it parallelises internally.
  bool evaluate(const double* z, ObjectiveValue& value, double* gradient = nullptr) const;

  /// Diagonal of the Gauss-Newton matrix 2 J^T J at z (the curvature of L per unknown), of the
  /// squared tangent loss whatever the loss: a robust loss's rho' = 0 would make it the data
  /// term's alone and the Jacobi-scaled steps huge.
  std::vector<double> gaussNewtonDiagonal(const double* z) const;

  /// Depth image (CV_32F, 0 at non-unknowns) of z.
  cv::Mat toImage(const double* z) const;
  /// Values of a depth image at the unknowns; pixels <= 0 there take d~.
  std::vector<double> fromImage(const cv::Mat& depth_m) const;

  /// One pixel's tangent residuals for residual-block layouts (without the loss rho): the
  /// unknowns they depend on (the pixel itself first, then its stencil neighbours),
  /// sqrt(weight) * r of each difference (kMaxResiduals: u then v, two differences each with the
  /// one-sided stencil; absent ones are 0) and their derivatives by each of those unknowns.
  /// count = 0 when the pixel has no tangent term.
  static constexpr int kMaxResiduals = 4;
  struct PixelStencil {
    int count = 0;
    std::array<int, 5> unknown{};
  };
  PixelStencil stencil(int i) const;
  /// z_stencil: the depths of stencil(i).unknown[0..count). jacobian[k][j] = d residual_k / d z_j.
  void tangentResiduals(int i, const double* z_stencil, double residuals[kMaxResiduals],
                        double jacobian[kMaxResiduals][5]) const;
  /// Unknown i's data term is dataWeight(i) * (z - d~)^2: lambda2 / m, times (f / d~)^2 in footprints.
  double dataWeight(int i) const { return data_weight_[i]; }
  /// lambda1 (1 - U) / m of unknown i (0 without a tangent term): its term is weight * rho(s).
  double tangentWeight(int i) const { return tangent_weight_[i]; }
  TangentLoss loss() const { return loss_; }
  double lossScale() const { return loss_scale_; }

 private:
  struct Axis {  // one image axis of one unknown's tangent residual
    int before = -1, after = -1;  // unknowns at -1 and +1 along the axis, -1 = none
    float offset = 0;             // n_x (or n_y): the residual at zero slope
    float slope_factor = 0;       // c * f: r = offset + slope_factor * D z / z
  };
  // One difference of an axis, D = after z_after + self z + before z_before, its residual weighted by `weight`.
  struct Difference {
    double after = 0, self = 0, before = 0, weight = 0;
  };
  // The differences of an axis under the stencil (0, 1 or 2; one-sided where a neighbour is missing).
  int differences(const Axis& a, Difference out[2]) const;

  cv::Size size_;
  std::vector<int> pixel_;  // row-major pixel index of each unknown
  std::vector<double> filtered_;
  std::vector<Axis> u_, v_;
  std::vector<float> tangent_weight_;  // lambda1 (1 - U) / m, 0 without a normal
  std::vector<double> data_weight_;    // per unknown, see dataWeight()
  TangentStencil stencil_ = TangentStencil::Central;
  TangentLoss loss_ = TangentLoss::Squared;
  double loss_scale_ = 1;
  int tangent_pixels_ = 0;
  // Scratch of evaluate(): per unknown, the gradient its residuals send to its +1 and -1
  // neighbours along u and v, and to itself.
  mutable std::vector<float> to_after_u_, to_before_u_, to_after_v_, to_before_v_;
  mutable std::vector<double> own_;
};

}  // namespace solo
