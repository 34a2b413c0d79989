// A valid planner for the host tests: sends each robot to one of its `candidates` nearest
// reachable frontier cells, picked with the seed (so the seed matters and fixes the plan).
// Options (JSON text, read naively): "candidates": n, "sleep_ms": n, "fail": refuse to start.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "plugins/planner_cpp.h"

namespace {

int IntOption(const std::string& json, const std::string& key, int fallback) {
  const size_t at = json.find("\"" + key + "\"");
  if (at == std::string::npos) return fallback;
  const size_t colon = json.find(':', at);
  return colon == std::string::npos ? fallback : std::atoi(json.c_str() + colon + 1);
}

class NearestFrontier : public vp::Planner {
 public:
  explicit NearestFrontier(const vp::Config& config)
      : seed_(config.seed),
        candidates_(std::max(1, IntOption(config.json, "candidates", 1))),
        sleep_ms_(IntOption(config.json, "sleep_ms", 0)) {
    if (config.json.find("\"fail\"") != std::string::npos) {
      throw vp::Error(VP_ERROR_INVALID_ARGUMENT, "option fail is set");
    }
  }

  void Plan(const vp::WorldView& world, vp::PlanOutput& out) override {
    vp::StageTimer timer(world, out, "plan");
    if (sleep_ms_ > 0) std::this_thread::sleep_for(std::chrono::milliseconds(sleep_ms_));
    std::mt19937_64 rng(seed_ * 0x9E3779B97F4A7C15ull + world.seed());
    const vp::FloorView floor = world.Floor();
    std::vector<size_t> frontier;
    for (size_t i = 0; i < floor.size(); ++i) {
      if (floor.cells()[i] == VP_FLOOR_FRONTIER) frontier.push_back(i);
    }
    out.Diagnostic("frontier_cells", double(frontier.size()));
    if (frontier.empty()) {
      out.SetDone(true);
      return;
    }
    for (uint32_t r = 0; r < world.RobotCount(); ++r) {
      const vp_robot robot = world.Robot(r);
      const std::span<const float> field =
          world.GeodesicField(robot.x_m, robot.y_m, robot.radius_m);
      std::vector<std::pair<float, size_t>> reachable;
      for (size_t i : frontier) {
        if (std::isfinite(field[i]) && floor.clearance_m()[i] >= robot.radius_m) {
          reachable.push_back({field[i], i});
        }
      }
      if (reachable.empty()) continue;
      std::sort(reachable.begin(), reachable.end());
      const size_t k = std::min(reachable.size(), size_t(candidates_));
      const size_t cell = reachable[size_t(rng() % k)].second;
      const auto [x, y] =
          floor.CellCenter(int(cell % size_t(floor.width())), int(cell / size_t(floor.width())));
      vp_task task{x,
                   y,
                   std::atan2(y - robot.y_m, x - robot.x_m),
                   0.f,
                   0.f,
                   0.5f,
                   VP_MODE_EXPLORER,
                   uint32_t(cell)};
      out.ReplaceTasks(r);
      out.AddTask(r, task);
      if (auto path = world.ShortestPath(robot.x_m, robot.y_m, x, y, robot.radius_m)) {
        std::vector<vp_path_point> points;
        std::vector<float> xyz;
        for (size_t i = 0; i < path->size(); i += 2) {
          points.push_back({(*path)[i], (*path)[i + 1], 0.f});
          xyz.insert(xyz.end(), {(*path)[i], (*path)[i + 1], 0.f});
        }
        out.SetPath(r, points);
        out.DebugPolyline("paths", xyz, 0x00ff00ffu);
      }
      out.DebugLabel("targets", x, y, 0.f, "robot " + std::to_string(r), 0xffffffffu);
    }
  }

 private:
  uint64_t seed_;
  int candidates_;
  int sleep_ms_;
};

}  // namespace

VP_PLANNER_EXPORT(NearestFrontier, "minimal", "1.0.0")
