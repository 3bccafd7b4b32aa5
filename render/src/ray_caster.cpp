#include "solo/render/ray_caster.h"

#include <embree3/rtcore.h>
#include <tbb/version.h>

#include <array>
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

// Two triangles that share an edge, given to Embree as one quad (v0, v1, v2, v3): Embree splits
// it into (v0, v1, v3) and (v2, v3, v1), so the shared edge is v1-v3. Half the primitives make a
// smaller BVH with faster traversal. A triangle without a partner is the quad (a, b, c, c).
struct QuadSource {
  std::uint32_t first = 0, second = kNoTriangle;  // input triangle indices
  std::uint8_t first_rotation = 0, second_rotation = 0;  // input vertex index of quad v0 / v2
  static constexpr std::uint32_t kNoTriangle = 0xFFFFFFFFu;
};

namespace {

// Pairs each triangle with the next one when they share an edge with consistent orientation
// (as the two halves of a depth mesh's pixel quad, stored one after the other, do).
void pairIntoQuads(const std::vector<std::uint32_t>& triangles, std::vector<std::uint32_t>& quads,
                   std::vector<QuadSource>& sources) {
  const std::size_t count = triangles.size() / 3;
  quads.reserve(count * 4);  // at most one quad per triangle: the arrays are never copied to grow
  sources.reserve(count);
  const auto vertex = [&](std::size_t t, int k) { return triangles[3 * t + static_cast<std::size_t>(k % 3)]; };
  for (std::size_t t = 0; t < count; ++t) {
    QuadSource source;
    source.first = static_cast<std::uint32_t>(t);
    std::array<std::uint32_t, 4> quad = {vertex(t, 0), vertex(t, 1), vertex(t, 2), vertex(t, 2)};
    if (t + 1 < count) {
      // Edge (a[r+1], a[r+2]) of the first is (b[s+2], b[s+1]) of the second, traversed backwards.
      for (int r = 0; r < 3 && source.second == QuadSource::kNoTriangle; ++r)
        for (int s = 0; s < 3; ++s)
          if (vertex(t, r + 1) == vertex(t + 1, s + 2) && vertex(t, r + 2) == vertex(t + 1, s + 1) &&
              vertex(t, r) != vertex(t + 1, s)) {
            quad = {vertex(t, r), vertex(t, r + 1), vertex(t + 1, s), vertex(t, r + 2)};
            source = {static_cast<std::uint32_t>(t), static_cast<std::uint32_t>(t + 1), static_cast<std::uint8_t>(r),
                      static_cast<std::uint8_t>(s)};
            break;
          }
    }
    quads.insert(quads.end(), quad.begin(), quad.end());
    sources.push_back(source);
    if (source.second != QuadSource::kNoTriangle) ++t;
  }
}

}  // namespace

struct RayCaster::Impl {
  std::vector<float> vertices;  // padded by one float: Embree reads 16 bytes per vertex
  std::size_t triangle_count = 0;  // the input's; its index array is not kept (the quads replace it)
  std::vector<std::uint32_t> quads;  // four indices each, handed to Embree
  std::vector<QuadSource> quad_sources;
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
  impl_->triangle_count = triangles.size() / 3;
  pairIntoQuads(triangles, impl_->quads, impl_->quad_sources);

  impl_->device = rtcNewDevice(nullptr);
  if (!impl_->device) throw std::runtime_error("Embree: cannot create a device");
  rtcSetDeviceErrorFunction(impl_->device, throwOnEmbreeError, nullptr);
  impl_->scene = rtcNewScene(impl_->device);
  rtcSetSceneBuildQuality(impl_->scene, quality_high ? RTC_BUILD_QUALITY_HIGH : RTC_BUILD_QUALITY_MEDIUM);
  rtcSetSceneFlags(impl_->scene, RTC_SCENE_FLAG_ROBUST);
  if (!impl_->quads.empty()) {
    RTCGeometry geometry = rtcNewGeometry(impl_->device, RTC_GEOMETRY_TYPE_QUAD);
    rtcSetSharedGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, impl_->vertices.data(), 0,
                               3 * sizeof(float), vertex_count);
    rtcSetSharedGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT4, impl_->quads.data(), 0,
                               4 * sizeof(std::uint32_t), impl_->quads.size() / 4);
    rtcCommitGeometry(geometry);
    rtcAttachGeometry(impl_->scene, geometry);
    rtcReleaseGeometry(geometry);
  }
  rtcCommitScene(impl_->scene);
}

