// Misbehaves on purpose, for the host's supervision tests: in plan call `"call"` (by call index,
// 0 by default) or in create (`"in": "create"`), `"fault"`:
//   "null"   writes through a null pointer (SIGSEGV)
//   "abort"  calls std::abort (SIGABRT)
//   "fpe"    divides an integer by zero (SIGFPE)
//   "stack"  recurses until the stack overflows (SIGSEGV on a full stack)
//   "loop"   spins forever
//   "query"  asks the host for the map info forever, ignoring its errors
// Other plan calls return an empty plan. Options are read naively, like minimal.cpp's.
#include <cstdint>
#include <cstdlib>
#include <string>

#include "plugins/planner_cpp.h"

namespace {

std::string StringOption(const std::string& json, const std::string& key) {
  const size_t at = json.find("\"" + key + "\"");
  if (at == std::string::npos) return "";
  const size_t open = json.find('"', json.find(':', at));
  const size_t close = open == std::string::npos ? open : json.find('"', open + 1);
  return close == std::string::npos ? "" : json.substr(open + 1, close - open - 1);
}

int IntOption(const std::string& json, const std::string& key, int fallback) {
  const size_t at = json.find("\"" + key + "\"");
  if (at == std::string::npos) return fallback;
  return std::atoi(json.c_str() + json.find(':', at) + 1);
}

int* volatile g_null = nullptr;  // volatile: the compiler cannot see the store is to NULL
volatile int g_zero = 0;
volatile uint64_t g_spins = 0;

int Recurse(int depth) {
  volatile char pad[1024];
  pad[0] = char(depth);
  if (g_zero != 0) return 0;  // never: the compiler cannot tell
  return depth + Recurse(depth + 1) + pad[0];
}

void Misbehave(const std::string& fault, const vp::WorldView* world) {
  if (fault == "null") *g_null = 1;
  if (fault == "abort") std::abort();
  if (fault == "fpe") g_spins = uint64_t(int(g_spins + 7) / g_zero);  // not 1 / x: GCC folds that
  if (fault == "stack") g_spins = uint64_t(Recurse(0));
  if (fault == "loop")
    for (;;) g_spins = g_spins + 1;
  if (fault == "query" && world != nullptr) {
    for (;;) {
      try {
        g_spins = g_spins + world->MapInfo().revision;
      } catch (const vp::Error&) {
        g_spins = g_spins + 1;  // revoked: the host gave this call up
      }
    }
  }
}

class Faulty : public vp::Planner {
 public:
  explicit Faulty(const vp::Config& config)
      : fault_(StringOption(config.json, "fault")), call_(IntOption(config.json, "call", 0)) {
    if (StringOption(config.json, "in") == "create") Misbehave(fault_, nullptr);
  }

  void Plan(const vp::WorldView& world, vp::PlanOutput&) override {
    if (int(world.call().call_index) == call_) Misbehave(fault_, &world);
  }

 private:
  std::string fault_;
  int call_;
};

}  // namespace

VP_PLANNER_EXPORT(Faulty, "faulty", "0.0.1")
