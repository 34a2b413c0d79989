// Header-only C++ layer over planner_api.h for in-tree planners: write a class deriving from
// vp::Planner, construct it from a vp::Config, and export it with one macro.
//
//   class NearestFrontier : public vp::Planner {
//    public:
//     explicit NearestFrontier(const vp::Config& config);
//     void Plan(const vp::WorldView& world, vp::PlanOutput& out) override;
//   };
//   VP_PLANNER_EXPORT(NearestFrontier, "nearest", "1.0.0")
//
// Errors inside a plugin are exceptions (vp::Error, or any std::exception); the macro's
// trampolines catch every one at the boundary and turn it into a status code plus message, so
// nothing but integers and C structs crosses. Plugins may use Eigen or anything header-only but
// never link voxplan libraries: all they know of the engine is the host table.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <exception>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "plugins/planner_api.h"

namespace vp {

// A failed host call or a planner's own refusal; `status` is what crosses the boundary.
class Error : public std::runtime_error {
 public:
  Error(vp_status status, const std::string& message)
      : std::runtime_error(message), status_(status) {}
  vp_status status() const { return status_; }

 private:
  vp_status status_;
};

inline void Check(vp_status status, const char* what) {
  if (status != VP_OK) {
    throw Error(status, std::string(what) + " failed with status " + std::to_string(status));
  }
}

// What create() received: the planner's options as JSON text ("{}" for defaults) and the seed.
struct Config {
  std::string json = "{}";
  uint64_t seed = 0;
};

// The floor raster of one plan() call (host memory, valid until Plan returns).
class FloorView {
 public:
  explicit FloorView(const vp_floor& floor) : f_(floor) {}
  int width() const { return f_.width; }
  int height() const { return f_.height; }
  float cell_size_m() const { return f_.cell_size_m; }
  uint64_t revision() const { return f_.revision; }
  size_t size() const { return size_t(f_.width) * size_t(f_.height); }
  bool Contains(int ix, int iy) const {
    return ix >= 0 && iy >= 0 && ix < f_.width && iy < f_.height;
  }
  size_t Linear(int ix, int iy) const { return size_t(iy) * size_t(f_.width) + size_t(ix); }
  // VP_FLOOR_*; unknown outside the raster.
  uint8_t Cell(int ix, int iy) const {
    return Contains(ix, iy) ? f_.cells[Linear(ix, iy)] : uint8_t(VP_FLOOR_UNKNOWN);
  }
  float Clearance(int ix, int iy) const {
    return Contains(ix, iy) ? f_.clearance_m[Linear(ix, iy)] : 0.0f;
  }
  std::span<const uint8_t> cells() const { return {f_.cells, size()}; }
  std::span<const float> clearance_m() const { return {f_.clearance_m, size()}; }
  // World xy of a cell centre; the raster cell of a world point (may lie outside).
  std::pair<float, float> CellCenter(int ix, int iy) const {
    return {f_.origin_x_m + (float(ix) + 0.5f) * f_.cell_size_m,
            f_.origin_y_m + (float(iy) + 0.5f) * f_.cell_size_m};
  }
  std::pair<int, int> CellOf(float x_m, float y_m) const {
    return {int(std::floor((x_m - f_.origin_x_m) / f_.cell_size_m)),
            int(std::floor((y_m - f_.origin_y_m) / f_.cell_size_m))};
  }
  const vp_floor& raw() const { return f_; }

 private:
  vp_floor f_;
};

// A vp_task_ext that changes nothing: the mount's rest pose, no look-at, no sweep, no object.
inline vp_task_ext DefaultTaskExt() {
  vp_task_ext e{};
  e.struct_size = sizeof(e);
  e.camera_height_m = std::numeric_limits<float>::quiet_NaN();
  e.camera_offset_m[0] = e.camera_offset_m[1] = std::numeric_limits<float>::quiet_NaN();
  e.object_id = -1;
  return e;
}

// Read-only view of the maps for one plan() call. Spans point at host memory that stays valid
// until Plan returns; copy what must outlive it.
class WorldView {
 public:
  WorldView(const vp_host_api* host, const vp_world* world) : host_(host), world_(world) {
    call_.struct_size = sizeof(call_);
    Check(host_->get_call_info(world_, &call_), "get_call_info");
  }

