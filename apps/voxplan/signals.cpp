#include "apps/voxplan/signals.h"

#include <unistd.h>

#include <atomic>
#include <csignal>
#include <iostream>

#include "apps/voxplan/cli_common.h"
#include "io/temp_files.h"

namespace voxplan::cli {

namespace {

std::atomic<int> g_signal{0};   // the first signal received, 0 before
std::atomic<int> g_polling{0};  // StopPolling scopes alive
// A forked child (a supervised planner) inherits the handler and the table of temporary files,
// which are its parent's: it exits without touching them.
pid_t g_main_pid = 0;

void Say(const char* text) {
  size_t n = 0;
  while (text[n] != '\0') ++n;
  [[maybe_unused]] const ssize_t ignored = ::write(STDERR_FILENO, text, n);
}

// Async-signal-safe throughout: atomics, write, unlink, rmdir, _exit.
void OnSignal(int sig) {
  if (::getpid() != g_main_pid) ::_exit(128 + sig);
  int expected = 0;
  const bool first = g_signal.compare_exchange_strong(expected, sig);
  if (first && g_polling.load() > 0) {
    Say("\nvoxplan: stopping after the current frame (signal again to stop at once)\n");
    return;
  }
  RemoveTempFiles();
  Say(sig == SIGINT
          ? "\nerror: interrupted by SIGINT: stopped at once, temporary files removed\n"
          : "\nerror: interrupted by SIGTERM: stopped at once, temporary files removed\n");
  ::_exit(128 + sig);
}

}  // namespace

void InstallSignalHandlers() {
  g_main_pid = ::getpid();
  struct sigaction action {};
  action.sa_handler = OnSignal;
  sigemptyset(&action.sa_mask);
  // Restarted system calls: a signal must not turn a read into an I/O error.
  action.sa_flags = SA_RESTART;
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

StopPolling::StopPolling() { ++g_polling; }
StopPolling::~StopPolling() { --g_polling; }

bool StopRequested() { return g_signal.load() != 0; }

std::function<bool()> StopRequestedFn() {
  return [] { return StopRequested(); };
}

int Interrupted(const std::string& what) {
  const int sig = g_signal.load();
  std::cerr << "error: interrupted by " << (sig == SIGTERM ? "SIGTERM" : "SIGINT") << ": " << what
            << std::endl;
  return sig == SIGTERM ? kExitSigterm : kExitSigint;
}

int CommitOutputs(OutputTransaction& outputs) {
  if (StopRequested()) {
    outputs.Rollback();
    return Interrupted("nothing written");
  }
  // The renames are quick and finish even when a first signal comes now: the run is done.
  const StopPolling renaming;
  if (Status s = outputs.Commit(); !s.ok()) return Fail(s.message());
  return kExitOk;
}

}  // namespace voxplan::cli
