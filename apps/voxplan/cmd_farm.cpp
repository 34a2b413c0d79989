// voxplan farm: a task file's commands dealt out to mpirun's ranks (distributed/task_farm.h).
#include <iostream>
#include <memory>

#include "apps/voxplan/cli_common.h"
#include "apps/voxplan/path_check.h"
#include "apps/voxplan/signals.h"
#include "distributed/task_farm.h"

namespace voxplan::cli {

namespace {

struct FarmOptions {
  std::string tasks_path;
  std::string stats_path;
};

int RunFarm(const FarmOptions& o) {
  Result<std::unique_ptr<Communicator>> world = WorldCommunicator();
  if (!world.ok()) return Fail(world.status().message());
  Communicator& comm = **world;
  std::vector<FarmTask> tasks;
  int code = kExitOk;
  if (comm.is_root()) {
    Result<std::vector<FarmTask>> read = ReadFarmTasks(o.tasks_path);
    if (read.ok())
      tasks = std::move(*read);
    else
      code = Fail(read.status().message(), kExitUsage);
  }
  // Every rank learns whether rank 0 could read the tasks.
  Result<uint64_t> agreed = comm.AllMax(uint64_t(code));
  if (!agreed.ok()) return Fail(agreed.status().message());
  if (*agreed != 0) return int(*agreed);

  FarmObserver observer;
  const StopPolling polling;  // Ctrl-C: deal no more tasks, let the running ones finish
  if (comm.is_root()) {
    std::cerr << "farm: " << tasks.size() << " tasks from " << o.tasks_path << " on " << comm.size()
              << (comm.size() == 1 ? " rank" : " ranks") << std::endl;
    observer.stop_requested = StopRequestedFn();
    observer.finished = [&](size_t task, int exit_code, int rank, size_t done) {
      std::cerr << "farm: task " << task + 1 << " done on rank " << rank << " (exit " << exit_code
                << "), " << done << " of " << tasks.size() << std::endl;
    };
  }
  Result<FarmResult> result = RunTaskFarm(comm, tasks, observer);
  if (!result.ok()) return Fail(result.status().message());
  if (!comm.is_root()) return kExitOk;

  std::vector<size_t> per_rank(size_t(comm.size()), 0);
  size_t not_run = 0;
  nlohmann::json failed = nlohmann::json::array();
  for (size_t t = 0; t < result->tasks; ++t) {
    if (result->ran_on[t] >= 0) ++per_rank[size_t(result->ran_on[t])];
    if (result->exit_codes[t] < 0) ++not_run;
    if (result->exit_codes[t] != 0) failed.push_back(t + 1);
  }
  nlohmann::json j;
  j["command"] = "farm";
  j["tasks"] = result->tasks;
  j["failed"] = result->failed;
  j["not_run"] = not_run;
  j["failed_tasks"] = failed;  // 1-based, as the progress lines number them
  j["ranks"] = comm.size();
  j["tasks_per_rank"] = per_rank;
  j["wall_s"] = RoundTo(result->wall_s, 3);
  if (!o.stats_path.empty()) {
    if (Status s = WriteJsonFile(j, o.stats_path); !s.ok())
      return Fail(MessageNaming(s, o.stats_path));
  }
  PrintJsonLine(j);
  if (not_run > 0) return Interrupted(std::to_string(not_run) + " tasks not run");
  return result->failed > 0 ? kExitFailure : kExitOk;
}

}  // namespace

Command AddFarmCommand(CLI::App& app) {
  auto o = std::make_shared<FarmOptions>();
  CLI::App* sub = app.add_subcommand(
      "farm",
      "Run a task file's shell commands, one per line, dealt out to mpirun's ranks as they "
      "become free (the planner suites' VOXPLAN_SUITE_MPI). Each runs as /bin/sh -c LINE in the "
      "current folder, without MPI's variables. Exit 0 when every task exited 0, 1 when some "
      "failed (listed in the summary), 130/143 when stopped before all ran");
  sub->add_option("tasks", o->tasks_path, "Task file: one shell command per line ('#' comments)")
      ->required()
      ->check(CLI::ExistingFile);
  sub->add_option("--stats", o->stats_path, "Write the summary JSON")->check(OutputFileValidator());
  return {sub, [o] { return RunFarm(*o); }};
}

}  // namespace voxplan::cli
