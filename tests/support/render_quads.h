#pragma once
// Hand-built render scenes for the tracer's tests: quads of given reflectance and emitter.

#include <solo/render/render_scene.h>

#include <Eigen/Core>

#include <cstdint>

namespace solo::test {

/// Adds the quad corner, corner + u, corner + u + v, corner + v (metres, camera frame) to `s` as
/// two faces of the given reflectance and emitter index (-1: none).
inline void addQuad(RenderScene& s, const Eigen::Vector3f& corner, const Eigen::Vector3f& u, const Eigen::Vector3f& v,
                    float reflectance, int emitter = -1) {
  const auto base = static_cast<std::uint32_t>(s.vertices.size());
  s.vertices.insert(s.vertices.end(), {corner, corner + u, corner + u + v, corner + v});
  s.faces.push_back({base, base + 1, base + 2});
  s.faces.push_back({base, base + 2, base + 3});
  for (int k = 0; k < 2; ++k) {
    s.face_reflectance.push_back(Eigen::Vector3f::Constant(reflectance));
    s.face_emitter.push_back(emitter);
  }
}

}  // namespace solo::test
