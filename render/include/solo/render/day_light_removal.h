#pragma once
// Albedo from a day image and the scene's geometry: the day light taken out. The day image is
// modelled as Lambertian under a white sun and an ambient light measured in the image itself,
//   I(x) = A(x) * (V_sun(x) * max(0, n.s) + q * E(x)),
// with s the direction toward the sun, V_sun its visibility through the mesh (cast shadows), E
// the irradiance that cosine-weighted rays gather from the sky pixels (by elevation) and from
// the surfaces the camera sees where they hit (interreflections), and q the sun's irradiance per
// unit of E, per channel. The sun direction is searched on the upper hemisphere: each candidate
// is scored by the spread of the de-lit log intensity within each Cityscapes class. Then
// A = I / shading, white-balanced (the road and sidewalk are grey, else grey-world) and scaled
// to a median reflectance. Without a clear sun only the ambient light is divided out; without
// enough geometry the day image is kept; either with a note. With
// DayLightRemovalOptions::shadows_from_image the shadows are read from the image instead:
// each material region (one instance, one surface orientation) whose log(I / E) splits into
// a lit and a shadowed mode of the sun's colour is a shadow edge, the sun is the direction
// that makes the modes of a region and the regions of an instance one albedo, and the
// visibility is the mode (softened by a guided filter). docs/rendering.md, "Albedo from the
// day image", has the measurements (on solo's estimated geometry neither finds the sun).

#include <solo/core/camera.h>
#include <solo/core/report.h>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include <cstdint>
#include <vector>

namespace solo {

struct DepthMesh;

struct DayLightRemovalOptions {
  /// Pixel pairs scoring each candidate sun direction (each costs two shadow rays).
  int search_pairs = 4000;
  /// Pixel pairs of the local refinement around the best candidates.
  int refine_pairs = 12000;
  double coarse_step_deg = 10;     ///< spacing of the candidate grid (elevation and azimuth)
  double min_elevation_deg = 4;    ///< candidates from this elevation above the horizon
  double final_step_deg = 0.6;     ///< the refinement halves its step down to this
  int ambient_rays = 12;           ///< per ambient sample (every second pixel in x and y)
  /// The sun is kept when its shading lowers the pairs' robust log-difference cost by at least
  /// this share against the sky alone; else only the sky term is divided out.
  double min_sun_gain = 0.15;
  /// The de-lit albedo is scaled so that the median luminance of the non-sky pixels is this.
  double median_reflectance = 0.2;
  std::uint64_t seed = 1;
  /// The sun and its shadows read from the image (each material region's lit and shadowed
  /// modes) instead of searched with shadow rays through the mesh; search_pairs,
  /// refine_pairs, the steps and min_sun_gain then do not apply.
  bool shadows_from_image = false;
  /// The direction toward the sun in the camera frame when it is known (from the capture's time
  /// and place and the camera's pose): no search, its shadows traced through the mesh (also with
  /// shadows_from_image). Zero (the default) or not finite: searched.
  Eigen::Vector3f sun_direction = Eigen::Vector3f::Zero();

  /// The defaults with `shadows_from_image` on.
  static DayLightRemovalOptions withShadowsFromImage() {
    DayLightRemovalOptions options;
    options.shadows_from_image = true;
    return options;
  }
};

/// The scene as the removal sees it: a triangle mesh in the camera frame (metres) with the
/// Cityscapes instanceId of each triangle (0 = unknown), and the camera at the day image's
/// resolution. normals: CV_32FC3 unit camera-frame normals at that resolution, or empty (the
/// triangles' own normals).
struct DayLightGeometry {
  PinholeCamera camera;
  std::vector<float> vertices;            ///< x0 y0 z0 x1 ...
  std::vector<std::uint32_t> triangles;   ///< i0 j0 k0 i1 ...
  std::vector<int> triangle_instance;     ///< one per triangle
  cv::Mat normals;
  /// CV_32S Cityscapes instanceIds at the image resolution, or empty: then each pixel takes
  /// the instance of the triangle it shows.
  cv::Mat instances;
};

/// The depth mesh's faces with their vertices' instance (the first vertex that has one), for
/// a day image of camera's size. normals as in DayLightGeometry.
DayLightGeometry dayLightGeometry(const DepthMesh& mesh, const PinholeCamera& camera, const cv::Mat& normals = {});

enum class DayLightMethod {
  SunAndSky,  ///< sun direction found: sun and sky shading divided out
  SkyOnly,    ///< no clear sun: the ambient irradiance divided out
  DayImage,   ///< too little geometry: the linearised day image, white-balanced and scaled
};

const char* dayLightMethodName(DayLightMethod method);

struct DayLightRemoval {
  cv::Mat albedo;  ///< CV_32FC3 linear reflectance in [0, 1], the day image's size
  DayLightMethod method = DayLightMethod::DayImage;
  Eigen::Vector3f sun_direction = Eigen::Vector3f::Zero();  ///< unit, toward the sun; zero without one
  /// q per channel: the sun's irradiance per unit of ambient irradiance measured in the image.
  Eigen::Vector3f ambient_scale = Eigen::Vector3f::Zero();
  Eigen::Vector3f white_balance = Eigen::Vector3f::Ones();  ///< per-channel gains applied, scale included
  double sun_gain = 0;  ///< the share of the sky-only cost the sun removes (shadow-ray search only)
  StageReport report;   ///< "day_light": method, sun direction, gains, time; notes on fallbacks
};

/// day_linear: CV_32FC3 linear RGB (the day image with its sRGB encoding removed), of
/// geometry.camera's size. Never throws on degenerate input (no mesh, all sky, NaN normals):
/// it falls back and says so in the report's notes.
DayLightRemoval removeDayLight(const cv::Mat& day_linear, const DayLightGeometry& geometry,
                               const DayLightRemovalOptions& options = {});

}  // namespace solo
