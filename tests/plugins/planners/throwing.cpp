// Throws from create or plan, as the config says: the boundary must turn every exception into
// a status code and a message. "create": std::runtime_error in the constructor; "int": a
// non-std exception from Plan; "bad_robot": a query with an invalid robot index (host status);
// otherwise std::runtime_error from Plan.
#include <stdexcept>
#include <string>

#include "plugins/planner_cpp.h"

namespace {

class Throwing : public vp::Planner {
 public:
  explicit Throwing(const vp::Config& config) : json_(config.json) {
    if (json_.find("create") != std::string::npos) {
      throw std::runtime_error("refusing to be created");
    }
  }
  void Plan(const vp::WorldView& world, vp::PlanOutput& out) override {
    out.Diagnostic("reached", 1.0);
    if (json_.find("int") != std::string::npos) throw 42;
    if (json_.find("bad_robot") != std::string::npos) world.Robot(world.RobotCount() + 5);
    throw std::runtime_error("boom in plan");
  }

 private:
  std::string json_;
};

}  // namespace

VP_PLANNER_EXPORT(Throwing, "throwing", "0.0.1")
