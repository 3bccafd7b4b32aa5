#include "solo/synth/scene_raster.h"

#include "solo/render/ray_caster.h"

#include <solo/core/srgb.h>

#include <tbb/parallel_for.h>

#include <cmath>

namespace solo {
namespace {

constexpr int kSkyLabel = 23;

RayCaster casterFor(const StreetScene& scene) {
  const TriangleMesh mesh = streetSceneMesh(scene);
  std::vector<float> vertices;
  vertices.reserve(mesh.vertices.size() * 3);
  for (const Eigen::Vector3d& v : mesh.vertices)
    for (int k = 0; k < 3; ++k) vertices.push_back(static_cast<float>(v[k]));
  std::vector<std::uint32_t> triangles;
  triangles.reserve(mesh.faces.size() * 3);
  for (const auto& f : mesh.faces) triangles.insert(triangles.end(), f.begin(), f.end());
  return RayCaster(std::move(vertices), std::move(triangles), true);
}

}  // namespace

GroundTruthMaps rasterizeGroundTruth(const StreetScene& scene) {
  const int w = scene.options.width, h = scene.options.height;
  const PinholeCamera& cam = scene.camera;
  const RayCaster caster = casterFor(scene);
  GroundTruthMaps t;
  t.depth_m.create(h, w, CV_32F);
  t.normals.create(h, w, CV_32FC3);
  t.albedo.create(h, w, CV_32FC3);
  t.roughness.create(h, w, CV_32F);
  for (cv::Mat* m : {&t.labels, &t.instances, &t.lights, &t.light_groups, &t.part}) m->create(h, w, CV_32S);

  tbb::parallel_for(0, h, [&](int y) {
    for (int x = 0; x < w; ++x) {
      // Unnormalised direction with z = 1: the hit distance t is the z-depth itself.
      const Eigen::Vector3f direction(static_cast<float>((x - cam.cx) / cam.fx), static_cast<float>((y - cam.cy) / cam.fy),
                                      1.f);
      const RayHit hit = caster.intersect(Eigen::Vector3f::Zero(), direction);
      if (!hit.hit) {
        t.depth_m.at<float>(y, x) = 0.f;
        t.normals.at<cv::Vec3f>(y, x) = {0, 0, 0};
        t.albedo.at<cv::Vec3f>(y, x) = {0, 0, 0};
        t.roughness.at<float>(y, x) = 0.f;
        t.labels.at<int>(y, x) = kSkyLabel;
        t.instances.at<int>(y, x) = kSkyLabel;
        t.lights.at<int>(y, x) = 0;
        t.light_groups.at<int>(y, x) = 0;
        t.part.at<int>(y, x) = -1;
        continue;
      }
      const ScenePart& part = scene.parts[hit.triangle / 12];
      Eigen::Vector3f n = hit.geometric_normal.normalized();
      if (n.dot(direction) > 0) n = -n;
      t.depth_m.at<float>(y, x) = hit.distance;
      t.normals.at<cv::Vec3f>(y, x) = {n.x(), n.y(), n.z()};
      t.albedo.at<cv::Vec3f>(y, x) = {part.albedo.x(), part.albedo.y(), part.albedo.z()};
      t.roughness.at<float>(y, x) = part.roughness;
      t.labels.at<int>(y, x) = part.label_id;
      t.instances.at<int>(y, x) = part.instance_id;
      t.lights.at<int>(y, x) = part.light_id;
      t.light_groups.at<int>(y, x) = part.group_id;
      t.part.at<int>(y, x) = static_cast<int>(hit.triangle / 12);
    }
  });
  return t;
}

cv::Mat renderDaylight(const StreetScene& scene, const GroundTruthMaps& truth, const DaylightOptions& o) {
  const int w = scene.options.width, h = scene.options.height;
  const PinholeCamera& cam = scene.camera;
  const RayCaster caster = casterFor(scene);
  const Eigen::Vector3f sun = scene.sun_direction.cast<float>().normalized();
  const Eigen::Vector3f up(0, -1, 0);
  const Eigen::Vector3f horizon(0.75f, 0.83f, 0.95f), zenith(0.25f, 0.45f, 0.85f);
  cv::Mat image(h, w, CV_32FC3);
  tbb::parallel_for(0, h, [&](int y) {
    for (int x = 0; x < w; ++x) {
      const Eigen::Vector3f direction(static_cast<float>((x - cam.cx) / cam.fx), static_cast<float>((y - cam.cy) / cam.fy),
                                      1.f);
      const float depth = truth.depth_m.at<float>(y, x);
      Eigen::Vector3f colour;
      if (depth <= 0.f) {
        const float elevation = std::max(0.f, direction.normalized().dot(up));
        colour = horizon + (zenith - horizon) * std::sqrt(elevation);
      } else {
        const cv::Vec3f nv = truth.normals.at<cv::Vec3f>(y, x);
        const cv::Vec3f av = truth.albedo.at<cv::Vec3f>(y, x);
        const Eigen::Vector3f n(nv[0], nv[1], nv[2]), albedo(av[0], av[1], av[2]);
        const Eigen::Vector3f point = direction * depth;
        const float cosine = n.dot(sun);
        float direct = 0.f;
        if (cosine > 0.f) {
          // Offset along the normal scaled with distance: float precision of far hits.
          const Eigen::Vector3f origin = point + n * (1e-3f * std::max(1.f, depth * 0.01f));
          if (!caster.occluded(origin, sun, 0.f, 1e5f)) direct = cosine;
        }
        const float sky = 0.5f * (1.f + n.dot(up));
        colour = albedo * static_cast<float>(o.sun_irradiance * direct + o.sky_irradiance * sky);
      }
      colour *= static_cast<float>(o.exposure);
      image.at<cv::Vec3f>(y, x) = {colour.x(), colour.y(), colour.z()};
    }
  });
  return image;
}

cv::Mat srgbEncode8(const cv::Mat& linear_rgb) {
  CV_Assert(linear_rgb.type() == CV_32FC3);
  cv::Mat out(linear_rgb.size(), CV_8UC3);
  for (int y = 0; y < linear_rgb.rows; ++y)
    for (int x = 0; x < linear_rgb.cols; ++x) {
      const cv::Vec3f c = linear_rgb.at<cv::Vec3f>(y, x);
      cv::Vec3b& o = out.at<cv::Vec3b>(y, x);
      for (int k = 0; k < 3; ++k) {
        const float v = std::clamp(std::isfinite(c[k]) ? c[k] : 0.f, 0.f, 1.f);
        o[k] = static_cast<unsigned char>(std::lround(linearToSrgb(v) * 255.f));
      }
    }
  return out;
}

}  // namespace solo
