// Open3D as a child process: posix_spawn with an edited environment, the frame list in a
// temporary file, the script's last stdout line parsed as its result.
#include "bench/harness/open3d_runner.h"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <sstream>

extern char** environ;

namespace voxplan::bench {

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

constexpr const char* kPython = "/usr/bin/python3";
constexpr const char* kSetupHint =
    "install Open3D for /usr/bin/python3 with scripts/setup-deps --bench";

std::string ScriptPath() { return std::string(VOXPLAN_SOURCE_DIR) + "/bench/open3d_fusion.py"; }

}  // namespace

Result<int> Spawn(const std::vector<std::string>& argv, const std::vector<std::string>& extra_env,
                  std::string* out, bool quiet) {
  std::vector<std::string> env_strings;
  for (char** e = environ; *e != nullptr; ++e) {
    const std::string entry(*e);
    const std::string name = entry.substr(0, entry.find('='));
    const bool overridden = std::any_of(extra_env.begin(), extra_env.end(), [&](const auto& x) {
      return x.substr(0, x.find('=')) == name;
    });
    if (!overridden) env_strings.push_back(entry);
  }
  env_strings.insert(env_strings.end(), extra_env.begin(), extra_env.end());
  std::vector<char*> envp, args;
  for (std::string& s : env_strings) envp.push_back(s.data());
  envp.push_back(nullptr);
  std::vector<std::string> argv_copy = argv;
  for (std::string& s : argv_copy) args.push_back(s.data());
  args.push_back(nullptr);

  int pipe_fds[2];
  if (pipe(pipe_fds) != 0) return IoError(std::string("pipe: ") + std::strerror(errno));
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addclose(&actions, pipe_fds[0]);
  posix_spawn_file_actions_adddup2(&actions, pipe_fds[1], STDOUT_FILENO);
  posix_spawn_file_actions_addclose(&actions, pipe_fds[1]);
  if (quiet) posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, "/dev/null", O_WRONLY, 0);
  pid_t pid = 0;
  const int rc = posix_spawn(&pid, args[0], &actions, nullptr, args.data(), envp.data());
  posix_spawn_file_actions_destroy(&actions);
  close(pipe_fds[1]);
  if (rc != 0) {
    close(pipe_fds[0]);
    return IoError("cannot run " + argv[0] + ": " + std::strerror(rc));
  }
  char buffer[4096];
  ssize_t n = 0;
  while ((n = read(pipe_fds[0], buffer, sizeof(buffer))) != 0) {
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) break;
    out->append(buffer, size_t(n));
  }
  close(pipe_fds[0]);
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  return status;
}

TempFrameList::~TempFrameList() {
  if (!path_.empty()) std::remove(path_.c_str());
}

Status TempFrameList::Write(const json& list) {
  std::string pattern = (fs::temp_directory_path() / "voxplan-bench-frames-XXXXXX").string();
  const int fd = mkstemp(pattern.data());
  if (fd < 0) return IoError("cannot create a temporary file in " + pattern);
  path_ = pattern;
  const std::string text = list.dump() + "\n";
  size_t written = 0;
  while (written < text.size()) {
    const ssize_t n = write(fd, text.data() + written, text.size() - written);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      close(fd);
      return IoError("cannot write " + path_ + ": " + std::strerror(errno));
    }
    written += size_t(n);
  }
  if (close(fd) != 0) return IoError("cannot write " + path_);
  return Status::Ok();
}

Status CheckOpen3d() {
  if (access(kPython, X_OK) != 0)
    return NotFound(std::string(kPython) + " not found; " + kSetupHint);
  if (!fs::exists(ScriptPath())) return NotFound("Open3D script not found: " + ScriptPath());
  std::string out;
  Result<int> status = Spawn({kPython, "-c", "import open3d"}, {}, &out, /*quiet=*/true);
  if (!status.ok()) return NotFound(status.status().message() + "; " + kSetupHint);
  if (!WIFEXITED(*status) || WEXITSTATUS(*status) != 0) {
    return NotFound(std::string(kPython) + " cannot import open3d; " + kSetupHint);
  }
  return Status::Ok();
}

Result<json> RunOpen3d(const std::string& list_path, const std::string& path, int threads,
                       int repeat, const std::string& raycast_poses) {
  std::string out;
  // ACTIVE: Open3D's OpenMP loops stall on small machines with the default passive wait.
  Result<int> status =
      Spawn({kPython, ScriptPath(), list_path, "--path", path, "--repeat", std::to_string(repeat),
             "--raycast-poses", raycast_poses},
            {"OMP_WAIT_POLICY=ACTIVE", "OMP_NUM_THREADS=" + std::to_string(threads)}, &out);
  if (!status.ok()) return status.status();
  if (!WIFEXITED(*status) || WEXITSTATUS(*status) != 0) {
    return Status(StatusCode::kInternal,
                  ScriptPath() + " --path " + path + " failed (exit " +
                      std::to_string(WIFEXITED(*status) ? WEXITSTATUS(*status) : -1) + ")");
  }
  std::string line, last;
  std::istringstream lines(out);
  while (std::getline(lines, line))
    if (!line.empty()) last = line;
  json j = json::parse(last, nullptr, /*allow_exceptions=*/false);
  if (!j.is_object()) {
    return Status(StatusCode::kInternal,
                  ScriptPath() + " --path " + path + ": last stdout line is not JSON: " + last);
  }
  return j;
}

}  // namespace voxplan::bench
