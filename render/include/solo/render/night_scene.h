#pragma once
// Assembles what the path tracer renders from the pipeline's products: the cleaned depth
// mesh (its vertices keep their pixels), the material maps at the mesh's resolution and the
// instantiated light record. A face takes the material and the light of the pixel under its
// vertices' mean pixel position.

#include "solo/render/day_light_removal.h"
#include "solo/render/render_scene.h"

#include <solo/geometry/depth_mesh.h>
#include <solo/core/report.h>
#include <solo/lighting/light_record.h>

#include <opencv2/core.hpp>

namespace solo {

struct NightSceneOptions {
  bool headlights = true;
  /// Luminous flux of each ego headlight, lm (a halogen low beam emits about 1000-1500 lm);
  /// turned into the luminance of its 0.3 x 0.15 m rectangle as flux / (pi * area).
  double headlight_flux_lm = 1200;
  double sky_luminance_cd_m2 = 0.0;  ///< a dim night sky for rays that leave the scene; 0 = black
  float default_reflectance = 0.3f;  ///< faces with no pixel (mesh-file input) or no albedo map
  /// A flux light (a compact lamp) whose mesh faces cover more than this many times the area
  /// its record measured emits from its pixels on the record's plane instead (night_scene.cpp).
  double max_flux_area_ratio = 2.0;
  /// Faces made from pixels shade with the normal map's mean normal at their three pixels
  /// (where it faces the camera) instead of their own: depth noise folds a surface seen at
  /// grazing, and a fold's face turned from the lamps rendered as a black speck.
  bool shading_normals = true;
  /// Without an albedo map, the day image's light is taken out of it (sun, sky and
  /// interreflections through the mesh; day_light_removal.h) before it stands in for the
  /// reflectance. Off: the linearised day image, as it is (docs/rendering.md).
  bool remove_day_light = false;
  /// The removal's options; the sun's shadows are read from the image (`shadows_from_image`):
  /// on path-traced synthetic days its night images are closer to those of the exact albedo
  /// than with shadow rays (docs/rendering.md, "Albedo from the day image").
  DayLightRemovalOptions day_light = DayLightRemovalOptions::withShadowsFromImage();
};

struct NightScene {
  RenderScene scene;
  StageReport report;
  /// CV_32FC3 XYZ reflectance relative to E per pixel of the maps' resolution: what a face made
  /// from that pixel reflects (before emitting faces are made black); empty without an albedo
  /// map and a day image. Texture for a render made below the image size (render_upsample.h).
  cv::Mat reflectance;
  /// CV_32S per pixel of the maps' resolution: the light-map id of the emitting light the pixel
  /// shows (as the render's light-id AOV), 0 for none.
  cv::Mat light_id;  ///< "scene": faces, emitting faces per category, lights on without faces
};

/// albedo: CV_32FC3 linear RGB reflectance at the image resolution, or empty (then the
/// linearised day image stands in for it, with a note). roughness: CV_32F of the same size, or
/// empty. record: lights at the same resolution (tree.width x tree.height); lights that are off
/// emit nothing. The render camera is at the albedo's (else the record's, else the mesh's)
/// resolution; the mesh may come from a depth map downsampled by an integer factor (its pixel
/// coordinates are scaled to the maps). Units: emitted luminance in cd/m^2 = render units
/// (docs/lighting.md). normals: CV_32FC3 unit camera-frame normals at the maps' resolution
/// (the refined depth's predicted normals), or empty: the faces shade with their own normals.
NightScene buildNightScene(const DepthMesh& mesh, const cv::Mat& albedo, const cv::Mat& roughness,
                           const cv::Mat& day_image, const LightRecord& record, const NightSceneOptions& options = {},
                           const cv::Mat& normals = cv::Mat());

}  // namespace solo
