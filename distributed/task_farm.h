#pragma once
// A task farm over ranks: the planner suites' runs (one shell command each) dealt out one at a
// time to whichever rank is free, so long and short runs balance. Rank 0 deals and runs tasks
// too; every task runs as `/bin/sh -c COMMAND` in the current folder, with MPI's variables taken
// out of its environment (a voxplan it starts is a serial process, not a rank). Each task writes
// its own outputs, so the results are the same as running the commands one after the other.
#include <functional>
#include <string>
#include <vector>

#include "core/status.h"
#include "distributed/communicator.h"

namespace voxplan {

struct FarmTask {
  std::string command;  // one shell command line
};

struct FarmResult {
  size_t tasks = 0, failed = 0;
  std::vector<int> exit_codes;  // per task (128 + signal when killed by one)
  std::vector<int> ran_on;      // per task, the rank that ran it
  std::vector<double> task_s;   // per task, its wall time
  double wall_s = 0.0;
};

struct FarmObserver {
  // Rank 0: after each finished task (index, exit code, rank, done so far).
  std::function<void(size_t task, int exit_code, int rank, size_t done)> finished;
  std::function<bool()> stop_requested;  // rank 0: deal no more tasks (those running finish)
};

// Reads a task file: one command per line; blank lines and lines starting with '#' skipped.
// At most kMaxFarmTasks tasks of at most 64 KiB each; errors name the file and line.
inline constexpr size_t kMaxFarmTasks = 1000000;
Result<std::vector<FarmTask>> ReadFarmTasks(const std::string& path);

// Collective. `tasks` is read on rank 0 (ignored elsewhere). Returns on rank 0 the result of
// every task; elsewhere an empty result. A task that fails is counted, not fatal; stopping
// leaves the tasks not dealt with exit code -1.
Result<FarmResult> RunTaskFarm(Communicator& comm, const std::vector<FarmTask>& tasks,
                               const FarmObserver& observer = {});

}  // namespace voxplan
