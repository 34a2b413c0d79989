// The task-flow planner (Guo et al. 2022) as a plugin: whenever a robot runs dry it generates
// exploration tasks (frontier views, G§4.1) and reconstruction tasks (views of objects the
// geometric completion finds incomplete, G§4.2), assigns both with the mode-aware MDMTSP (G§5)
// and appends the new sequences to every robot's queue (the task flow, G§3). The ablations and
// the NBO baseline are options; config keys: plugins/taskflow/README.md.
#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "plugins/common/world_input.h"
#include "plugins/planner_cpp.h"
#include "plugins/taskflow/algorithms/assignment.h"
#include "plugins/taskflow/algorithms/flow.h"
#include "plugins/taskflow/tasks.h"

namespace voxplan::taskflow {
namespace {

constexpr uint32_t kExploreColor = 0x4e79a7ffu, kReconColor = 0xe15759ffu;
constexpr float kPi = 3.14159265358979f;

float WrapAngle(float a) {
  a = std::remainder(a, 2.f * kPi);
  return a <= -kPi ? a + 2.f * kPi : a;
}

struct Options {
  TaskOptions tasks;
  AssignmentParams assignment;
  FlowPolicy flow = FlowPolicy::kAsync;
  bool nbo = false;          // "policy": "nbo": next best object, one task per idle robot
  bool nbo_regions = false;  // NBO x R: each robot confined to its strip of the map
};

Options ReadOptions(const std::string& json_text) {
  planners::JsonOptions json("taskflow", json_text);
  Options o;
  o.flow = json.Choice("flow", "async", {"async", "sync"}) == "sync" ? FlowPolicy::kSync
                                                                     : FlowPolicy::kAsync;
  const std::string modes = json.Choice("modes", "switch", {"switch", "fixed"});
  const std::string force =
      json.Choice("force_mode", "none", {"none", "explorer", "reconstructor"});
  AssignmentParams& a = o.assignment;
  a.fixed_explorers = json.Integer("fixed_explorers", a.fixed_explorers, 0, 64);
  a.mode_policy = force == "explorer"        ? ModePolicy::kForceExplorer
                  : force == "reconstructor" ? ModePolicy::kForceReconstructor
                  : modes == "fixed"         ? ModePolicy::kFixed
                                             : ModePolicy::kSwitch;
  a.lambda_c = json.Number("lambda_c", a.lambda_c, 0.0, 1e6);
  a.sa_max_iterations = json.Integer("sa_iterations", a.sa_max_iterations, 0, 100000);
  a.energy_cut = json.Flag("energy_cut", a.energy_cut);
  a.max_hop_m = json.Number("max_hop_m", a.max_hop_m, 0.1, 1e4);
  TaskOptions& t = o.tasks;
  t.completion_on = json.Choice("completion", "geometric", {"geometric", "none"}) == "geometric";
  t.explore.paper_sign = json.Choice("score_sign", "ours", {"ours", "paper"}) == "paper";
  t.explore.views_per_robot = json.Integer("views_per_robot", t.explore.views_per_robot, 1, 64);
  t.completion.tau = float(json.Number("tau", t.completion.tau, 0.0, 1.0));
  t.max_objects_per_round = json.Integer("max_objects_per_round", t.max_objects_per_round, 0, 1000);
  t.clearance_margin_m = json.Number("clearance_margin_m", t.clearance_margin_m, 0.0, 1.0);
  t.recon_dwell_s = float(json.Number("recon_dwell_s", t.recon_dwell_s, 0.0, 60.0));
  t.view_dwell_s = float(json.Number("view_dwell_s", t.view_dwell_s, 0.0, 60.0));
  o.nbo = json.Choice("policy", "taskflow", {"taskflow", "nbo"}) == "nbo";
  o.nbo_regions = json.Flag("nbo_regions", o.nbo_regions);
  json.RejectUnknownKeys();
  return o;
}

// What the robots hold: where each queue ends, in which mode, and the objects queued for.
struct Team {
  std::vector<vp_robot> robots;
  std::vector<vp_mode_params> explorer, reconstructor;
  std::vector<AssignRobot> ends;
  std::set<int> queued_objects;
  float radius_m = 0.f;
};

Team ReadTeam(const vp::WorldView& world) {
  Team team;
  for (uint32_t r = 0; r < world.RobotCount(); ++r) {
    const vp_robot robot = world.Robot(r);
    team.robots.push_back(robot);
    team.explorer.push_back(world.Mode(r, VP_MODE_EXPLORER));
    team.reconstructor.push_back(world.Mode(r, VP_MODE_RECONSTRUCTOR));
    team.radius_m = std::max(team.radius_m, robot.radius_m);
    const std::span<const vp_task> queue = world.Queue(r);
    AssignRobot end;
    end.rest_count = int(queue.size());
    if (queue.empty()) {
      end.end_xy_m = {robot.x_m, robot.y_m};
      end.mode = robot.mode == VP_MODE_RECONSTRUCTOR ? Mode::kReconstructor : Mode::kExplorer;
    } else {
      end.end_xy_m = {queue.back().x_m, queue.back().y_m};
      end.mode =
          queue.back().mode == VP_MODE_RECONSTRUCTOR ? Mode::kReconstructor : Mode::kExplorer;
    }
    team.ends.push_back(end);
    for (const vp_task_ext& e : world.QueueExt(r))
      if (e.object_id >= 0) team.queued_objects.insert(e.object_id);
  }
  return team;
}

class TaskflowPlanner : public vp::Planner {
 public:
  explicit TaskflowPlanner(const vp::Config& config)
      : options_(ReadOptions(config.json)), generator_(options_.tasks) {}