  const vp_call_info& call() const { return call_; }
  int32_t event() const { return call_.event; }
  uint64_t seed() const { return call_.seed; }
  double ElapsedS() const { return host_->elapsed_s(world_); }
  // Seconds left of the time budget; infinity when there is none.
  double TimeLeftS() const {
    return call_.time_budget_s > 0.0 ? call_.time_budget_s - ElapsedS()
                                     : std::numeric_limits<double>::infinity();
  }
  void Log(int32_t level, const std::string& message) const {
    host_->log(world_, level, message.c_str());
  }

  vp_map_info MapInfo() const {
    vp_map_info info{};
    info.struct_size = sizeof(info);
    Check(host_->get_map_info(world_, &info), "get_map_info");
    return info;
  }
  // points_xyz holds 3 floats per point; one VP_VOXEL_* per point.
  std::vector<uint8_t> VoxelStates(std::span<const float> points_xyz) const {
    std::vector<uint8_t> states(points_xyz.size() / 3);
    Check(host_->voxel_states(world_, points_xyz.data(), states.size(), states.data()),
          "voxel_states");
    return states;
  }
  std::vector<vp_ray_hit> Raycast(std::span<const vp_ray> rays) const {
    std::vector<vp_ray_hit> hits(rays.size());
    Check(host_->raycast(world_, rays.data(), rays.size(), hits.data()), "raycast");
    return hits;
  }
  // 3 floats per frontier voxel centre.
  std::span<const float> FrontierVoxels() const {
    const float* xyz = nullptr;
    uint64_t count = 0;
    Check(host_->get_frontier_voxels(world_, &xyz, &count), "get_frontier_voxels");
    return {xyz, size_t(count) * 3};
  }
  std::span<const vp_surface_voxel> SurfaceVoxels() const {
    const vp_surface_voxel* voxels = nullptr;
    uint64_t count = 0;
    Check(host_->get_surface_voxels(world_, &voxels, &count), "get_surface_voxels");
    return {voxels, size_t(count)};
  }

  FloorView Floor() const {
    vp_floor floor{};
    floor.struct_size = sizeof(floor);
    Check(host_->get_floor(world_, &floor), "get_floor");
    return FloorView(floor);
  }
  // Geodesic distance from (x, y) to every floor cell over cells with at least min_clearance_m;
  // +inf where unreachable.
  std::span<const float> GeodesicField(float x_m, float y_m, float min_clearance_m) const {
    const float source[2] = {x_m, y_m};
    const float* field = nullptr;
    Check(host_->geodesic_field(world_, source, min_clearance_m, &field), "geodesic_field");
    return {field, Floor().size()};
  }
  // Row-major n x n geodesic distances between n points (2 floats each).
  std::span<const float> DistanceMatrix(std::span<const float> points_xy,
                                        float min_clearance_m) const {
    const uint32_t n = uint32_t(points_xy.size() / 2);
    const float* matrix = nullptr;
    Check(host_->distance_matrix(world_, points_xy.data(), n, min_clearance_m, &matrix),
          "distance_matrix");
    return {matrix, size_t(n) * n};
  }
  // xy pairs from -> to, or nullopt when no traversable path exists.
  std::optional<std::vector<float>> ShortestPath(float from_x, float from_y, float to_x, float to_y,
                                                 float min_clearance_m) const {
    const float from[2] = {from_x, from_y}, to[2] = {to_x, to_y};
    const float* xy = nullptr;
    uint32_t count = 0;
    const vp_status s = host_->shortest_path(world_, from, to, min_clearance_m, &xy, &count);
    if (s == VP_ERROR_NOT_AVAILABLE) return std::nullopt;
    Check(s, "shortest_path");
    return std::vector<float>(xy, xy + size_t(count) * 2);
  }

