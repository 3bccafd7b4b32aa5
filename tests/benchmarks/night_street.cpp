#include "night_street.h"

#include <solo/lighting/light_category.h>
#include <solo/synth/street_scene.h>

#include <map>

namespace solo::bench {
namespace {

// Emitted luminance per category in render units (a lit window about 10, a street-light head
// about 800): only the orders of magnitude matter for comparing samplers and renderers.
float luminanceOf(int category) {
  switch (static_cast<LightCategory>(category)) {
    case LightCategory::WindowBuilding: return 8.f;
    case LightCategory::WindowParked: return 2.f;
    case LightCategory::WindowTransport: return 9.f;
    case LightCategory::StreetLightHighCct:
    case LightCategory::StreetLightLowCct: return 900.f;
    case LightCategory::ParkedFront:
    case LightCategory::MovingFront: return 800.f;
    case LightCategory::ParkedRear:
    case LightCategory::MovingRear: return 70.f;
    default: return 150.f;
  }
}

}  // namespace

RenderScene nightStreet(const NightStreetOptions& o) {
  StreetSceneOptions street_options;
  street_options.width = o.width;
  street_options.height = o.height;
  const StreetScene street = buildStreetScene(street_options);
  const TriangleMesh mesh = streetSceneMesh(street);
  RenderScene scene;
  scene.camera = street.camera;
  for (const auto& v : mesh.vertices) scene.vertices.push_back(v.cast<float>());
  scene.faces = mesh.faces;
  std::map<int, int> emitter_of_light;
  for (std::size_t f = 0; f < mesh.faces.size(); ++f) {
    const ScenePart& part = street.parts[f / 12];  // every part is a box of 12 triangles
    scene.face_reflectance.push_back(reflectanceFromLinearSrgb(part.albedo));
    int emitter = -1;
    if (part.light_id > 0) {
      auto it = emitter_of_light.find(part.light_id);
      if (it == emitter_of_light.end()) {
        const int category = lightCategoryOfId(part.light_id);
        const bool profiled =
            o.profiled_emitters && (category == 7 || category == 8 || category == 9 || category == 10);
        scene.emitters.push_back({Eigen::Vector3f(0.95f, 1.f, 0.8f) * luminanceOf(category),
                                  profiled ? EmitterProfile::CosineLobe : EmitterProfile::Uniform, 0.f,
                                  part.light_id});
        it = emitter_of_light.emplace(part.light_id, static_cast<int>(scene.emitters.size()) - 1).first;
      }
      emitter = it->second;
    }
    scene.face_emitter.push_back(emitter);
  }
  scene.rectangle_lights = egoHeadlights(2000.f);
  if (o.headlight_spread_rad >= 0)
    for (auto& light : scene.rectangle_lights) light.spread_rad = o.headlight_spread_rad;
  return scene;
}

}  // namespace solo::bench
