#include "apps/voxplan/cli_bounds.h"

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <sstream>

#include "core/bounds.h"

namespace voxplan::cli {

namespace {

std::string TypeName(double lo, double hi, const std::string& unit) {
  return "NUMBER in " + bounds::RangeText(lo, hi, unit);
}

// Integers in full: "[0, 1073741824]", not "1.07374e+09".
std::string IntRangeText(int64_t lo, int64_t hi, const std::string& unit) {
  std::string text = "[";  // appended: GCC 12 warns (-Wrestrict, falsely) on "[" + std::string
  text += std::to_string(lo);
  text += ", ";
  text += std::to_string(hi);
  text += "]";
  if (!unit.empty()) text += " " + unit;
  return text;
}

}  // namespace

CLI::Validator InRange(double lo, double hi, const std::string& unit) {
  return CLI::Validator(
      [lo, hi, unit](std::string& text) -> std::string {
        double v = 0.0;
        if (!CLI::detail::lexical_cast(text, v) || !std::isfinite(v))
          return "not a number: " + text + " (must be in " + bounds::RangeText(lo, hi, unit) + ")";
        if (v >= lo && v <= hi) return {};
        return "must be in " + bounds::RangeText(lo, hi, unit) + ", got " + text;
      },
      TypeName(lo, hi, unit));
}

CLI::Validator IntInRange(int64_t lo, int64_t hi, const std::string& unit) {
  return CLI::Validator(
      [lo, hi, unit](std::string& text) -> std::string {
        const std::string range = IntRangeText(lo, hi, unit);
        int64_t v = 0;
        if (!CLI::detail::lexical_cast(text, v))
          return "not an integer: " + text + " (must be in " + range + ")";
        if (v < lo || v > hi) return "must be in " + range + ", got " + text;
        return {};
      },
      "INT in " + IntRangeText(lo, hi, unit));
}

CLI::Validator ThreadCount() { return IntInRange(0, bounds::kThreadsMax, "(0: all)"); }
CLI::Validator VoxelSize() { return InRange(bounds::kVoxelSizeMinM, bounds::kVoxelSizeMaxM, "m"); }
CLI::Validator FrameCount() { return IntInRange(0, bounds::kFramesMax, "(0: all)"); }
CLI::Validator Stride() { return IntInRange(1, bounds::kFramesMax); }
CLI::Validator ImageSide() { return IntInRange(1, bounds::kImageSideMax, "pixels"); }

std::string CheckVoxelAndTrunc(double voxel_size_m, double trunc_m,
                               const std::string& trunc_option) {
  const double voxels = trunc_m / voxel_size_m;
  if (voxels >= bounds::kTruncMinVoxels && voxels <= bounds::kTruncMaxVoxels) return {};
  std::ostringstream message;
  message << trunc_option << " must be in "
          << bounds::RangeText(bounds::kTruncMinVoxels, bounds::kTruncMaxVoxels, "voxels") << " ("
          << bounds::RangeText(bounds::kTruncMinVoxels * voxel_size_m,
                               bounds::kTruncMaxVoxels * voxel_size_m, "m")
          << " at --voxel-size " << voxel_size_m << "), got " << trunc_m << " m";
  return message.str();
}

void AddMemoryBudgetOptions(CLI::App* sub, MemoryBudgetOptions& o, bool with_on_limit) {
  sub->add_option("--max-memory", o.max_memory,
                  "Memory budget of the map, e.g. 512M or 4G (default: half the machine's "
                  "memory); past it no new blocks are allocated")
      ->check(CLI::Validator(
          [](std::string& text) -> std::string {
            Result<uint64_t> bytes = ParseMemorySize(text);
            return bytes.ok() ? std::string() : bytes.status().message();
          },
          "SIZE"));
  if (!with_on_limit) return;
  sub->add_option("--on-memory-limit", o.on_limit,
                  "Past the budget: drop (fuse on without new blocks, counted) or fail")
      ->check(CLI::IsMember({"drop", "fail"}))
      ->capture_default_str();
}

Result<std::pair<int, int>> ParseImageSize(const std::string& text) {
  int width = 0, height = 0;
  char x = 0, extra = 0;
  std::istringstream in(text);
  if (!(in >> width >> x >> height) || (x != 'x' && x != 'X') || (in >> extra)) {
    return InvalidArgument("--size wants WxH, e.g. 640x480: " + text);
  }
  VOXPLAN_RETURN_IF_ERROR(bounds::CheckImageSize("image size", width, height));
  return std::pair(width, height);
}

Result<uint64_t> ParseMemorySize(const std::string& text) {
  std::string range = "[";  // appended: GCC 12 warns (-Wrestrict, falsely) on "[" + std::string
  range += std::to_string(bounds::kMemoryMinBytes >> 20);
  range += "M, ";
  range += std::to_string(bounds::kMemoryMaxBytes >> 40);
  range += "T]";
  size_t used = 0;
  double value = 0.0;
  try {
    value = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  std::string unit = text.substr(used);
  if (!unit.empty() && (unit.back() == 'B' || unit.back() == 'b')) unit.pop_back();
  if (unit.size() == 2 && (unit[1] == 'i' || unit[1] == 'I')) unit.pop_back();  // "GiB"
  const std::string units = "KMGT";
  double scale = 1.0;
  if (unit.size() == 1 && units.find(char(std::toupper(unit[0]))) != std::string::npos) {
    scale = std::pow(1024.0, double(units.find(char(std::toupper(unit[0]))) + 1));
  } else if (!unit.empty() || used == 0) {
    return InvalidArgument("not a memory size (e.g. 512M, 4G): " + text);
  }
  const double bytes = value * scale;
  if (!(bytes >= double(bounds::kMemoryMinBytes) && bytes <= double(bounds::kMemoryMaxBytes)))
    return InvalidArgument("must be in " + range + ", got " + text);
  return uint64_t(bytes);
}

uint64_t DefaultMemoryBudget() {
  const long pages = ::sysconf(_SC_PHYS_PAGES), page = ::sysconf(_SC_PAGESIZE);
  uint64_t total = pages > 0 && page > 0 ? uint64_t(pages) * uint64_t(page) : uint64_t(8) << 30;
  // A container's limit (cgroup v2) is what the OOM killer enforces.
  std::ifstream cgroup("/sys/fs/cgroup/memory.max");
  uint64_t limit = 0;
  if (cgroup >> limit && limit > 0) total = std::min(total, limit);
  return std::clamp(total / 2, bounds::kMemoryMinBytes, bounds::kMemoryMaxBytes);
}

uint64_t MemoryBudgetBytes(const MemoryBudgetOptions& o) {
  if (o.max_memory.empty()) return DefaultMemoryBudget();
  Result<uint64_t> bytes = ParseMemorySize(o.max_memory);  // checked by the validator
  return bytes.ok() ? *bytes : DefaultMemoryBudget();
}

OnMemoryLimit MemoryLimitAction(const MemoryBudgetOptions& o) {
  return o.on_limit == "fail" ? OnMemoryLimit::kFail : OnMemoryLimit::kDrop;
}

}  // namespace voxplan::cli
