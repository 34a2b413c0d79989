#pragma once
// SIGINT and SIGTERM for the voxplan command (libraries never install handlers or exit).
// The first signal asks the command to stop: a command that polls (StopPolling in scope: fuse
// between frames, render between views) finishes the current frame, writes nothing and exits
// 130 (SIGINT) or 143 (SIGTERM). A second signal, or the first while no command polls, removes
// the temporary files in flight (io/temp_files.h) and exits at once with the same codes.
#include <functional>
#include <string>

#include "io/output_transaction.h"

namespace voxplan::cli {

inline constexpr int kExitSigint = 130;   // 128 + SIGINT
inline constexpr int kExitSigterm = 143;  // 128 + SIGTERM

void InstallSignalHandlers();

// While one lives, the first signal only sets the stop request.
class StopPolling {
 public:
  StopPolling();
  ~StopPolling();
  StopPolling(const StopPolling&) = delete;
  StopPolling& operator=(const StopPolling&) = delete;
};

bool StopRequested();
// For a library's observer: true once a signal asked to stop.
std::function<bool()> StopRequestedFn();
// Prints `error: interrupted by SIG...: <what>` and returns 130 or 143.
int Interrupted(const std::string& what);
// The last step of a command that writes: rolls `outputs` back when a signal asked to stop
// (returns 130 / 143), else commits them. kExitOk, or the exit code after printing why.
int CommitOutputs(OutputTransaction& outputs);

}  // namespace voxplan::cli
