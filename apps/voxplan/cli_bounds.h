#pragma once
// Range checks for numeric options, with messages that give the range, and the memory budget
// options. The ranges are core/bounds.h's, the ones the libraries' Validate() apply.
#include <CLI/CLI.hpp>
#include <cstdint>
#include <string>
#include <utility>

#include "core/volume.h"
#include "pipeline/fuse_dataset.h"

namespace voxplan::cli {

// Finite numbers in [lo, hi]: "must be in [lo, hi] unit, got X" (CLI11 puts the option first).
CLI::Validator InRange(double lo, double hi, const std::string& unit = "");
// Integers in [lo, hi] (a fraction or NaN is "not an integer").
CLI::Validator IntInRange(int64_t lo, int64_t hi, const std::string& unit = "");
// The common ones: worker threads (0: all), voxel size (m), frame counts (0: all), strides.
CLI::Validator ThreadCount();
CLI::Validator VoxelSize();
CLI::Validator FrameCount();
CLI::Validator Stride();
// Image and render width or height in pixels.
CLI::Validator ImageSide();

// Usage message for a voxel size and truncation (metres) that VolumeParams::Validate refuses,
// naming the options; empty when they are fine.
std::string CheckVoxelAndTrunc(double voxel_size_m, double trunc_m,
                               const std::string& trunc_option = "--trunc");

// --max-memory and --on-memory-limit of the commands that fuse.
struct MemoryBudgetOptions {
  std::string max_memory;  // empty: DefaultMemoryBudget()
  std::string on_limit = "drop";
};
void AddMemoryBudgetOptions(CLI::App* sub, MemoryBudgetOptions& o, bool with_on_limit = true);
// "512M", "4G", "1.5G", "65536K", "1073741824" (bytes): 1024-based, within core/bounds.h's
// memory range; the message says what is wrong.
Result<uint64_t> ParseMemorySize(const std::string& text);
// "WxH" (or "WXH"), each side and the pixel count within bounds::CheckImageSize's.
Result<std::pair<int, int>> ParseImageSize(const std::string& text);
// Half the machine's memory: physical memory, or the cgroup's limit where that is lower.
uint64_t DefaultMemoryBudget();
// The budget in bytes (the option's, or the default) and what to do past it.
uint64_t MemoryBudgetBytes(const MemoryBudgetOptions& o);
OnMemoryLimit MemoryLimitAction(const MemoryBudgetOptions& o);

}  // namespace voxplan::cli