  // The named extension table (planner_api.h, "Growth") at min_version or later, or nullptr.
  // T is the table's struct (e.g. vp_objects_ext).
  template <class T>
  const T* Extension(const char* name, uint32_t min_version) const {
    const vp_extension_header* h = host_->get_extension(name, min_version);
    if (h == nullptr || h->struct_size < sizeof(T)) return nullptr;
    return reinterpret_cast<const T*>(h);
  }
  // The same, or a vp::Error naming the extension when this host lacks it.
  template <class T>
  const T& RequireExtension(const char* name, uint32_t min_version) const {
    const T* table = Extension<T>(name, min_version);
    if (table == nullptr) {
      throw Error(VP_ERROR_NOT_AVAILABLE, std::string("this host has no extension ") + name +
                                              " version " + std::to_string(min_version) +
                                              " or later; run it with a newer voxplan");
    }
    return *table;
  }
  // vp.objects 1: the surface voxels of one instance.
  std::span<const vp_surface_voxel> InstanceSurface(uint32_t id) const {
    const auto& ext = RequireExtension<vp_objects_ext>(VP_EXT_OBJECTS, 1);
    const vp_surface_voxel* voxels = nullptr;
    uint64_t count = 0;
    Check(ext.get_instance_surface(world_, id, &voxels, &count), "get_instance_surface");
    return {voxels, size_t(count)};
  }

  // vp.task 1: the camera parts of Queue(robot)'s tasks, in the same order.
  std::vector<vp_task_ext> QueueExt(uint32_t robot) const {
    const auto& ext = RequireExtension<vp_task_ext_table>(VP_EXT_TASK, 1);
    const vp_task_ext* first = nullptr;
    uint32_t count = 0;
    Check(ext.get_robot_queue_ext(world_, robot, &first, &count), "get_robot_queue_ext");
    std::vector<vp_task_ext> out;
    if (count == 0) return out;
    // The host's records may be longer than this header's: step by its size, keep ours.
    const uint32_t stride = first->struct_size;
    for (uint32_t i = 0; i < count; ++i) {
      vp_task_ext e = DefaultTaskExt();
      const char* p = reinterpret_cast<const char*>(first) + size_t(i) * stride;
      std::memcpy(&e, p, std::min<size_t>(sizeof(e), stride));
      e.struct_size = sizeof(e);
      out.push_back(e);
    }
    return out;
  }

  std::span<const vp_instance> Instances() const {
    const vp_instance* instances = nullptr;
    uint32_t count = 0;
    Check(host_->get_instances(world_, &instances, &count), "get_instances");
    return {instances, count};
  }

  uint32_t RobotCount() const { return host_->robot_count(world_); }
  vp_robot Robot(uint32_t robot) const {
    vp_robot r{};
    r.struct_size = sizeof(r);
    Check(host_->get_robot(world_, robot, &r), "get_robot");
    return r;
  }
  vp_mode_params Mode(uint32_t robot, uint32_t mode) const {
    vp_mode_params m{};
    m.struct_size = sizeof(m);
    Check(host_->get_robot_mode(world_, robot, mode, &m), "get_robot_mode");
    return m;
  }
  std::span<const vp_task> Queue(uint32_t robot) const {
    const vp_task* tasks = nullptr;
    uint32_t count = 0;
    Check(host_->get_robot_queue(world_, robot, &tasks, &count), "get_robot_queue");
    return {tasks, count};
  }

  const vp_host_api* host() const { return host_; }
  const vp_world* world() const { return world_; }

 private:
  const vp_host_api* host_;
  const vp_world* world_;
  vp_call_info call_{};
};

// What a plan() call answers; every method copies its arguments into the host.
class PlanOutput {
 public:
  PlanOutput(const vp_host_api* host, vp_plan_output* out) : host_(host), out_(out) {}

