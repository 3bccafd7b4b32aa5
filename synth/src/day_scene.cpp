#include "solo/synth/day_scene.h"

#include <Eigen/LU>

namespace solo {

RenderScene streetDayScene(const StreetScene& street, const DayRenderOptions& o) {
  const TriangleMesh mesh = streetSceneMesh(street);
  RenderScene scene;
  scene.camera = street.camera;
  scene.vertices.reserve(mesh.vertices.size());
  for (const Eigen::Vector3d& v : mesh.vertices) scene.vertices.push_back(v.cast<float>());
  scene.faces = mesh.faces;
  scene.face_reflectance.reserve(mesh.faces.size());
  scene.face_roughness.reserve(mesh.faces.size());
  for (std::size_t f = 0; f < mesh.faces.size(); ++f) {
    const ScenePart& part = street.parts[f / 12];  // 12 triangles per box
    scene.face_reflectance.push_back(reflectanceFromLinearSrgb(part.albedo));
    scene.face_roughness.push_back(part.roughness);
  }
  scene.sky_radiance = reflectanceFromLinearSrgb(o.sky_horizon_rgb);
  scene.sky_zenith_radiance = reflectanceFromLinearSrgb(o.sky_zenith_rgb);
  scene.sky_up = Eigen::Vector3f(0.f, -1.f, 0.f);
  scene.sun.direction = street.sun_direction.cast<float>().normalized();
  scene.sun.illuminance = Eigen::Vector3f::Constant(static_cast<float>(o.sun_illuminance));  // white: E-relative
  scene.sun.angular_radius_rad = o.sun_angular_radius_rad;
  return scene;
}

DaylightRender renderDaylightPathTraced(const StreetScene& street, const DayRenderOptions& o) {
  PathTracerOptions tracer;
  tracer.min_samples = o.min_samples;
  tracer.max_samples = o.max_samples;
  tracer.relative_error = o.relative_error;
  tracer.max_bounces = o.max_bounces;
  tracer.seed = o.seed;
  tracer.progress = o.progress;
  tracer.light_sampler = LightSamplerKind::Power;  // no emitters: the choice does not matter
  RenderOutput out = renderPathTraced(streetDayScene(street, o), tracer);

  // Back to linear sRGB: the inverse of reflectanceFromLinearSrgb, a linear map.
  Eigen::Matrix3f to_xyz;
  for (int k = 0; k < 3; ++k) to_xyz.col(k) = reflectanceFromLinearSrgb(Eigen::Vector3f::Unit(k));
  const Eigen::Matrix3f to_rgb = to_xyz.inverse();
  DaylightRender result;
  result.linear_rgb.create(out.radiance.size(), CV_32FC3);
  for (int y = 0; y < out.radiance.rows; ++y)
    for (int x = 0; x < out.radiance.cols; ++x) {
      const cv::Vec3f v = out.radiance.at<cv::Vec3f>(y, x);
      const Eigen::Vector3f rgb = to_rgb * Eigen::Vector3f(v[0], v[1], v[2]);
      result.linear_rgb.at<cv::Vec3f>(y, x) = {rgb.x(), rgb.y(), rgb.z()};
    }
  result.report = std::move(out.report);
  result.report.name = "daylight";
  result.report.add("sun_illuminance", o.sun_illuminance);
  return result;
}

}  // namespace solo
