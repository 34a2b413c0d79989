#include "sim/raycaster.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <mutex>
#include <string>
#include <vector>

#include "core/parallel.h"

namespace voxplan {

namespace {

// Pixels per tile side; one ParallelFor item per tile keeps rays of a task coherent.
constexpr int kTileSize = 16;
// Packet footprint: 4 x 4 pixels fill one 16-wide Embree packet (AVX-512; Embree splits it
// on narrower CPUs).
constexpr int kPacketW = 4;
constexpr int kPacketH = 4;
constexpr int kPacketSize = kPacketW * kPacketH;
constexpr uint8_t kDefaultGrey = 180;

// Embree reports errors through this callback; the first one is kept as a Status.
struct ErrorSink {
  std::mutex mutex;
  Status status;
  void Record(RTCError code, const char* message) {
    std::lock_guard<std::mutex> lock(mutex);
    if (status.ok())
      status = Status(StatusCode::kInternal, "Embree error " + std::to_string(int(code)) + ": " +
                                                 (message ? message : "(no message)"));
  }
};

void OnEmbreeError(void* user_ptr, RTCError code, const char* message) {
  static_cast<ErrorSink*>(user_ptr)->Record(code, message);
}

}  // namespace

namespace {
// What the cutaway filter reads: the raycaster's own copies, which outlive the Embree scene.
struct CutawayView {
  const std::vector<float>* vertices = nullptr;
  const std::vector<uint32_t>* indices = nullptr;
  const MeshCutaway* cutaway = nullptr;
};
}  // namespace

struct MeshRaycaster::Impl {
  ErrorSink errors;
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  // Owned copies so the caller's Mesh may die; Embree reads them through shared buffers.
  std::vector<float> vertices_xyz;  // 3 floats per vertex plus one pad float (Embree reads 16 B)
  std::vector<uint32_t> indices;    // 3 per triangle
  std::vector<std::array<uint8_t, 3>> colors;  // empty or one per vertex
  std::vector<uint32_t> triangle_instance;     // empty or one per triangle
  MeshCutaway cutaway;
  CutawayView view;

  ~Impl() {
    if (scene) rtcReleaseScene(scene);
    if (device) rtcReleaseDevice(device);
  }

  Status TakeError() {
    std::lock_guard<std::mutex> lock(errors.mutex);
    return errors.status;
  }

