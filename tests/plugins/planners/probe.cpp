// Reads every query of the host table once and reports what it saw as diagnostics, so the test
// can compare the C view with the PlannerWorld behind it.
#include <algorithm>
#include <cmath>
#include <string>

#include "plugins/planner_cpp.h"

namespace {

class Probe : public vp::Planner {
 public:
  explicit Probe(const vp::Config& config) : seed_(config.seed) {}

  void Plan(const vp::WorldView& world, vp::PlanOutput& out) override {
    const vp_call_info& call = world.call();
    out.Diagnostic("create_seed", double(seed_));
    out.Diagnostic("event", call.event);
    out.Diagnostic("event_robot", call.event_robot);
    out.Diagnostic("call_index", call.call_index);
    out.Diagnostic("call_seed", double(call.seed));
    out.Diagnostic("budget_s", call.time_budget_s);
    out.Diagnostic("failed_tag", call.failed_task.tag);
    const vp_map_info map = world.MapInfo();
    out.Diagnostic("revision", double(map.revision));
    out.Diagnostic("voxel_size_m", map.voxel_size_m);
    out.Diagnostic("bounds_max_x", map.bounds_max[0]);
    // A wall cell (0, 0), a free cell and an unknown cell of the fake world's floor.
    const float points[9] = {0.1f, 0.1f, 0.5f, 1.f, 0.6f, 0.5f, 3.6f, 0.6f, 0.5f};
    const std::vector<uint8_t> states = world.VoxelStates(points);
    for (size_t i = 0; i < states.size(); ++i) {
      out.Diagnostic("state_" + std::to_string(i), states[i]);
    }
    // From a free cell towards -x: the border wall's cell starts at x = 0.25.
    const vp_ray ray = {{1.1f, 0.6f, 0.5f}, {-1.f, 0.f, 0.f}, 4.f};
    const std::vector<vp_ray_hit> hits = world.Raycast({&ray, 1});
    out.Diagnostic("ray_distance", hits[0].distance_m);
    out.Diagnostic("ray_result", hits[0].result);
    out.Diagnostic("frontier_voxels", double(world.FrontierVoxels().size() / 3));
    const auto surface = world.SurfaceVoxels();
    out.Diagnostic("surface_voxels", double(surface.size()));
    out.Diagnostic("surface_normal_norm",
                   surface.empty() ? 0.0
                                   : std::hypot(surface[0].normal[0], surface[0].normal[1],
                                                surface[0].normal[2]));
    const vp::FloorView floor = world.Floor();
    out.Diagnostic("floor_width", floor.width());
    out.Diagnostic("floor_cell_0", floor.Cell(0, 0));
    const auto instances = world.Instances();
    out.Diagnostic("instances", double(instances.size()));
    if (!instances.empty()) {
      out.Diagnostic("instance_label_is_chair", std::string(instances[0].label) == "chair");
    }
    out.Diagnostic("robots", world.RobotCount());
    const vp_robot r1 = world.Robot(1);
    out.Diagnostic("robot1_id", r1.id);
    out.Diagnostic("robot1_status", r1.status);
    out.Diagnostic("robot1_modes", r1.mode_count);
    out.Diagnostic("robot1_queue_tag", world.Queue(1).empty() ? -1.0 : world.Queue(1)[0].tag);
    out.Diagnostic("reconstructor_speed", world.Mode(1, VP_MODE_RECONSTRUCTOR).max_speed_mps);
    // 1.1's appended fields.
    out.Diagnostic("robot1_distance_m", r1.distance_m);
    out.Diagnostic("robot1_busy_s", r1.busy_s);
    out.Diagnostic("robot1_idle_s", r1.idle_s);
    const vp_mode_params arm = world.Mode(1, VP_MODE_RECONSTRUCTOR);
    out.Diagnostic("reconstructor_mount", arm.mount);
    out.Diagnostic("reconstructor_height_max_m", arm.camera_height_max_m);
    out.Diagnostic("reconstructor_reach_max_m", arm.reach_max_m);
    out.Diagnostic("reconstructor_capture_hz", arm.capture_hz);
    out.Diagnostic("reconstructor_switch_s", arm.switch_s);
    // Extensions: vp.objects 1 is there, a later version and an unknown name are not.
    out.Diagnostic("ext_objects_1", world.Extension<vp_objects_ext>(VP_EXT_OBJECTS, 1) != nullptr);
    out.Diagnostic("ext_objects_2", world.Extension<vp_objects_ext>(VP_EXT_OBJECTS, 2) != nullptr);
    out.Diagnostic("ext_unknown", world.host()->get_extension("vp.unknown", 1) != nullptr);
    out.Diagnostic("ext_null_name", world.host()->get_extension(nullptr, 1) != nullptr);
    const auto chair = world.InstanceSurface(3);
    out.Diagnostic("chair_voxels", double(chair.size()));
    out.Diagnostic("chair_voxels_all_its_own",
                   std::all_of(chair.begin(), chair.end(),
                               [](const vp_surface_voxel& v) { return v.instance == 3; }));
    out.Diagnostic("chair_first_x", chair.empty() ? -1.0 : chair[0].position[0]);
    out.Diagnostic("absent_voxels", double(world.InstanceSurface(4000000000u).size()));
    const float xy[4] = {r1.x_m, r1.y_m, world.Robot(0).x_m, world.Robot(0).y_m};
    const auto d = world.DistanceMatrix(xy, r1.radius_m);
    out.Diagnostic("d01", d[1]);
    out.Diagnostic("d10", d[2]);
    out.Diagnostic("d00", d[0]);
    world.Log(VP_LOG_INFO, "probe done");
  }

 private:
  uint64_t seed_;
};

}  // namespace

VP_PLANNER_EXPORT(Probe, "probe", "0.0.1")
