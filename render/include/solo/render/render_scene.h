#pragma once
// What the path tracer renders: a triangle mesh with per-face reflectance, emitting faces
// with their radiance, and the ego vehicle's headlights. Colour: every radiance and
// reflectance is a CIE XYZ triple relative to white E (a reflectance of (1,1,1) reflects any
// light unchanged), the space the reference renders in. Units: metres; radiance in the
// renderer's unit (docs/rendering.md states its mapping to cd/m^2).

#include <solo/core/camera.h>

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <optional>
#include <vector>

namespace solo {

/// How an emitter's radiance depends on the direction v (unit) the light leaves a face in.
enum class EmitterProfile : std::uint8_t {
  Uniform,     ///< 1: Lambertian
  CosineLobe,  ///< g(v, n) = cos(pi (|v.n| - 1) / 2): 1 along the normal, 0 at grazing
  /// max(0, v.a)^beam_exponent, a the unit direction from the emitting point to the camera
  /// (the origin): a beam aimed at the camera, which sees the radiance unchanged
  TowardCamera,
};

/// An emitting surface: every face whose emitter index points here emits this radiance.
struct Emitter {
  Eigen::Vector3f radiance{0.f, 0.f, 0.f};  ///< XYZ relative to E, along the profile's peak
  /// Front lights and street lights: CosineLobe; traffic signals: TowardCamera; others Uniform.
  /// Both sides of a face emit.
  EmitterProfile profile = EmitterProfile::Uniform;
  float beam_exponent = 0;  ///< TowardCamera's exponent
  int light_id = 0;  ///< the light-map id, for the light-id AOV
};

/// A rectangular area light that is not part of the visible geometry (the ego headlights).
struct RectangleLight {
  Eigen::Vector3f centre{0.f, 0.f, 0.f};  ///< metres, camera frame
  Eigen::Vector3f normal{0.f, 0.f, 1.f};  ///< emitting direction (unit)
  Eigen::Vector3f edge_u{0.3f, 0.f, 0.f}; ///< full edge vectors, metres, perpendicular to normal
  Eigen::Vector3f edge_v{0.f, 0.15f, 0.f};
  Eigen::Vector3f radiance{0.f, 0.f, 0.f};
  float spread_rad = 3.14159265f;  ///< full cone angle of emission; pi = a Lambertian hemisphere
};

/// A distant light: the sun as a disc of small angular radius and uniform radiance
/// illuminance / (pi sin^2(radius)), so that a surface facing it receives `illuminance`.
struct SunLight {
  Eigen::Vector3f direction{0.f, -1.f, 0.f};  ///< unit, toward the sun, camera frame
  /// XYZ irradiance on a surface facing the sun, render units times sr (lux when radiance is
  /// in cd/m^2); 0 = no sun.
  Eigen::Vector3f illuminance{0.f, 0.f, 0.f};
  float angular_radius_rad = 0.00465f;  ///< the sun's, seen from the earth: 0.267 degrees
};

struct RenderScene {
  std::vector<Eigen::Vector3f> vertices;            ///< metres, camera frame
  std::vector<std::array<std::uint32_t, 3>> faces;
  std::vector<Eigen::Vector3f> face_reflectance;    ///< per face, XYZ relative to E, each in [0, 1]
  std::vector<float> face_roughness;                ///< per face in [0, 1]; empty = no roughness map
  std::vector<std::int32_t> face_emitter;           ///< per face: index into emitters, or -1; empty = none
  /// Per face, a unit shading normal used instead of the face's own (its geometry is unchanged:
  /// rays still hit the face); a zero or non-finite entry, or a face beyond the vector's end,
  /// keeps the face's normal.
  std::vector<Eigen::Vector3f> face_shading_normal;
  std::vector<Emitter> emitters;
  std::vector<RectangleLight> rectangle_lights;
  Eigen::Vector3f sky_radiance{0.f, 0.f, 0.f};      ///< seen by rays that leave the scene; 0 = black sky
  /// Optional sky gradient: radiance sky_radiance at and below the horizon rising to this at
  /// the zenith as sky_radiance + (zenith - sky_radiance) sqrt(max(0, w.sky_up)). Empty = uniform.
  std::optional<Eigen::Vector3f> sky_zenith_radiance;
  Eigen::Vector3f sky_up{0.f, -1.f, 0.f};           ///< unit, camera frame (OpenCV: y down)
  SunLight sun;                                     ///< daytime mode; zero illuminance = none
  PinholeCamera camera;                             ///< for the image resolution
  /// Row-major at camera.width x camera.height, or empty (= unknown): 1 where the input saw a
  /// surface (a pixel with depth, not sky). A depth mesh without its spurious faces has a gap of
  /// about a pixel between a near sheet's silhouette and the far sheet behind it; a camera ray in
  /// such a pixel that hits nothing went through that gap, and the renderer does not count it
  /// (path_tracer.h, "Mesh cracks"). Used only when rendering at the camera's own size.
  std::vector<std::uint8_t> surface_pixels;
  /// Optional texture on the depth mesh's pixel grid (texture_width x texture_height texels,
  /// row-major), used by a render at that size. A face takes the material and the light of one
  /// pixel, so an edge between two materials follows the diagonals of the mesh's quads (teeth a
  /// pixel long, in the day image a straight edge). A camera ray that hits a face whose three
  /// vertices were made from pixels, one of them its own pixel's, takes that pixel's texel
  /// instead: the edge is the pixels' own. Rays after the first bounce keep the faces' values.
  /// Empty = off.
  int texture_width = 0, texture_height = 0;
  std::vector<std::int32_t> vertex_texel;        ///< per vertex: its pixel's texel, -1 for one not made from a pixel
  std::vector<Eigen::Vector3f> texel_reflectance;  ///< per texel, as face_reflectance
  std::vector<float> texel_roughness;            ///< per texel, as face_roughness; empty = no roughness map
  std::vector<std::int32_t> texel_emitter;       ///< per texel, as face_emitter
};

/// Linear sRGB (D65) reflectance to XYZ relative to E: the sRGB matrix, then the white of
/// (1,1,1) scaled to (1,1,1). Exact for greys, an approximation for colours (as every
/// three-channel renderer).
Eigen::Vector3f reflectanceFromLinearSrgb(const Eigen::Vector3f& rgb);

/// The ego vehicle's two headlights as in the reference: 0.3 x 0.15 m, at (+-0.5, 0.3, 0.5) m
/// from the camera (OpenCV frame), aimed forward and 45 degrees up (the reference's literal
/// rotation: docs/rendering.md, "Ego headlights"), yawed 18 degrees outward, spread 125 degrees,
/// the reference colour, with the given radiance luminance Y.
std::vector<RectangleLight> egoHeadlights(float luminance_y);

}  // namespace solo