  void Plan(const vp::WorldView& world, vp::PlanOutput& out) override {
    vp::StageTimer total(world, out, "plan");
    const Team team = ReadTeam(world);
    if (team.robots.empty()) return;
    std::vector<FlowRobot> flow;
    for (const vp_robot& r : team.robots)
      flow.push_back({r.status == VP_ROBOT_EXECUTING, int(r.queued_tasks)});
    const FlowDecision decision = DecideFlow(FlowEvent(world.event()), flow, options_.flow);
    if (!decision.plan) return;

    GenerationStats stats;
    const std::vector<Candidate> candidates =
        generator_.Generate(world, team.radius_m, team.queued_objects, world.seed(), &stats);
    Report(stats, out);
    if (candidates.empty()) {
      // Nothing left worth a task: done once nobody is still working on something.
      bool all_idle = true;
      for (const FlowRobot& r : flow) all_idle = all_idle && r.Idle();
      if (all_idle) out.SetDone(true);
      return;
    }
    std::vector<std::vector<int>> sequences(team.robots.size());
    std::vector<Mode> modes(team.robots.size(), Mode::kExplorer);
    if (options_.nbo) {
      Nbo(world, team, candidates, decision, &sequences, &modes);
    } else {
      Assign(world, team, candidates, out, &sequences, &modes);
    }
    Emit(team, candidates, sequences, modes, out);
  }

 private:
  void Report(const GenerationStats& s, vp::PlanOutput& out) const {
    out.Diagnostic("gen_exp_ms", s.explore_ms);
    out.Diagnostic("completion_ms", s.completion_ms);
    out.Diagnostic("gen_rec_ms", s.recon_ms);
    out.Diagnostic("frontier_samples", s.frontier_samples);
    out.Diagnostic("settled_frontiers", s.settled_frontiers);
    out.Diagnostic("exploration_views", s.exploration_views);
    out.Diagnostic("objects", s.objects);
    out.Diagnostic("objects_completed", s.objects_completed);
    out.Diagnostic("objects_incomplete", s.objects_incomplete);
    out.Diagnostic("reconstruction_views", s.reconstruction_views);
    // The completion's predicted incompleteness per object, for its calibration against the
    // ground truth (scripts/taskflow-suite); the plugin itself never sees that.
    for (const auto& [id, value] : s.incompleteness)
      out.Diagnostic("obj_" + std::to_string(id) + "_incompleteness", value);
  }

