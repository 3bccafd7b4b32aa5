#pragma once
// Upsampling of a render made at a fraction of the image size, keeping the image's texture
// (docs/rendering.md, "Rendering below the image size"). Where a pixel sees a surface, its
// radiance is the full-size reflectance times the irradiance (radiance / first-hit albedo) of
// the render pixels around it that see the same surface: the light is smooth at the render's
// scale, the texture is not. A pixel of a lamp takes its lamp's radiance. Elsewhere (sky, black
// surfaces, silhouettes without a neighbour on the pixel's own surface) it is the bilinear
// radiance.

#include <solo/core/report.h>

#include "solo/render/path_tracer.h"

#include <opencv2/core.hpp>

namespace solo {

struct RenderUpsampleOptions {
  /// false: the radiance is bilinear everywhere (the guides are not used).
  bool texture = true;
  /// A render pixel's irradiance is used where its first-hit albedo's every XYZ channel is at
  /// least this (darker: the division would amplify its noise). > 0.
  float min_albedo = 0.02f;
  /// Weight of a render pixel by its first-hit depth d_j against the full-size pixel's depth d:
  /// exp(-((d_j - d) / (depth_tolerance d))^2). 0.1: a pixel 10 % nearer or farther weighs 1/e,
  /// one 30 % off (a silhouette) 1e-4. > 0.
  float depth_tolerance = 0.1f;
};

/// What the full-size image knows, to guide the upsampling; every map at the image size, any of
/// them may be empty.
struct UpsampleGuides {
  /// CV_32FC3 XYZ reflectance relative to E (the faces' reflectance, NightScene::reflectance).
  /// Empty: the radiance is bilinear.
  cv::Mat reflectance;
  /// CV_32F z-depth, metres (the refined depth); <= 0 or not finite: no surface. Empty: the
  /// radiance is bilinear.
  cv::Mat depth_m;
  /// CV_8U, non-zero where the input saw a surface (RenderScene::surface_pixels). Empty: every
  /// pixel with a depth.
  cv::Mat surface;
  /// CV_32S light-map id of the emitting light each pixel shows (NightScene::light_id), 0 none.
  /// Empty: a pixel beside a render pixel that sees an emitter keeps the bilinear radiance.
  cv::Mat light_id;
};

/// Upsamples `low` (every AOV of one size, that of a camera divided by an integer factor) to
/// `size`. The radiance:
/// - a pixel that shows a light (guides.light_id) takes the radiance of the render pixels around
///   it that see only that light (emitter coverage 1, the same id), so a lamp keeps its outline;
/// - a pixel of a surface takes its reflectance times the irradiance (radiance / mean_albedo, or
///   albedo when the render has no mean_albedo) of the render pixels around it that see no
///   emitter, weighted bilinearly and by depth;
/// - any other pixel, or one without such neighbours, the bilinear radiance.
/// Albedo and normal bilinear; depth, light ids, emitter coverage, samples and standard error
/// nearest. Returns the counts in `report` (may be null): pixels given the texture, lamp pixels
/// from their lamp, pixels bilinear. Throws std::invalid_argument for maps of another size or
/// type, or options out of range.
RenderOutput upsampleRender(const RenderOutput& low, cv::Size size, const UpsampleGuides& guides,
                            const RenderUpsampleOptions& options = {}, StageReport* report = nullptr);

}  // namespace solo
