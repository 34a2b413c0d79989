#pragma once
// What the bench runs share: timing summaries, memory figures, the machine, the progress
// callback. The same arithmetic as the CLI's helpers (apps/ sits above the libraries).
#include <cstddef>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace voxplan::bench {

struct TimingSummary {
  double median = 0.0, p90 = 0.0, mean = 0.0, total = 0.0;
};
// Quantiles by linear interpolation between closest ranks; all zero when empty.
TimingSummary Summarize(std::vector<double> values_ms);

double PeakRssMb();  // MiB to 0.1, from getrusage
double RoundTo(double value, int decimals);
double Mib(size_t bytes);  // to 0.001

// A figure in a progress line or table cell: fixed with `decimals` decimals, "-" when absent.
std::string Cell(const std::optional<double>& v, int decimals = 2);

// Progress in pieces of text ("threads 2:", " integrate 12.34 ms", ...); a piece ending in '\n'
// ends a line. Library code never prints; front ends pass these on.
using ProgressText = std::function<void(const std::string& text)>;

int Nproc();             // CPUs this process may run on
std::string CpuModel();  // /proc/cpuinfo's model name, or "unknown"

}  // namespace voxplan::bench
