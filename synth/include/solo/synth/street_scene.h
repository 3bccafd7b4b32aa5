#pragma once
// A seeded, procedural street scene made of axis-aligned boxes, with exact semantics: every
// box carries its Cityscapes label and instance, its light-source id and window group, its
// albedo and roughness. The world frame is the camera frame (OpenCV: x right, y down,
// z forward, metres); the camera sits at the origin, 1.5 m above the road (road top y = 1.5).

#include <solo/core/camera.h>
#include <solo/geometry/triangle_mesh.h>

#include <Eigen/Core>

#include <cstdint>
#include <string>
#include <vector>

namespace solo {

/// Scene variants; the hard ones each isolate one numerical difficulty.
enum class StreetVariant {
  Default,     ///< street, buildings, vehicles, lights, thin objects, far buildings, sky
  Grazing,     ///< open ground plane to 500 m seen at grazing angles
  ThinPole,    ///< a pole 5 cm wide 3 m in front of the camera
  NearObject,  ///< an object 0.6 m from the camera
  WideSky,     ///< low buildings, no far buildings: large sky regions
  NoLights,    ///< the default layout with no light source at all
};

/// "default", "grazing", "thin-pole", "near-object", "wide-sky", "no-lights".
const char* streetVariantName(StreetVariant variant);
/// Inverse of streetVariantName; throws std::invalid_argument listing the names.
StreetVariant streetVariantFromName(const std::string& name);

struct AxisBox {
  Eigen::Vector3d min, max;  ///< metres, camera frame
};

struct ScenePart {
  AxisBox box;
  int label_id = 0;     ///< Cityscapes labelId
  int instance_id = 0;  ///< Cityscapes instanceId: classId * 1000 + k for things, else classId
  int light_id = 0;     ///< light map value categoryId * 1000 + k; 0 = not a light source
  int group_id = 0;     ///< building-floor window group; 0 = none
  Eigen::Vector3f albedo{0.5f, 0.5f, 0.5f};  ///< linear diffuse reflectance
  float roughness = 0.7f;
};

struct StreetSceneOptions {
  std::uint64_t seed = 1;
  StreetVariant variant = StreetVariant::Default;
  int width = 960, height = 540;  ///< image size, pixels; ACDC intrinsics scaled to it
};

struct StreetScene {
  StreetSceneOptions options;
  PinholeCamera camera;
  std::vector<ScenePart> parts;
  Eigen::Vector3d sun_direction;  ///< unit, toward the sun, camera frame
};

/// Builds the scene. Deterministic for a given seed and variant.
StreetScene buildStreetScene(const StreetSceneOptions& options);

/// The scene as one mesh: 8 vertices and 12 outward-facing triangles per box, in part
/// order (triangle t belongs to part t / 12). Every box is closed, so the mesh has no
/// boundary; boxes may touch or overlap one another.
TriangleMesh streetSceneMesh(const StreetScene& scene);

}  // namespace solo
