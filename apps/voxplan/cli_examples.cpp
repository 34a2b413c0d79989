#include "apps/voxplan/cli_examples.h"

#include <utility>

#include "plugins/host/plugin_host.h"

namespace voxplan::cli {
namespace {

constexpr const char* kData = "../shared/data";

std::string D(const std::string& rest) { return std::string(kData) + "/" + rest; }

}  // namespace

std::vector<std::pair<std::string, std::vector<std::string>>> HelpExamples() {
  const std::string kitchen = D("rgbd/7scenes_redkitchen"), icl = D("rgbd/iclnuim_office_traj0");
  const std::string house = D("scenes/aws_small_house/derived/small_house_visual.ply");
  return {
      {"fuse",
       {"voxplan fuse " + kitchen + " --frames 200 --map out/kitchen.vpmap --mesh out/kitchen.ply",
        "voxplan fuse " + icl + " --voxel-size 0.02 --trunc 0.08 --track --trajectory " +
            "out/icl_track.txt --mesh out/icl.ply",
        "mpirun -n 4 voxplan fuse " + kitchen +
            " --voxel-size 0.005 --map out/kitchen5.vpmap --checkpoint-every 50 --mesh "
            "out/kitchen5.ply"}},
      {"farm", {"mpirun -n 4 voxplan farm out/suite_tasks.txt --stats out/farm.json"}},
      {"mesh", {"voxplan mesh out/kitchen.vpmap --out out/kitchen.glb --min-weight 2"}},
      {"info", {"voxplan info " + kitchen, "voxplan info out/kitchen.vpmap"}},
      {"render",
       {"voxplan render out/kitchen.vpmap --orbit 8 --out out/orbit",
        "voxplan render out/kitchen.ply --mode normals --size 1280x960 --out out/view",
        "voxplan render out/kitchen.vpmap --dataset " + kitchen +
            " --frames 3 --stride 60 --out out/at_frames"}},
      {"eval mesh",
       {"voxplan eval mesh out/replica.ply " + D("scenes/replica_office0/office0_mesh.ply")}},
      {"eval trajectory",
       {"voxplan eval trajectory out/icl_track.txt " + icl + "/traj0.gt.freiburg"}},
      {"eval run",
       {"voxplan eval run out/explore/run_log.csv --scene out/explore/world.ply",
        "voxplan eval run out/explore/run_log.csv --floor-area 60"}},
      {"eval objects", {"voxplan eval objects out/explore/mesh.ply --scene out/explore/world.ply"}},
      {"demo", {"voxplan demo --out out/demo --frames 120"}},
      {"bench fusion", {"voxplan bench fusion " + icl + " --threads 1,2 --vs-open3d"}},
      {"bench raycast", {"voxplan bench raycast " + kitchen + " --threads 2"}},
      {"bench mesh", {"voxplan bench mesh " + kitchen + " --threads 1,2"}},
      {"bench maps", {"voxplan bench maps " + kitchen + " --frames 100"}},
      {"sim scene",
       {"voxplan sim scene --generate apartment --size M --seed 3 --out out/apt",
        "voxplan sim scene --scene " + house + " --out out/house"}},
      {"sim tour", {"voxplan sim tour --scene out/apt/world.glb --out out/apt_tour.txt"}},
      {"sim render",
       {"voxplan sim render --scene out/apt/world.glb --trajectory out/apt_tour.txt --out "
        "out/apt_ds"}},
      {"explore",
       {"voxplan explore --scene apartment:size=M,seed=1 --robots 3 --planner omt --out "
        "out/explore",
        "voxplan explore --scene apartment:size=R,seed=2 --robots 1 --planner tensorfield "
        "--profile xu2017 --out out/tf"}},
  };
}

void AddHelpExamples(CLI::App& app) {
  for (auto& [path, examples] : HelpExamples()) {
    CLI::App* sub = &app;
    std::string rest = path;
    while (sub && !rest.empty()) {
      const size_t space = rest.find(' ');
      const std::string name = rest.substr(0, space);
      rest = space == std::string::npos ? "" : rest.substr(space + 1);
      try {
        sub = sub->get_subcommand(name);
      } catch (const CLI::OptionNotFound&) {
        sub = nullptr;  // a command this build leaves out
      }
    }
    if (!sub) continue;
    std::string footer = "\nExamples:\n";
    for (const std::string& e : examples) footer += "  " + e + "\n";
    if (path == "explore") {
      // The planners found now (the search path may change between builds and installs).
      sub->footer([footer]() {
        std::string text = footer + "\nPlanners found:";
        const std::vector<std::string> names = AvailablePlanners(DefaultPlannerSearchPath());
        for (const std::string& n : names) text += " " + n;
        if (names.empty()) text += " none (set VOXPLAN_PLANNER_PATH)";
        return text +
               "\nEach takes --planner-config FILE.json; its keys are in plugins/<name>/README.md "
               "(greedy and voronoi: plugins/README.md).\n";
      });
    } else {
      sub->footer(footer);
    }
  }
}

}  // namespace voxplan::cli