  // G§5: the mode-aware MDMTSP over every robot's queue end.
  void Assign(const vp::WorldView& world, const Team& team,
              const std::vector<Candidate>& candidates, vp::PlanOutput& out,
              std::vector<std::vector<int>>* sequences, std::vector<Mode>* modes) {
    const double t0 = world.ElapsedS();
    AssignmentInput in;
    in.robots = team.ends;
    // The host's distance matrix holds at most 4096 points: the best candidates first.
    const size_t room = 4096 - std::min<size_t>(4096, in.robots.size());
    const size_t used = std::min(candidates.size(), room);
    std::vector<float> xy;
    for (const AssignRobot& r : in.robots)
      xy.insert(xy.end(), {float(r.end_xy_m.x()), float(r.end_xy_m.y())});
    for (size_t k = 0; k < used; ++k) {
      const Candidate& c = candidates[k];
      in.tasks.push_back(
          {c.xy_m, c.reconstruction ? TaskType::kReconstruction : TaskType::kExploration});
      xy.insert(xy.end(), {float(c.xy_m.x()), float(c.xy_m.y())});
    }
    const size_t n = xy.size() / 2;
    const std::span<const float> m =
        world.DistanceMatrix(xy, team.radius_m + float(options_.tasks.clearance_margin_m));
    in.distance = omt::DistanceMatrix(int(n), int(n));
    for (size_t i = 0; i < n * n; ++i) in.distance.values[i] = double(m[i]);
    in.explorer_speed_mps = team.explorer[0].max_speed_mps;
    in.reconstructor_speed_mps = team.reconstructor[0].max_speed_mps;
    AssignmentParams params = options_.assignment;
    params.seed = world.seed();
    // No wall-clock deadline on the annealing: its iteration cap keeps it short (a few ms at 4
    // robots), and a deadline would make the plan depend on the machine's speed.
    const AssignmentResult result = AssignTasks(in, params);
    if (!result.status.ok())
      throw vp::Error(VP_ERROR_PLUGIN, "taskflow: assignment: " + result.status.message);
    int explorers = 0;
    for (size_t r = 0; r < result.robots.size(); ++r) {
      (*sequences)[r] = result.robots[r].tasks;
      (*modes)[r] = result.robots[r].mode;
      explorers += result.robots[r].mode == Mode::kExplorer;
    }
    out.Diagnostic("assign_ms", (world.ElapsedS() - t0) * 1e3);
    out.Diagnostic("sa_iterations", result.sa_iterations);
    out.Diagnostic("E_d", result.energy_d);
    out.Diagnostic("E_c", result.energy_c);
    out.Diagnostic("explorers", explorers);
    out.Diagnostic("reconstructors", double(result.robots.size()) - explorers);
    out.Diagnostic("dropped_tasks", double(result.dropped.size()));
  }

  // The NBO baseline (after Liu 2018): each robot the flow hands work takes the reconstruction
  // view with the most coverage per metre, else the nearest frontier view; with regions, only
  // within its strip of the map (x split in R equal parts).
  void Nbo(const vp::WorldView& world, const Team& team, const std::vector<Candidate>& candidates,
           const FlowDecision& decision, std::vector<std::vector<int>>* sequences,
           std::vector<Mode>* modes) {
    const vp_map_info map = world.MapInfo();
    const size_t robots = team.robots.size();
    std::set<size_t> taken;
    for (int r : decision.receivers) {
      if (team.robots[size_t(r)].queued_tasks > 0) continue;  // one task at a time
      const vp_robot& robot = team.robots[size_t(r)];
      const std::span<const float> field = world.GeodesicField(
          robot.x_m, robot.y_m, team.radius_m + float(options_.tasks.clearance_margin_m));
      const vp::FloorView floor = world.Floor();
      const float strip = (map.bounds_max[0] - map.bounds_min[0]) / float(robots);
      double best = -1.0;
      size_t pick = candidates.size();
      for (size_t k = 0; k < candidates.size(); ++k) {
        if (taken.count(k)) continue;
        const Candidate& c = candidates[k];
        if (options_.nbo_regions) {
          const int region =
              std::clamp(int((float(c.xy_m.x()) - map.bounds_min[0]) / strip), 0, int(robots) - 1);
          if (region != r) continue;
        }
        const auto [ix, iy] = floor.CellOf(float(c.xy_m.x()), float(c.xy_m.y()));
        if (!floor.Contains(ix, iy)) continue;
        const float d = field[floor.Linear(ix, iy)];
        if (!std::isfinite(d)) continue;
        // Objects first (their gain per metre), then frontiers by nearness.
        const double value =
            c.reconstruction ? 1e6 + c.recon.coverage / (1.0 + d) : 1.0 / (1.0 + d);
        if (value > best) best = value, pick = k;
      }
      if (pick == candidates.size()) continue;
      taken.insert(pick);
      (*sequences)[size_t(r)] = {int(pick)};
      (*modes)[size_t(r)] =
          candidates[pick].reconstruction ? Mode::kReconstructor : Mode::kExplorer;
    }
  }

