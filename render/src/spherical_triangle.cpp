#include "solo/render/spherical_triangle.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>

namespace solo {
namespace {

constexpr double kPi = 3.14159265358979323846;

// The unit part of v orthogonal to the unit vector `axis`; false when v is (nearly) along it.
bool orthogonalUnit(const Eigen::Vector3d& v, const Eigen::Vector3d& axis, Eigen::Vector3d* out) {
  const Eigen::Vector3d w = v - v.dot(axis) * axis;
  const double norm = w.norm();
  if (!(norm > 1e-300)) return false;
  *out = w / norm;
  return true;
}

// Angle (radians) at vertex `at` of the spherical triangle between the arcs toward p and q:
// the angle between their tangents at `at`, by atan2 for accuracy near 0 and pi.
double vertexAngle(const Eigen::Vector3d& at, const Eigen::Vector3d& p, const Eigen::Vector3d& q) {
  const Eigen::Vector3d tp = p - p.dot(at) * at, tq = q - q.dot(at) * at;
  return std::atan2(tp.cross(tq).norm(), tp.dot(tq));
}

// Sampling the bilinear density on [0, 1]^2 with corner values w[0] at (0, 0), w[1] at (1, 0),
// w[2] at (0, 1), w[3] at (1, 1): the second coordinate from its marginal, then the first
// from its conditional, each a linear density on [0, 1].
double sampleLinear(double u, double a, double b) {  // density proportional to (1 - x) a + x b
  if (std::abs(a - b) < 1e-9 * (a + b)) return u;
  const double x = (a - std::sqrt(std::max(0.0, a * a * (1 - u) + b * b * u))) / (a - b);
  return std::clamp(x, 0.0, 1.0);
}

double bilinearPdf(double x, double y, const std::array<double, 4>& w) {
  const double sum = w[0] + w[1] + w[2] + w[3];
  if (!(sum > 0)) return 1;
  return 4 * ((1 - x) * (1 - y) * w[0] + x * (1 - y) * w[1] + (1 - x) * y * w[2] + x * y * w[3]) / sum;
}

void sampleBilinear(double u1, double u2, const std::array<double, 4>& w, double* x, double* y) {
  *y = sampleLinear(u2, w[0] + w[1], w[2] + w[3]);
  *x = sampleLinear(u1, (1 - *y) * w[0] + *y * w[2], (1 - *y) * w[1] + *y * w[3]);
}

// Corner weights: the receiver's cosine toward the triangle corner each corner of the unit
// square maps to ((0, 0) and (1, 0): b; (0, 1): a; (1, 1): c), at least 0.01.
std::array<double, 4> cosineCorners(const Eigen::Vector3d& point, const Eigen::Vector3d& normal, const Eigen::Vector3d& a,
                                    const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const auto cosine = [&](const Eigen::Vector3d& v) { return std::max(0.01, normal.dot((v - point).normalized())); };
  const double cb = cosine(b);
  return {cb, cb, cosine(a), cosine(c)};
}

}  // namespace

double triangleSolidAngle(const Eigen::Vector3d& point, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                          const Eigen::Vector3d& c) {
  const Eigen::Vector3d ra = a - point, rb = b - point, rc = c - point;
  const double la = ra.norm(), lb = rb.norm(), lc = rc.norm();
  if (!(la > 0) || !(lb > 0) || !(lc > 0)) return 0;
  const double triple = std::abs(ra.dot(rb.cross(rc)));
  const double denominator = la * lb * lc + ra.dot(rb) * lc + rb.dot(rc) * la + rc.dot(ra) * lb;
  const double omega = 2 * std::atan2(triple, denominator);
  return std::isfinite(omega) ? std::max(0.0, omega) : 0.0;
}

bool sampleSphericalTriangle(const Eigen::Vector3d& point, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                             const Eigen::Vector3d& c, double u1, double u2, Eigen::Vector3d* direction) {
  const Eigen::Vector3d A = (a - point).normalized(), B = (b - point).normalized(), C = (c - point).normalized();
  if (!A.allFinite() || !B.allFinite() || !C.allFinite()) return false;
  const double alpha = vertexAngle(A, B, C), beta = vertexAngle(B, C, A), gamma = vertexAngle(C, A, B);
  const double area = alpha + beta + gamma - kPi;
  if (!(area > 0)) return false;
  // The sub-triangle A B C' of area u1 * area: C' on the arc A C (Arvo's closed form for the
  // cosine of the arc A C').
  const double sub_area = u1 * area;
  const double s = std::sin(sub_area - alpha), t = std::cos(sub_area - alpha);
  const double cos_alpha = std::cos(alpha), sin_alpha = std::sin(alpha);
  const double u = t - cos_alpha;
  const double v = s + sin_alpha * A.dot(B);
  const double denominator = (v * s + u * t) * sin_alpha;
  if (!(std::abs(denominator) > 0)) return false;
  const double q = std::clamp(((v * t - u * s) * cos_alpha - v) / denominator, -1.0, 1.0);
  Eigen::Vector3d c_perp;
  if (!orthogonalUnit(C, A, &c_perp)) return false;
  const Eigen::Vector3d c_prime = q * A + std::sqrt(std::max(0.0, 1 - q * q)) * c_perp;
  // Then a point on the arc B C', uniform in the sub-triangle's remaining coordinate.
  const double z = 1 - u2 * (1 - c_prime.dot(B));
  Eigen::Vector3d cp_perp;
  if (!orthogonalUnit(c_prime, B, &cp_perp)) {
    *direction = B;  // C' at B: the whole arc is one point
    return true;
  }
  const Eigen::Vector3d w = z * B + std::sqrt(std::max(0.0, 1 - z * z)) * cp_perp;
  if (!w.allFinite()) return false;
  *direction = w.normalized();
  return true;
}

bool invertSphericalTriangleSample(const Eigen::Vector3d& point, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                   const Eigen::Vector3d& c, const Eigen::Vector3d& w, double* u1, double* u2) {
  const Eigen::Vector3d A = (a - point).normalized(), B = (b - point).normalized(), C = (c - point).normalized();
  const double total = triangleSolidAngle(Eigen::Vector3d::Zero(), A, B, C);
  if (!(total > 0)) return false;
  // C': where the great circle through B and w meets the arc A C.
  Eigen::Vector3d c_prime = B.cross(w).cross(A.cross(C));
  const double norm = c_prime.norm();
  if (!(norm > 1e-300)) {
    c_prime = C;  // w at B: any C' gives u2 = 0
  } else {
    c_prime /= norm;
    if (c_prime.dot(A + C) < 0) c_prime = -c_prime;
  }
  *u1 = std::clamp(triangleSolidAngle(Eigen::Vector3d::Zero(), A, B, c_prime) / total, 0.0, 1.0);
  const double arc = 1 - c_prime.dot(B);
  *u2 = arc > 0 ? std::clamp((1 - w.dot(B)) / arc, 0.0, 1.0) : 0.0;
  return std::isfinite(*u1) && std::isfinite(*u2);
}

bool sampleSphericalTriangleCosine(const Eigen::Vector3d& point, const Eigen::Vector3d& normal, const Eigen::Vector3d& a,
                                   const Eigen::Vector3d& b, const Eigen::Vector3d& c, double u1, double u2,
                                   Eigen::Vector3d* direction, double* pdf) {
  const double solid_angle = triangleSolidAngle(point, a, b, c);
  if (!(solid_angle > 0)) return false;
  const std::array<double, 4> w = cosineCorners(point, normal, a, b, c);
  double x = 0, y = 0;
  sampleBilinear(u1, u2, w, &x, &y);
  if (!sampleSphericalTriangle(point, a, b, c, x, y, direction)) return false;
  *pdf = bilinearPdf(x, y, w) / solid_angle;
  return std::isfinite(*pdf) && *pdf > 0;
}

double sphericalTriangleCosinePdf(const Eigen::Vector3d& point, const Eigen::Vector3d& normal, const Eigen::Vector3d& a,
                                  const Eigen::Vector3d& b, const Eigen::Vector3d& c, const Eigen::Vector3d& w) {
  const double solid_angle = triangleSolidAngle(point, a, b, c);
  double x = 0, y = 0;
  if (!(solid_angle > 0) || !invertSphericalTriangleSample(point, a, b, c, w, &x, &y)) return 0;
  return bilinearPdf(x, y, cosineCorners(point, normal, a, b, c)) / solid_angle;
}

}  // namespace solo
