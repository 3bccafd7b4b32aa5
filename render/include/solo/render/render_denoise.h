#pragma once
// An edge-aware filter of a path-traced render's Monte Carlo noise, guided by its AOVs
// (docs/rendering.md, "Render denoising"). The radiance is divided by the first-hit albedo
// (texture out, irradiance in), the irradiance is smoothed by an edge-avoiding a-trous wavelet
// filter (5x5 B-spline taps 1, 2, 4, ... px apart) whose weights stop at changes of the surface
// (normal, distance from the pixel's tangent plane, albedo) and at luminance differences large against
// the render's own standard error, and the result is multiplied by the albedo again. Pixels that
// see an emitter or no surface (sky) are neither changed nor used.

#include <solo/core/camera.h>
#include <solo/core/report.h>

#include "solo/render/path_tracer.h"

namespace solo {

struct RenderDenoiseOptions {
  /// false: the render is left as it is and the report says so (skipped).
  bool enabled = true;
  /// A-trous passes, taps 1, 2, ..., 2^(iterations - 1) px apart: a footprint of
  /// 2 (2^iterations - 1) px around a pixel (5: 62 px). 1 to 10.
  int iterations = 5;
  /// Passes after those, with taps 2^(fine_passes - 1), ..., 2, 1 px apart. A pass of step s
  /// leaves a pattern of period s wherever its luminance weights differ from tap to tap (a
  /// rare bright sample among dark ones: the a-trous grid, blocks of 4-16 px); the fine passes
  /// average it out. 0 to 10; they add 2 (2^fine_passes - 1) px to the footprint.
  int fine_passes = 2;
  /// Albedo (per XYZ channel) below this is taken as this when the radiance is divided by it
  /// and multiplied back, so a black surface keeps its radiance and no division blows up. > 0.
  float albedo_floor = 0.02f;
  /// Weight of a neighbour by its normal: max(0, n_p . n_q)^normal_exponent (64: 0.5 at
  /// 8.4 degrees, 0.03 at 15 degrees). >= 0; 0 ignores normals.
  float normal_exponent = 64.f;
  /// Weight by the albedos: exp(-|ln a_p - ln a_q| / albedo_sigma), a the demodulation albedo's
  /// Y. Radiance that is not albedo x irradiance (the specular lobe's reflections) would move
  /// from dark to bright albedo through the demodulation; 0 ignores albedo. >= 0.
  float albedo_sigma = 0.3f;
  /// Weight by the neighbour's distance d from the pixel's tangent plane (through its
  /// first-hit point, along its normal): exp(-d / (plane_tolerance x depth)), depth the
  /// pixel's z-depth, metres. 0.01: a neighbour 1 % of the depth off the plane weighs 1/e.
  /// A depth discontinuity is far off the plane at any viewing angle, a plane seen at grazing
  /// is not. > 0.
  float plane_tolerance = 0.01f;
  /// Weight by the difference of the irradiance luminances: exp(-|Y_p - Y_q| /
  /// (luminance_sigma x sqrt(v_p + v_q))), v the variance of the pixel's irradiance estimate
  /// (the render's std_error over the albedo, squared, smoothed over 3x3 pixels, then carried
  /// through each pass). Keeps shadow edges the geometry does not show. > 0; ignored when the
  /// render has no std_error. Lower keeps more contrast and loses more of the light of rare bright
  /// paths (a pixel whose few samples missed them reports a small error): on the default scene
  /// 4 lost 3 % of the mean, 8 2 %, no luminance weight none (docs/accuracy.md).
  float luminance_sigma = 8.f;
  /// Firefly clamp before filtering: a pixel whose irradiance Y exceeds the mean of the other
  /// filtered pixels within `firefly_radius_px` by more than firefly_sigma times their standard
  /// deviation, and whose own standard error is at least a quarter of its value (a rare bright
  /// sample, not a steady highlight), is scaled down to that bound. Without it the filter spreads
  /// such a sample over its footprint as a blotch of light. 0 = off. >= 0; needs the render's
  /// std_error.
  float firefly_sigma = 20.f;
  /// Half-width of the square window of the firefly statistics, pixels. >= 1.
  int firefly_radius_px = 7;
  /// The light above the bound is spread over the filtered pixels around, by a Gaussian of
  /// this standard deviation (pixels; albedo-weighted, so the light added is the light taken),
  /// wide enough that no blotch comes back; 0 removes it (biased dark). >= 0.
  float firefly_spread_px = 96.f;
};

/// Filters `render.radiance` (CV_32FC3, XYZ) in place with the options above, guided by
/// render.albedo (CV_32FC3; empty: no demodulation), render.normal (CV_32FC3, unit or 0),
/// render.depth_m (CV_32F z-depth, m; <= 0 or not finite: no surface), render.std_error
/// (CV_32F standard error of Y, render units; empty: no luminance weight), render.light_id
/// (CV_32S) and render.emitter_coverage (CV_32F); empty ones of the last two mark no emitter.
/// `camera` gives the first-hit points (its width and height must be the render's). Pixels with
/// light_id != 0, emitter_coverage > 0, no surface, a zero normal or a non-finite radiance keep
/// their radiance bit for bit and are not used for others. The other AOVs are not changed.
/// Returns the report "denoise": time (s), pixels filtered and kept, the passes, the footprint
/// (px) and the filtered pixels' luminance after / before; skipped when options.enabled is
/// false. Throws std::invalid_argument for an AOV of another size or type, a camera of another
/// size, or options out of range.
StageReport denoiseRender(RenderOutput& render, const PinholeCamera& camera, const RenderDenoiseOptions& options = {});

}  // namespace solo
