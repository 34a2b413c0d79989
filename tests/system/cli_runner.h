#pragma once
// Runs the built voxplan executable as a user would, for the CLI-level system tests.
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace voxplan::test {

struct RunResult {
  int exit_code = -1;
  std::string out, err;
  nlohmann::json last_json;  // the last stdout line, parsed; null when it is not JSON
};

std::string ReadAll(const std::filesystem::path& path);
// `voxplan args...` with stdout and stderr captured in files (not a terminal, so progress is
// plain lines) and no stdin. env_prefix: shell assignments for the run, e.g. "PYTHONHOME=/x".
RunResult RunCli(const std::vector<std::string>& args, const std::string& env_prefix = "");
std::string Describe(const RunResult& r);  // exit code and both streams, for failure messages

// The shared ICL-NUIM sequence, and a copy of its first `frames` frames (associations, depth,
// colour, ground truth) into `to`, for tests that break a frame of their own.
std::filesystem::path IclDir();
void CopyIclFrames(const std::filesystem::path& to, int frames);

}  // namespace voxplan::test