  uint32_t Shade(uint32_t prim_id, float b1, float b2) const {
    if (colors.empty()) return PackRgb(kDefaultGrey, kDefaultGrey, kDefaultGrey);
    const uint32_t* tri = &indices[size_t(prim_id) * 3];
    const float b0 = 1.f - b1 - b2;
    const auto& c0 = colors[tri[0]];
    const auto& c1 = colors[tri[1]];
    const auto& c2 = colors[tri[2]];
    std::array<uint8_t, 3> rgb;
    for (int k = 0; k < 3; ++k) {
      const float c = b0 * float(c0[k]) + b1 * float(c1[k]) + b2 * float(c2[k]);
      rgb[k] = uint8_t(std::clamp(c + 0.5f, 0.f, 255.f));  // round half up; c >= 0
    }
    return PackRgb(rgb[0], rgb[1], rgb[2]);
  }
};

namespace {

// Embree's intersection filter for a cutaway: rejects candidate hits on back faces (normal from
// our counter-clockwise winding, not Embree's Ng convention) and beyond the cut height.
void CutawayFilter(const RTCFilterFunctionNArguments* args) {
  const auto* impl = static_cast<const CutawayView*>(args->geometryUserPtr);
  for (unsigned i = 0; i < args->N; ++i) {
    if (args->valid[i] != -1) continue;
    const Eigen::Vector3f dir(RTCRayN_dir_x(args->ray, args->N, i),
                              RTCRayN_dir_y(args->ray, args->N, i),
                              RTCRayN_dir_z(args->ray, args->N, i));
    if (impl->cutaway->cull_back_faces) {
      const uint32_t* tri = &(*impl->indices)[size_t(RTCHitN_primID(args->hit, args->N, i)) * 3];
      const auto vertex = [&](uint32_t v) {
        return Eigen::Vector3f((*impl->vertices)[v * 3], (*impl->vertices)[v * 3 + 1],
                               (*impl->vertices)[v * 3 + 2]);
      };
      const Eigen::Vector3f a = vertex(tri[0]);
      if ((vertex(tri[1]) - a).cross(vertex(tri[2]) - a).dot(dir) >= 0.f) {
        args->valid[i] = 0;
        continue;
      }
    }
    if (impl->cutaway->cut_above) {
      const Eigen::Vector3f org(RTCRayN_org_x(args->ray, args->N, i),
                                RTCRayN_org_y(args->ray, args->N, i),
                                RTCRayN_org_z(args->ray, args->N, i));
      // During filtering the ray's tfar holds the candidate hit's distance.
      const Eigen::Vector3f p = org + RTCRayN_tfar(args->ray, args->N, i) * dir;
      if (p.dot(impl->cutaway->up_W) > impl->cutaway->max_height_m) args->valid[i] = 0;
    }
  }
}

}  // namespace

Result<std::unique_ptr<MeshRaycaster>> MeshRaycaster::Create(const Mesh& mesh,
                                                             const MeshCutaway& cutaway) {
  const size_t nv = mesh.num_vertices();
  const size_t nt = mesh.num_triangles();
  if (!mesh.colors.empty() && mesh.colors.size() != nv)
    return InvalidArgument("MeshRaycaster: " + std::to_string(mesh.colors.size()) +
                           " colours for " + std::to_string(nv) + " vertices");
  for (size_t i = 0; i < nv; ++i)
    if (!mesh.positions[i].allFinite())
      return InvalidArgument("MeshRaycaster: vertex " + std::to_string(i) + " is not finite");
  for (size_t t = 0; t < nt; ++t)
    for (uint32_t idx : mesh.triangles[t])
      if (idx >= nv)
        return InvalidArgument("MeshRaycaster: triangle " + std::to_string(t) + " indexes vertex " +
                               std::to_string(idx) + " of " + std::to_string(nv));

  std::unique_ptr<MeshRaycaster> raycaster(new MeshRaycaster());
  raycaster->impl_ = std::make_unique<Impl>();
  Impl& impl = *raycaster->impl_;

  impl.device = rtcNewDevice(nullptr);
  if (!impl.device)
    return Status(StatusCode::kInternal, "Embree device creation failed, error code " +
                                             std::to_string(int(rtcGetDeviceError(nullptr))));
  rtcSetDeviceErrorFunction(impl.device, OnEmbreeError, &impl.errors);

  impl.vertices_xyz.resize(nv * 3 + 1, 0.f);
  for (size_t i = 0; i < nv; ++i)
    for (int k = 0; k < 3; ++k) impl.vertices_xyz[i * 3 + k] = mesh.positions[i][k];
  impl.indices.resize(nt * 3);
  for (size_t t = 0; t < nt; ++t)
    for (int k = 0; k < 3; ++k) impl.indices[t * 3 + k] = mesh.triangles[t][k];
  impl.colors = mesh.colors;
  impl.cutaway = cutaway;
  impl.view = {&impl.vertices_xyz, &impl.indices, &impl.cutaway};

  impl.scene = rtcNewScene(impl.device);
  if (impl.scene) {
    // Robust traversal: no rays slip through shared edges of the closed rooms we render.
    rtcSetSceneFlags(impl.scene, RTC_SCENE_FLAG_ROBUST);
    rtcSetSceneBuildQuality(impl.scene, RTC_BUILD_QUALITY_HIGH);
    if (nt > 0) {
      RTCGeometry geometry = rtcNewGeometry(impl.device, RTC_GEOMETRY_TYPE_TRIANGLE);
      if (geometry) {
        rtcSetSharedGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                   impl.vertices_xyz.data(), 0, 3 * sizeof(float), nv);
        rtcSetSharedGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                   impl.indices.data(), 0, 3 * sizeof(uint32_t), nt);
        if (cutaway.any()) {
          rtcSetGeometryUserData(geometry, &impl.view);
          rtcSetGeometryIntersectFilterFunction(geometry, CutawayFilter);
        }
        rtcCommitGeometry(geometry);
        rtcAttachGeometryByID(impl.scene, geometry, 0);
        rtcReleaseGeometry(geometry);
      }
    }
    rtcCommitScene(impl.scene);
  }
  if (Status s = impl.TakeError(); !s.ok()) return s.WithContext("MeshRaycaster::Create");
  if (!impl.scene) return Status(StatusCode::kInternal, "MeshRaycaster::Create: no Embree scene");
  return raycaster;
}

Result<std::unique_ptr<MeshRaycaster>> MeshRaycaster::Create(const World& world) {
  if (world.triangle_instance.size() != world.mesh.num_triangles())
    return InvalidArgument("MeshRaycaster: world '" + world.name + "' has " +
                           std::to_string(world.triangle_instance.size()) + " instance ids for " +
                           std::to_string(world.mesh.num_triangles()) + " triangles");
  auto raycaster = Create(world.mesh);
  if (!raycaster.ok()) return raycaster.status();
  (*raycaster)->impl_->triangle_instance = world.triangle_instance;
  return raycaster;
}

MeshRaycaster::~MeshRaycaster() = default;