  void Emit(const Team& team, const std::vector<Candidate>& candidates,
            const std::vector<std::vector<int>>& sequences, const std::vector<Mode>& modes,
            vp::PlanOutput& out) {
    std::vector<Candidate> sent;
    std::map<int, std::vector<ReconView>> views_sent;
    std::vector<float> explore_xyz, recon_xyz;
    for (size_t r = 0; r < sequences.size(); ++r) {
      if (sequences[r].empty()) continue;
      const int32_t mode =
          modes[r] == Mode::kReconstructor ? VP_MODE_RECONSTRUCTOR : VP_MODE_EXPLORER;
      const vp_mode_params& m =
          mode == VP_MODE_RECONSTRUCTOR ? team.reconstructor[r] : team.explorer[r];
      out.AppendTasks(uint32_t(r));
      for (int k : sequences[r]) {
        const Candidate& c = candidates[size_t(k)];
        vp_task task{float(c.xy_m.x()),
                     float(c.xy_m.y()),
                     c.theta_rad,
                     0.f,
                     0.f,
                     options_.tasks.view_dwell_s,
                     mode,
                     uint32_t(k)};
        vp_task_ext ext = vp::DefaultTaskExt();
        if (c.reconstruction) {
          const ReconView& v = c.recon;
          task.camera_yaw_rad = WrapAngle(v.yaw_rad - v.base_yaw_rad);
          task.camera_pitch_rad = std::clamp(v.pitch_rad, m.min_pitch_rad, m.max_pitch_rad);
          task.dwell_s = options_.tasks.recon_dwell_s;
          if (m.mount == VP_MOUNT_ARM) {
            ext.camera_height_m = v.camera_height_m;
            ext.camera_offset_m[0] = v.camera_forward_m;
            ext.camera_offset_m[1] = v.camera_left_m;
          }
          ext.look_at = 1;
          for (int i = 0; i < 3; ++i) ext.look_at_W[i] = v.target_m[i];
          ext.object_id = v.object_id;
          views_sent[v.object_id].push_back(v);
          recon_xyz.insert(recon_xyz.end(), {v.camera_m.x(), v.camera_m.y(), v.camera_m.z()});
        } else {
          // The head's tilt up and down at the view (G L97), inside the mode's pitch range.
          const float half = options_.tasks.sweep_half_rad;
          ext.sweep_pitch_min_rad = std::max(-half, m.min_pitch_rad);
          ext.sweep_pitch_max_rad = std::min(half, m.max_pitch_rad);
          ext.sweep_pitch_step_rad = options_.tasks.sweep_step_rad;
          explore_xyz.insert(explore_xyz.end(),
                             {task.x_m, task.y_m, team.robots[r].camera_height_m});
        }
        out.AddTask(uint32_t(r), task, ext);
        sent.push_back(c);
      }
    }
    generator_.Sent(sent);
    for (const auto& [id, views] : views_sent) generator_.SentViews(id, views);
    out.DebugPoints("taskflow_exploration", explore_xyz, kExploreColor);
    out.DebugPoints("taskflow_reconstruction", recon_xyz, kReconColor);
    out.Diagnostic("tasks_sent", double(sent.size()));
  }

  Options options_;
  TaskGenerator generator_;
};

}  // namespace
}  // namespace voxplan::taskflow

VP_PLANNER_EXPORT(voxplan::taskflow::TaskflowPlanner, "taskflow", "1.0.0")
