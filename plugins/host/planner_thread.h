#pragma once
// The thread every call into one plugin runs on (plugins/host/README.md, "Supervision"), so a
// crash or a hang in the plugin cannot take the host down:
//   - synchronous faults on this thread during a call (SIGSEGV, SIGBUS, SIGFPE, SIGILL, and
//     SIGABRT) are caught by a process-wide handler on this thread's alternate signal stack,
//     which siglongjmps back to the call site here. The same signals on any other thread, or on
//     this one outside a call, go to the handler that was installed before (or the default
//     action), as if this file did not exist;
//   - the host waits for a call at most its hard limit; past it the thread is abandoned: never
//     joined, never called again, the memory it can reach kept alive.
// After a fault the caller must treat the plugin as dead: its state may be anything, so it is
// never called again, never destroyed and its library never unloaded.
#include <functional>
#include <memory>
#include <string>
#include <thread>

#include "core/status.h"

namespace voxplan::internal {

struct CallOutcome {
  enum class Kind { kReturned, kCrashed, kHung };
  Kind kind = Kind::kReturned;
  int signal = 0;          // kCrashed: the signal number
  double elapsed_s = 0.0;  // wall time until it returned, crashed or was given up
};

class PlannerThread {
 public:
  // Installs the fault handlers (once per process) and starts the thread.
  static Result<std::unique_ptr<PlannerThread>> Start();
  PlannerThread(const PlannerThread&) = delete;
  PlannerThread& operator=(const PlannerThread&) = delete;
  // Joins the thread, or leaves it running after a hang.
  ~PlannerThread();

  // Runs `call` on the thread and waits at most limit_s for it. `call` must own nothing that
  // needs a destructor across the plugin call: a fault leaves its frames without unwinding.
  // After a kHung outcome every further Run answers kHung at once.
  CallOutcome Run(const std::function<void()>& call, double limit_s);

  bool abandoned() const { return abandoned_; }

 private:
  struct Shared;
  std::shared_ptr<Shared> shared_;  // with the thread, which keeps it alive after a hang
  std::thread thread_;
  bool abandoned_ = false;
  PlannerThread() = default;
  static void Loop(std::shared_ptr<Shared> s);
};

// "SIGSEGV", "SIGBUS", ... or "signal N".
std::string SignalName(int signal);

}  // namespace voxplan::internal
