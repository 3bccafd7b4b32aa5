#include "solo/render/ray_caster.h"

#include <embree3/rtcore.h>
#include <tbb/version.h>

#include <stdexcept>

namespace solo {
namespace {

void throwOnEmbreeError(void*, RTCError code, const char* message) {
  throw std::runtime_error("Embree error " + std::to_string(static_cast<int>(code)) + ": " +
                           (message ? message : "unknown"));
}

RTCRay makeRay(const Eigen::Vector3f& o, const Eigen::Vector3f& d, float t_near, float t_far) {
  RTCRay ray;
  ray.org_x = o.x();
  ray.org_y = o.y();
  ray.org_z = o.z();
  ray.dir_x = d.x();
  ray.dir_y = d.y();
  ray.dir_z = d.z();
  ray.tnear = t_near;
  ray.tfar = t_far;
  ray.time = 0.f;
  ray.mask = 0xFFFFFFFFu;
  ray.id = 0;
  ray.flags = 0;
  return ray;
}

}  // namespace

struct RayCaster::Impl {
  std::vector<float> vertices;  // padded by one float: Embree reads 16 bytes per vertex
  std::vector<std::uint32_t> triangles;
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;

  ~Impl() {
    if (scene) rtcReleaseScene(scene);
    if (device) rtcReleaseDevice(device);
  }
};

RayCaster::RayCaster(std::vector<float> vertices, std::vector<std::uint32_t> triangles, bool quality_high)
    : impl_(std::make_unique<Impl>()) {
  if (vertices.size() % 3 != 0 || triangles.size() % 3 != 0)
    throw std::invalid_argument("RayCaster: vertex and index arrays must hold triples");
  const std::size_t vertex_count = vertices.size() / 3;
  for (std::uint32_t index : triangles)
    if (index >= vertex_count) throw std::invalid_argument("RayCaster: triangle index out of range");
  impl_->vertices = std::move(vertices);
  impl_->vertices.push_back(0.f);
  impl_->triangles = std::move(triangles);

  impl_->device = rtcNewDevice(nullptr);
  if (!impl_->device) throw std::runtime_error("Embree: cannot create a device");
  rtcSetDeviceErrorFunction(impl_->device, throwOnEmbreeError, nullptr);
  impl_->scene = rtcNewScene(impl_->device);
  rtcSetSceneBuildQuality(impl_->scene, quality_high ? RTC_BUILD_QUALITY_HIGH : RTC_BUILD_QUALITY_MEDIUM);
  rtcSetSceneFlags(impl_->scene, RTC_SCENE_FLAG_ROBUST);
  if (!impl_->triangles.empty()) {
    RTCGeometry geometry = rtcNewGeometry(impl_->device, RTC_GEOMETRY_TYPE_TRIANGLE);
    rtcSetSharedGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, impl_->vertices.data(), 0,
                               3 * sizeof(float), vertex_count);
    rtcSetSharedGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, impl_->triangles.data(), 0,
                               3 * sizeof(std::uint32_t), impl_->triangles.size() / 3);
    rtcCommitGeometry(geometry);
    rtcAttachGeometry(impl_->scene, geometry);
    rtcReleaseGeometry(geometry);
  }
  rtcCommitScene(impl_->scene);
}

RayCaster::~RayCaster() = default;

std::size_t RayCaster::triangleCount() const { return impl_->triangles.size() / 3; }

RayHit RayCaster::intersect(const Eigen::Vector3f& origin, const Eigen::Vector3f& direction, float t_near,
                            float t_far) const {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRayHit query;
  query.ray = makeRay(origin, direction, t_near, t_far);
  query.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  query.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(impl_->scene, &context, &query);
  RayHit hit;
  if (query.hit.geomID == RTC_INVALID_GEOMETRY_ID) return hit;
  hit.hit = true;
  hit.distance = query.ray.tfar;
  hit.triangle = query.hit.primID;
  hit.geometric_normal = {query.hit.Ng_x, query.hit.Ng_y, query.hit.Ng_z};
  hit.u = query.hit.u;
  hit.v = query.hit.v;
  return hit;
}

bool RayCaster::occluded(const Eigen::Vector3f& origin, const Eigen::Vector3f& direction, float t_near,
                         float t_far) const {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRay ray = makeRay(origin, direction, t_near, t_far);
  rtcOccluded1(impl_->scene, &context, &ray);
  return ray.tfar < 0.f;  // Embree sets tfar to -inf on a hit
}

std::vector<std::pair<std::string, std::string>> renderDependencyVersions() {
  return {{"Embree", RTC_VERSION_STRING},
          {"TBB", std::to_string(TBB_VERSION_MAJOR) + "." + std::to_string(TBB_VERSION_MINOR)}};
}

}  // namespace solo