  void ReplaceTasks(uint32_t robot) {
    Check(host_->set_task_policy(out_, robot, VP_TASKS_REPLACE), "set_task_policy");
  }
  void AppendTasks(uint32_t robot) {
    Check(host_->set_task_policy(out_, robot, VP_TASKS_APPEND), "set_task_policy");
  }
  void AddTask(uint32_t robot, const vp_task& task) {
    Check(host_->add_task(out_, robot, &task), "add_task");
  }
  // vp.task 1: a task with its camera part (DefaultTaskExt() for the fields left alone).
  void AddTask(uint32_t robot, const vp_task& task, const vp_task_ext& camera) {
    Check(Table<vp_task_ext_table>(VP_EXT_TASK).add_task_ext(out_, robot, &task, &camera),
          "add_task_ext");
  }
  void SetPath(uint32_t robot, std::span<const vp_path_point> points) {
    Check(host_->set_path(out_, robot, points.data(), uint32_t(points.size())), "set_path");
  }
  // vp.motion 1: a path driven without stopping, at a speed per point (empty: the mode's).
  void SetContinuousPath(uint32_t robot, std::span<const vp_path_point> points,
                         std::span<const float> speeds_mps = {}) {
    if (!speeds_mps.empty() && speeds_mps.size() != points.size())
      throw Error(VP_ERROR_INVALID_ARGUMENT, "SetContinuousPath: one speed per point");
    const vp_path_ext ext = {sizeof(vp_path_ext), VP_PATH_CONTINUOUS,
                             speeds_mps.empty() ? nullptr : speeds_mps.data()};
    Check(Table<vp_motion_ext>(VP_EXT_MOTION)
              .set_path_ext(out_, robot, points.data(), uint32_t(points.size()), &ext),
          "set_path_ext");
  }
  // vp.schedule 1: be called (VP_EVENT_WAKEUP) at run time t_s.
  void RequestCall(double t_s) {
    Check(Table<vp_schedule_ext>(VP_EXT_SCHEDULE).request_call(out_, t_s), "request_call");
  }
  void SetCameraTrajectory(uint32_t robot, std::span<const vp_camera_sample> samples) {
    Check(host_->set_camera_trajectory(out_, robot, samples.data(), uint32_t(samples.size())),
          "set_camera_trajectory");
  }
  void SetDone(bool done) { Check(host_->set_done(out_, done ? 1 : 0), "set_done"); }
  void Diagnostic(const std::string& name, double value) {
    Check(host_->add_diagnostic(out_, name.c_str(), value), "add_diagnostic");
  }
  void DebugPoints(const std::string& layer, std::span<const float> xyz, uint32_t rgba) {
    Check(host_->add_debug_points(out_, layer.c_str(), xyz.data(), uint32_t(xyz.size() / 3), rgba),
          "add_debug_points");
  }
  void DebugPolyline(const std::string& layer, std::span<const float> xyz, uint32_t rgba) {
    Check(
        host_->add_debug_polyline(out_, layer.c_str(), xyz.data(), uint32_t(xyz.size() / 3), rgba),
        "add_debug_polyline");
  }
  void DebugLabel(const std::string& layer, float x, float y, float z, const std::string& text,
                  uint32_t rgba) {
    const float xyz[3] = {x, y, z};
    Check(host_->add_debug_label(out_, layer.c_str(), xyz, text.c_str(), rgba), "add_debug_label");
  }

 private:
  // An output-side extension table at version 1 or later; refused with the reason otherwise.
  template <typename T>
  const T& Table(const char* name) const {
    const vp_extension_header* h = host_->get_extension(name, 1);
    if (h == nullptr || h->struct_size < sizeof(T))
      throw Error(VP_ERROR_NOT_AVAILABLE, std::string("this host has no extension ") + name +
                                              " version 1; run it with a newer voxplan");
    return *reinterpret_cast<const T*>(h);
  }
  const vp_host_api* host_;
  vp_plan_output* out_;
};

// Reports the milliseconds from construction to destruction as diagnostic "<stage>_ms".
class StageTimer {
 public:
  StageTimer(const WorldView& world, PlanOutput& out, std::string stage)
      : world_(world), out_(out), stage_(std::move(stage)), start_s_(world.ElapsedS()) {}
  ~StageTimer() {
    try {
      out_.Diagnostic(stage_ + "_ms", (world_.ElapsedS() - start_s_) * 1e3);
    } catch (...) {  // a destructor must not throw; a lost timing is harmless
    }
  }

 private:
  const WorldView& world_;
  PlanOutput& out_;
  std::string stage_;
  double start_s_;
};

// Base of every in-tree planner. Plan may throw; the boundary catches it.
class Planner {
 public:
  virtual ~Planner() = default;
  virtual void Plan(const WorldView& world, PlanOutput& out) = 0;
};

}  // namespace vp

// The plugin's instance behind the opaque handle (defined only inside plugins).
struct vp_planner {
  std::unique_ptr<vp::Planner> impl;
  const vp_host_api* host = nullptr;
};

