// The supervised plugin thread (planner_thread.h): a sigsetjmp at the call site, a handler that
// jumps back to it for faults on this thread during a call and chains to the previous handler
// for every other fault, and a timed wait for the call.
#include "plugins/host/planner_thread.h"

#include <setjmp.h>
#include <signal.h>

#include <chrono>
#include <condition_variable>
#include <exception>
#include <mutex>
#include <string>
#include <vector>

#include "core/stopwatch.h"

namespace voxplan::internal {
namespace {

constexpr int kSignals[] = {SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT};
// Big enough for the handler (and a sanitizer's) after a stack overflow in the plugin.
constexpr size_t kAltStackBytes = 256 * 1024;

struct sigaction g_previous[NSIG];  // the handlers before ours, by signal

// Set on a plugin thread while it is inside a call: where a fault jumps to. Plain types, so a
// signal handler may read them.
thread_local sigjmp_buf* t_jump = nullptr;
thread_local int t_signal = 0;

// What would have happened without us: the previous handler, else the default action.
void Chain(int sig, siginfo_t* info, void* context) {
  const struct sigaction& prev = g_previous[sig];
  if ((prev.sa_flags & SA_SIGINFO) != 0 && prev.sa_sigaction != nullptr) {
    prev.sa_sigaction(sig, info, context);
    return;
  }
  if ((prev.sa_flags & SA_SIGINFO) == 0 && prev.sa_handler != SIG_DFL &&
      prev.sa_handler != SIG_IGN) {
    prev.sa_handler(sig);
    return;
  }
  // Default action: restored, and the signal raised again; it is delivered when this returns
  // (a hardware fault would also recur at the faulting instruction).
  struct sigaction dfl {};
  dfl.sa_handler = SIG_DFL;
  sigemptyset(&dfl.sa_mask);
  sigaction(sig, &dfl, nullptr);
  raise(sig);
}

void OnFault(int sig, siginfo_t* info, void* context) {
  sigjmp_buf* jump = t_jump;
  if (jump == nullptr) return Chain(sig, info, context);
  t_jump = nullptr;
  t_signal = sig;
  siglongjmp(*jump, 1);
}

void InstallHandlers() {
  static std::once_flag once;
  std::call_once(once, [] {
    struct sigaction act {};
    act.sa_sigaction = OnFault;
    act.sa_flags = SA_SIGINFO | SA_ONSTACK;
    sigfillset(&act.sa_mask);
    for (int sig : kSignals) sigaction(sig, &act, &g_previous[sig]);
  });
}

// 0 when `call` returned, else the signal that ended it. The frames between here and the
// plugin hold nothing with a destructor, so jumping over them loses nothing of the host's.
int CallGuarded(const std::function<void()>& call) {
  // volatile: read again after a jump back, never from a register the jump clobbered.
  const std::function<void()>* volatile fn = &call;
  sigjmp_buf jump;
  if (sigsetjmp(jump, 1) != 0) return t_signal;
  t_jump = &jump;
  (*fn)();
  t_jump = nullptr;
  return 0;
}

}  // namespace

struct PlannerThread::Shared {
  std::mutex mutex;
  std::condition_variable cv;
  std::function<void()> call;
  bool has_call = false, finished = false, quit = false;
  int signal = 0;
};

Result<std::unique_ptr<PlannerThread>> PlannerThread::Start() {
  InstallHandlers();
  std::unique_ptr<PlannerThread> t(new PlannerThread());
  t->shared_ = std::make_shared<Shared>();
  try {
    t->thread_ = std::thread(Loop, t->shared_);
  } catch (const std::exception& e) {
    return Status(StatusCode::kInternal, std::string("cannot start a planner thread: ") + e.what());
  }
  return t;
}

void PlannerThread::Loop(std::shared_ptr<Shared> s) {
  std::vector<char> stack(kAltStackBytes);
  stack_t alt{};
  alt.ss_sp = stack.data();
  alt.ss_size = stack.size();
  const bool have_alt = sigaltstack(&alt, nullptr) == 0;
  std::unique_lock lock(s->mutex);
  for (;;) {
    s->cv.wait(lock, [&] { return s->has_call || s->quit; });
    if (s->quit) break;
    const std::function<void()> call = std::move(s->call);
    s->has_call = false;
    lock.unlock();
    const int sig = CallGuarded(call);
    lock.lock();
    s->signal = sig;
    s->finished = true;
    s->cv.notify_all();
  }
  if (have_alt) {
    stack_t off{};
    off.ss_flags = SS_DISABLE;
    sigaltstack(&off, nullptr);
  }
}

PlannerThread::~PlannerThread() {
  if (!thread_.joinable()) return;
  if (abandoned_) {
    thread_.detach();  // it keeps shared_ alive; the process ends it
    return;
  }
  {
    const std::lock_guard lock(shared_->mutex);
    shared_->quit = true;
  }
  shared_->cv.notify_all();
  thread_.join();
}

CallOutcome PlannerThread::Run(const std::function<void()>& call, double limit_s) {
  CallOutcome out;
  if (abandoned_) {
    out.kind = CallOutcome::Kind::kHung;
    return out;
  }
  const Stopwatch clock;
  std::unique_lock lock(shared_->mutex);
  shared_->call = call;
  shared_->has_call = true;
  shared_->finished = false;
  shared_->cv.notify_all();
  const bool finished = shared_->cv.wait_for(lock, std::chrono::duration<double>(limit_s),
                                             [&] { return shared_->finished; });
  out.elapsed_s = clock.ElapsedS();
  if (!finished) {
    abandoned_ = true;
    shared_->quit = true;  // should it ever return, it leaves
    out.kind = CallOutcome::Kind::kHung;
  } else if (shared_->signal != 0) {
    out.kind = CallOutcome::Kind::kCrashed;
    out.signal = shared_->signal;
  }
  return out;
}

std::string SignalName(int signal) {
  switch (signal) {
    case SIGSEGV:
      return "SIGSEGV";
    case SIGBUS:
      return "SIGBUS";
    case SIGFPE:
      return "SIGFPE";
    case SIGILL:
      return "SIGILL";
    case SIGABRT:
      return "SIGABRT";
    default:
      return "signal " + std::to_string(signal);
  }
}

}  // namespace voxplan::internal
