#include "distributed/task_farm.h"

#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <deque>
#include <filesystem>
#include <optional>
#include <thread>

#include "core/stopwatch.h"
#include "distributed/wire.h"
#include "io/file_util.h"

extern char** environ;

namespace voxplan {

namespace {

constexpr int kTagReady = 101;  // worker -> rank 0: the last task's index and exit code
constexpr int kTagTask = 102;   // rank 0 -> worker: a task's index and command
constexpr int kTagStop = 103;   // rank 0 -> worker: no more tasks
constexpr uint64_t kNoTask = ~0ull;

// The environment without MPI's launch variables, so a child is not mistaken for a rank.
std::vector<std::string> ChildEnvironment() {
  std::vector<std::string> env;
  for (char** e = environ; *e; ++e) {
    const std::string v = *e;
    if (v.rfind("OMPI_", 0) == 0 || v.rfind("PMIX_", 0) == 0 || v.rfind("PMI_", 0) == 0) continue;
    env.push_back(v);
  }
  return env;
}

// A running task: its child process.
struct Child {
  pid_t pid = -1;
  size_t task = 0;
  Stopwatch clock;
};

Result<pid_t> Spawn(const std::string& command, const std::vector<std::string>& env) {
  std::vector<char*> envp;
  for (const std::string& v : env) envp.push_back(const_cast<char*>(v.c_str()));
  envp.push_back(nullptr);
  const char* argv[] = {"/bin/sh", "-c", command.c_str(), nullptr};
  pid_t pid = -1;
  const int rc =
      posix_spawn(&pid, "/bin/sh", nullptr, nullptr, const_cast<char* const*>(argv), envp.data());
  if (rc != 0) return IoError("cannot start /bin/sh for a task: " + std::string(std::strerror(rc)));
  return pid;
}

int ExitCode(int status) {
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  if (WIFSIGNALED(status)) return 128 + WTERMSIG(status);
  return 255;
}

// Waits for a child; `block` false returns nullopt while it still runs.
std::optional<int> Reap(pid_t pid, bool block) {
  int status = 0;
  for (;;) {
    const pid_t r = waitpid(pid, &status, block ? 0 : WNOHANG);
    if (r == pid) return ExitCode(status);
    if (r == 0) return std::nullopt;
    if (errno != EINTR) return 255;
  }
}

// Every farm message: a task's index, a number (exit code and time, or unused) and a text (the
// command, or empty).
struct FarmMessage {
  uint64_t index = 0;
  int64_t value = 0;
  std::string text;
};

Bytes Encode(uint64_t index, int64_t value, const std::string& text = {}) {
  wire::Writer w;
  w.Put(index);
  w.Put(value);
  w.PutString(text);
  return w.Take();
}

Result<FarmMessage> Decode(const Bytes& bytes, const std::string& what) {
  FarmMessage m;
  wire::Reader r(bytes);
  r.Get(m.index);
  r.Get(m.value);
  r.GetString(m.text);
  VOXPLAN_RETURN_IF_ERROR(r.Finish(what));
  return m;
}

}  // namespace

Result<std::vector<FarmTask>> ReadFarmTasks(const std::string& path) {
  std::error_code ec;
  const uint64_t size = std::filesystem::file_size(path, ec);
  if (ec) return IoError("cannot read task file " + path + ": " + ec.message());
  if (size > (uint64_t(256) << 20)) return InvalidArgument(path + ": task file over 256 MiB");
  Result<std::string> text = ReadFileToString(path);
  if (!text.ok()) return text.status();
  std::vector<FarmTask> tasks;
  size_t line_no = 0, pos = 0;
  while (pos < text->size()) {
    size_t end = text->find('\n', pos);
    if (end == std::string::npos) end = text->size();
    std::string line = text->substr(pos, end - pos);
    pos = end + 1;
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const size_t first = line.find_first_not_of(" \t");
    if (first == std::string::npos || line[first] == '#') continue;
    if (line.size() > (size_t(64) << 10))
      return InvalidArgument(path + ":" + std::to_string(line_no) + ": task longer than 64 KiB");
    if (line.find('\0') != std::string::npos)
      return InvalidArgument(path + ":" + std::to_string(line_no) + ": NUL byte in a task");
    if (tasks.size() == kMaxFarmTasks)
      return InvalidArgument(path + ": more than " + std::to_string(kMaxFarmTasks) + " tasks");
    tasks.push_back({line});
  }
  return tasks;
}

Result<FarmResult> RunTaskFarm(Communicator& comm, const std::vector<FarmTask>& tasks,
                               const FarmObserver& observer) {
  const std::vector<std::string> env = ChildEnvironment();
  if (!comm.is_root()) {
    // Ask for work, run it, report, until told to stop.
    Bytes report = Encode(kNoTask, 0);
    for (;;) {
      VOXPLAN_RETURN_IF_ERROR(comm.Send(report, 0, kTagReady));
      int source = 0, tag = 0;
      Result<Bytes> msg = comm.Receive(0, &source, &tag);
      if (!msg.ok()) return msg.status();
      if (tag == kTagStop) return FarmResult{};
      Result<FarmMessage> task = Decode(*msg, "task from rank 0");
      if (!task.ok()) return task.status();
      const Stopwatch clock;
      Result<pid_t> pid = Spawn(task->text, env);
      const int code = pid.ok() ? Reap(*pid, true).value_or(255) : 127;
      // The wall time travels in microseconds beside the exit code.
      report = Encode(task->index, (int64_t(code) << 40) | int64_t(clock.ElapsedMs() * 1000.0));
    }
  }

  FarmResult result;
  result.tasks = tasks.size();
  result.exit_codes.assign(tasks.size(), -1);
  result.ran_on.assign(tasks.size(), -1);
  result.task_s.assign(tasks.size(), 0.0);
  const Stopwatch wall;
  size_t next = 0, done = 0;
  int workers_stopped = 0;
  const int workers = comm.size() - 1;
  Child own;  // rank 0 runs tasks too, between dealing (pid -1: none running)
  bool stopping = false;
  const auto finish = [&](size_t task, int code, int rank, double seconds) {
    result.exit_codes[task] = code;
    result.ran_on[task] = rank;
    result.task_s[task] = seconds;
    result.failed += code != 0;
    ++done;
    if (observer.finished) observer.finished(task, code, rank, done);
  };
  const auto take = [&]() -> std::optional<size_t> {
    if (!stopping && observer.stop_requested && observer.stop_requested()) stopping = true;
    if (stopping || next == tasks.size()) return std::nullopt;
    return next++;
  };
  while (workers_stopped < workers || own.pid >= 0 || (!stopping && next < tasks.size())) {
    bool busy = false;
    if (own.pid >= 0) {
      if (std::optional<int> code = Reap(own.pid, false)) {
        finish(own.task, *code, 0, own.clock.ElapsedS());
        own.pid = -1;
        busy = true;
      }
    }
    if (own.pid < 0) {
      if (std::optional<size_t> t = take()) {
        Result<pid_t> pid = Spawn(tasks[*t].command, env);
        if (pid.ok()) {
          own.pid = *pid;
          own.task = *t;
          own.clock.Restart();
        } else {
          finish(*t, 127, 0, 0.0);
        }
        busy = true;
      }
    }
    int source = 0, tag = 0;
    Result<bool> waiting = comm.Poll(&source, &tag);
    if (!waiting.ok()) return waiting.status();
    if (*waiting) {
      Result<Bytes> msg = comm.Receive(source, &source, &tag);
      if (!msg.ok()) return msg.status();
      Result<FarmMessage> report = Decode(*msg, "report from rank " + std::to_string(source));
      if (!report.ok()) return report.status();
      const uint64_t index = report->index;
      const int64_t value = report->value;
      if (index != kNoTask && index < tasks.size())
        finish(size_t(index), int(value >> 40), source,
               double(value & ((int64_t(1) << 40) - 1)) / 1e6);
      if (std::optional<size_t> t = take()) {
        VOXPLAN_RETURN_IF_ERROR(comm.Send(Encode(*t, 0, tasks[*t].command), source, kTagTask));
      } else {
        VOXPLAN_RETURN_IF_ERROR(comm.Send(Bytes{}, source, kTagStop));
        ++workers_stopped;
      }
      busy = true;
    }
    // Idle: neither a child finished nor a worker asked. Sleep briefly instead of spinning, so
    // rank 0 leaves its core to the tasks.
    if (!busy) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  result.wall_s = wall.ElapsedS();
  return result;
}

}  // namespace voxplan
