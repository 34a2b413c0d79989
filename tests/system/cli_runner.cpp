#include "tests/system/cli_runner.h"

#include <sys/wait.h>

#include <cstdlib>
#include <fstream>
#include <sstream>

#include "tests/support/test_support.h"

namespace voxplan::test {

namespace fs = std::filesystem;

std::string ReadAll(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

namespace {
std::string Quote(const std::string& arg) {
  std::string q = "'";
  for (char c : arg) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}
}  // namespace

RunResult RunCli(const std::vector<std::string>& args, const std::string& env_prefix) {
  const TempDir capture("voxplan-cli-capture");
  const fs::path out = capture / "stdout", err = capture / "stderr";
  std::string command = env_prefix.empty() ? std::string() : env_prefix + " ";
  command.append(Quote(VOXPLAN_CLI_PATH));
  // Appended piecewise: `" " + Quote(...)` trips a GCC 12 -Wrestrict false positive.
  for (const std::string& a : args) command.append(" ").append(Quote(a));
  command.append(" >").append(Quote(out.string()));
  command.append(" 2>").append(Quote(err.string())).append(" </dev/null");
  const int status = std::system(command.c_str());
  RunResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = ReadAll(out);
  r.err = ReadAll(err);
  std::string line, last;
  std::istringstream lines(r.out);
  while (std::getline(lines, line))
    if (!line.empty()) last = line;
  r.last_json = nlohmann::json::parse(last, nullptr, /*allow_exceptions=*/false);
  if (r.last_json.is_discarded()) r.last_json = nullptr;
  return r;
}

std::string Describe(const RunResult& r) {
  return "exit " + std::to_string(r.exit_code) + "\nstdout:\n" + r.out + "\nstderr:\n" + r.err;
}

std::filesystem::path IclDir() { return SharedDataDir() / "rgbd" / "iclnuim_office_traj0"; }

void CopyIclFrames(const std::filesystem::path& to, int frames) {
  namespace fs = std::filesystem;
  fs::create_directories(to / "depth");
  fs::create_directories(to / "rgb");
  std::ofstream assoc(to / "associations.txt");
  for (int id = 1; id <= frames; ++id) {
    const std::string n = std::to_string(id);
    assoc << n << " depth/" << n << ".png " << n << " rgb/" << n << ".jpg\n";
    fs::copy_file(IclDir() / "depth" / (n + ".png"), to / "depth" / (n + ".png"));
    fs::copy_file(IclDir() / "rgb" / (n + ".jpg"), to / "rgb" / (n + ".jpg"));
  }
  fs::copy_file(IclDir() / "traj0.gt.freiburg", to / "traj0.gt.freiburg");
}

}  // namespace voxplan::test