RenderOutput MeshRaycaster::Render(const PinholeCamera& camera, const Pose3f& T_W_C,
                                   const RenderParams& params) const {
  RenderOutput out;
  if (!camera.Valid()) return out;
  const int width = camera.width, height = camera.height;
  out.depth = DepthImage(width, height, 0.f);
  if (params.color) out.color = ColorImage(width, height, PackRgb(0, 0, 0));
  if (params.labels) out.labels = LabelImage(width, height, kNoInstance);
  if (params.normals)
    out.normals_C = Image<Eigen::Vector3f>(width, height, Eigen::Vector3f::Zero());

  // Ray directions keep z_C = 1, so the hit distance t is the depth along the optical axis
  // whatever the signs of fx, fy. dir_W = R_W_C * (x_C, y_C, 1) splits into a per-column and a
  // per-row term, computed once each.
  const Eigen::Matrix3f R_W_C = T_W_C.linear();
  const Eigen::Vector3f origin_W = T_W_C.translation();
  std::vector<Eigen::Vector3f> column_term(size_t(width) + kPacketW);
  std::vector<Eigen::Vector3f> row_term(size_t(height) + kPacketH);
  for (size_t u = 0; u < column_term.size(); ++u)
    column_term[u] = R_W_C.col(0) * ((float(u) - camera.cx) / camera.fx);
  for (size_t v = 0; v < row_term.size(); ++v)
    row_term[v] = R_W_C.col(1) * ((float(v) - camera.cy) / camera.fy) + R_W_C.col(2);
  const float t_far =
      params.max_range_m > 0.f ? params.max_range_m : std::numeric_limits<float>::infinity();
  const int tiles_x = (width + kTileSize - 1) / kTileSize;
  const int tiles_y = (height + kTileSize - 1) / kTileSize;
  const Impl& impl = *impl_;

  ParallelFor(size_t(tiles_x) * size_t(tiles_y), 1, [&](size_t begin, size_t end) {
    RTCIntersectContext context;
    alignas(64) int valid[kPacketSize];
    alignas(64) RTCRayHit16 rayhit;
    for (size_t tile = begin; tile < end; ++tile) {
      const int u0 = int(tile % size_t(tiles_x)) * kTileSize;
      const int v0 = int(tile / size_t(tiles_x)) * kTileSize;
      const int u1 = std::min(u0 + kTileSize, width), v1 = std::min(v0 + kTileSize, height);
      for (int pv = v0; pv < v1; pv += kPacketH)
        for (int pu = u0; pu < u1; pu += kPacketW) {
          for (int i = 0; i < kPacketSize; ++i) {
            // Lanes past the image edge stay inactive; their (padded) directions are unused.
            const int u = pu + i % kPacketW, v = pv + i / kPacketW;
            valid[i] = (u < u1 && v < v1) ? -1 : 0;
            const Eigen::Vector3f dir_W = column_term[size_t(u)] + row_term[size_t(v)];
            rayhit.ray.org_x[i] = origin_W.x();
            rayhit.ray.org_y[i] = origin_W.y();
            rayhit.ray.org_z[i] = origin_W.z();
            rayhit.ray.dir_x[i] = dir_W.x();
            rayhit.ray.dir_y[i] = dir_W.y();
            rayhit.ray.dir_z[i] = dir_W.z();
            rayhit.ray.tnear[i] = 0.f;
            rayhit.ray.tfar[i] = t_far;
            rayhit.ray.time[i] = 0.f;
            rayhit.ray.mask[i] = ~0u;
            rayhit.ray.id[i] = unsigned(i);
            rayhit.ray.flags[i] = 0;
            rayhit.hit.geomID[i] = RTC_INVALID_GEOMETRY_ID;
            rayhit.hit.primID[i] = RTC_INVALID_GEOMETRY_ID;
            rayhit.hit.instID[0][i] = RTC_INVALID_GEOMETRY_ID;
          }
          rtcInitIntersectContext(&context);
          context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
          rtcIntersect16(valid, impl.scene, &context, &rayhit);
          for (int i = 0; i < kPacketSize; ++i) {
            if (!valid[i] || rayhit.hit.geomID[i] == RTC_INVALID_GEOMETRY_ID) continue;
            const int u = pu + i % kPacketW, v = pv + i / kPacketW;
            const uint32_t prim = rayhit.hit.primID[i];
            out.depth.at(u, v) = rayhit.ray.tfar[i];
            if (params.color)
              out.color.at(u, v) = impl.Shade(prim, rayhit.hit.u[i], rayhit.hit.v[i]);
            if (params.labels && !impl.triangle_instance.empty())
              out.labels.at(u, v) = impl.triangle_instance[prim];
            if (params.normals) {
              // Ng is unnormalised and world-frame. Turned against the lane's own world ray (a
              // rotation keeps the dot product's sign) and scaled by one reciprocal: the
              // divisions of a per-pixel camera ray and of normalized() were most of this loop.
              const float nx = rayhit.hit.Ng_x[i], ny = rayhit.hit.Ng_y[i], nz = rayhit.hit.Ng_z[i];
              const float along =
                  nx * rayhit.ray.dir_x[i] + ny * rayhit.ray.dir_y[i] + nz * rayhit.ray.dir_z[i];
              const float norm2 = nx * nx + ny * ny + nz * nz;
              if (norm2 > 0.f) {
                const float scale = (along > 0.f ? -1.f : 1.f) / std::sqrt(norm2);
                out.normals_C.at(u, v) =
                    R_W_C.transpose() * Eigen::Vector3f(nx * scale, ny * scale, nz * scale);
              }
            }
          }
        }
    }
  });
  return out;
}

}  // namespace voxplan