RayCaster::~RayCaster() = default;

std::size_t RayCaster::triangleCount() const { return impl_->triangle_count; }

std::size_t RayCaster::primitiveCount() const { return impl_->quad_sources.size(); }

namespace {

// Embree's closest hit: geomID is RTC_INVALID_GEOMETRY_ID for a miss.
RTCRayHit closestHit(RTCScene scene, const Eigen::Vector3f& origin, const Eigen::Vector3f& direction, float t_near,
                     float t_far) {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRayHit query;
  query.ray = makeRay(origin, direction, t_near, t_far);
  query.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  query.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(scene, &context, &query);
  return query;
}

/// A RayHit or SlotHit with what they share filled in from Embree's answer: whether the ray hit
/// and at what distance (a miss keeps the defaults).
template <typename Hit>
Hit hitOrMiss(const RTCRayHit& query) {
  Hit hit;
  if (query.hit.geomID == RTC_INVALID_GEOMETRY_ID) return hit;
  hit.hit = true;
  hit.distance = query.ray.tfar;
  return hit;
}

/// Whether a hit lies in the second half (v2, v3, v1) of its quad rather than the first (v0, v1, v3).
bool inSecondHalf(const RTCHit& hit) { return hit.u + hit.v > 1.f; }

}  // namespace

RayHit RayCaster::intersect(const Eigen::Vector3f& origin, const Eigen::Vector3f& direction, float t_near,
                            float t_far) const {
  const RTCRayHit query = closestHit(impl_->scene, origin, direction, t_near, t_far);
  RayHit hit = hitOrMiss<RayHit>(query);
  if (!hit.hit) return hit;
  hit.geometric_normal = {query.hit.Ng_x, query.hit.Ng_y, query.hit.Ng_z};
  // Back from the quad's (u, v) to the barycentrics of the input triangle's vertices 1 and 2.
  const QuadSource& source = impl_->quad_sources[query.hit.primID];
  std::array<float, 3> weight{};
  int rotation = source.first_rotation;
  float along_next = query.hit.u, along_previous = query.hit.v;  // (v0, v1, v3): weights of v1, v3
  hit.triangle = source.first;
  if (source.second != QuadSource::kNoTriangle && inSecondHalf(query.hit)) {
    rotation = source.second_rotation;  // (v2, v3, v1): weights of v3, v1 are 1 - u, 1 - v
    along_next = 1.f - query.hit.u;
    along_previous = 1.f - query.hit.v;
    hit.triangle = source.second;
  }
  weight[static_cast<std::size_t>(rotation)] = 1.f - along_next - along_previous;
  weight[static_cast<std::size_t>((rotation + 1) % 3)] = along_next;
  weight[static_cast<std::size_t>((rotation + 2) % 3)] = along_previous;
  hit.u = weight[1];
  hit.v = weight[2];
  return hit;
}

SlotHit RayCaster::intersectSlot(const Eigen::Vector3f& origin, const Eigen::Vector3f& direction, float t_near,
                                 float t_far) const {
  const RTCRayHit query = closestHit(impl_->scene, origin, direction, t_near, t_far);
  SlotHit hit = hitOrMiss<SlotHit>(query);
  if (!hit.hit) return hit;
  hit.slot = 2 * query.hit.primID + (inSecondHalf(query.hit) ? 1u : 0u);
  return hit;
}

std::vector<std::uint32_t> RayCaster::slotTriangles() const {
  std::vector<std::uint32_t> triangles;
  triangles.reserve(slotCount());
  for (const QuadSource& source : impl_->quad_sources) {
    triangles.push_back(source.first);
    triangles.push_back(source.second != QuadSource::kNoTriangle ? source.second : source.first);
  }
  return triangles;
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
