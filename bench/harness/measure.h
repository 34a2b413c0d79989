#pragma once
// What the bench runs share beside core/summary.h: table cells, the machine, the progress
// callback.
#include <cstddef>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "core/summary.h"

namespace voxplan::bench {

// A figure in a progress line or table cell: fixed with `decimals` decimals, "-" when absent.
std::string Cell(const std::optional<double>& v, int decimals = 2);

// Progress in pieces of text ("threads 2:", " integrate 12.34 ms", ...); a piece ending in '\n'
// ends a line. Library code never prints; front ends pass these on.
using ProgressText = std::function<void(const std::string& text)>;

int Nproc();             // CPUs this process may run on
std::string CpuModel();  // /proc/cpuinfo's model name, or "unknown"

}  // namespace voxplan::bench
