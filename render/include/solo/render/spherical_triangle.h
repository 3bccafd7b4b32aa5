#pragma once
// Sampling a triangle by the solid angle it subtends from a point (Arvo 1995, "Stratified
// sampling of spherical triangles"): directions uniform over the spherical triangle, so a
// triangle close to the shading point gets samples in proportion to how large it looks, not
// to its area, and the 1 / distance^2 of area sampling, unbounded next to an emitter, is gone.
// Computed in double: the spherical excess alpha + beta + gamma - pi loses digits on small
// triangles (the tests go down to 1e-9 sr).

#include <Eigen/Core>

namespace solo {

/// Below this solid angle (sr) the tracer samples by area: the distance varies by some 10 % at
/// most across such a triangle, so area sampling is nearly as good, and it is cheaper (on
/// bench_render's street a threshold of 1e-4 sr cost 27 % of the render time, 1e-2 about 4 %).
constexpr double kMinSphericalSolidAngle = 1e-2;

/// Solid angle (sr, in [0, 2 pi)) of triangle (a, b, c) seen from `point` (metres), either
/// side (Van Oosterom and Strackee 1983). 0 for a degenerate triangle or a point in its plane.
double triangleSolidAngle(const Eigen::Vector3d& point, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                          const Eigen::Vector3d& c);

/// A unit direction from `point` toward triangle (a, b, c), uniform in solid angle over it, from
/// (u1, u2) in [0, 1)^2. Returns false (direction untouched) when the triangle is degenerate
/// as seen from the point (solid angle 0, the point in its plane) or the numbers fail.
bool sampleSphericalTriangle(const Eigen::Vector3d& point, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                             const Eigen::Vector3d& c, double u1, double u2, Eigen::Vector3d* direction);

/// The (u1, u2) that sampleSphericalTriangle maps to unit direction `w` (which must point into
/// the triangle); false when the triangle is degenerate as seen from the point.
bool invertSphericalTriangleSample(const Eigen::Vector3d& point, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                   const Eigen::Vector3d& c, const Eigen::Vector3d& w, double* u1, double* u2);

/// Solid-angle sampling warped toward the receiver's cosine (as pbrt-v4 does): (u1, u2) first
/// go through a bilinear density whose corners are max(0.01, n . direction) at the triangle
/// corners they map to, so directions where the receiver with unit normal `normal` sees the
/// triangle at grazing get fewer samples. `pdf` receives the density per steradian. False when
/// the triangle is degenerate as seen from the point.
bool sampleSphericalTriangleCosine(const Eigen::Vector3d& point, const Eigen::Vector3d& normal, const Eigen::Vector3d& a,
                                   const Eigen::Vector3d& b, const Eigen::Vector3d& c, double u1, double u2,
                                   Eigen::Vector3d* direction, double* pdf);

/// The density per steradian with which sampleSphericalTriangleCosine returns unit direction
/// `w` (pointing into the triangle); 0 when it cannot.
double sphericalTriangleCosinePdf(const Eigen::Vector3d& point, const Eigen::Vector3d& normal, const Eigen::Vector3d& a,
                                  const Eigen::Vector3d& b, const Eigen::Vector3d& c, const Eigen::Vector3d& w);

}  // namespace solo