namespace vp::detail {

inline void CopyMessage(const char* message, char* buffer, uint32_t size) noexcept {
  if (buffer == nullptr || size == 0) return;
  const size_t n = std::min<size_t>(std::strlen(message), size - 1);
  std::memcpy(buffer, message, n);
  buffer[n] = '\0';
}

template <class PlannerT>
vp_status Create(const vp_host_api* host, const char* config_json, uint64_t seed, vp_planner** out,
                 char* error, uint32_t error_size) noexcept {
  if (out == nullptr || host == nullptr) return VP_ERROR_INVALID_ARGUMENT;
  *out = nullptr;
  try {
    auto instance = std::make_unique<vp_planner>();
    instance->host = host;
    instance->impl = std::make_unique<PlannerT>(Config{config_json ? config_json : "{}", seed});
    *out = instance.release();
    return VP_OK;
  } catch (const Error& e) {
    CopyMessage(e.what(), error, error_size);
    return e.status() == VP_OK ? VP_ERROR_PLUGIN : e.status();
  } catch (const std::exception& e) {
    CopyMessage(e.what(), error, error_size);
  } catch (...) {
    CopyMessage("unknown exception in create", error, error_size);
  }
  return VP_ERROR_PLUGIN;
}

inline void SetError(vp_planner* self, vp_plan_output* out, const char* message) noexcept {
  self->host->set_error(out, message);
}

inline vp_status Plan(vp_planner* self, const vp_world* world, vp_plan_output* out) noexcept {
  if (self == nullptr || world == nullptr || out == nullptr) return VP_ERROR_INVALID_ARGUMENT;
  try {
    const WorldView view(self->host, world);
    PlanOutput output(self->host, out);
    self->impl->Plan(view, output);
    return VP_OK;
  } catch (const Error& e) {
    SetError(self, out, e.what());
    return e.status() == VP_OK ? VP_ERROR_PLUGIN : e.status();
  } catch (const std::exception& e) {
    SetError(self, out, e.what());
  } catch (...) {
    SetError(self, out, "unknown exception in plan");
  }
  return VP_ERROR_PLUGIN;
}

inline void Destroy(vp_planner* self) noexcept { delete self; }

// The body of vp_planner_entry: version and size negotiation, then the table.
template <class PlannerT>
vp_status Entry(uint32_t host_abi_version, const vp_host_api* host, vp_planner_api* out,
                const char* name, const char* version) noexcept {
  // struct_size and abi_version are the first 8 bytes in every ABI version.
  if (out == nullptr || out->struct_size < 2 * sizeof(uint32_t)) return VP_ERROR_STRUCT_SIZE;
  out->abi_version = VP_PLANNER_ABI_VERSION;
  if (host_abi_version != VP_PLANNER_ABI_VERSION) return VP_ERROR_ABI_MISMATCH;
  if (host == nullptr || host->abi_version != VP_PLANNER_ABI_VERSION) {
    return VP_ERROR_ABI_MISMATCH;
  }
  if (host->struct_size < sizeof(vp_host_api)) return VP_ERROR_STRUCT_SIZE;
  vp_planner_api table{};
  table.struct_size = sizeof(table);
  table.abi_version = VP_PLANNER_ABI_VERSION;
  table.name = name;
  table.version = version;
  table.create = &Create<PlannerT>;
  table.plan = &Plan;
  table.destroy = &Destroy;
  // A host with a shorter table (older minor) gets the prefix it knows.
  const uint32_t size = std::min<uint32_t>(out->struct_size, uint32_t(sizeof(table)));
  std::memcpy(out, &table, size);
  out->struct_size = size;
  return VP_OK;
}

}  // namespace vp::detail

// Defines the plugin's one exported symbol for PlannerClass (constructible from vp::Config).
#define VP_PLANNER_EXPORT(PlannerClass, name_literal, version_literal)                  \
  extern "C" VP_PLANNER_EXPORT_SYMBOL vp_status vp_planner_entry(                       \
      uint32_t host_abi_version, const vp_host_api* host, vp_planner_api* out) {        \
    return ::vp::detail::Entry<PlannerClass>(host_abi_version, host, out, name_literal, \
                                             version_literal);                          \
  }
