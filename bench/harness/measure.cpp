// Timing summaries, memory figures and the machine description for the bench harness.
#include "bench/harness/measure.h"

#include <sched.h>
#include <sys/resource.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <numeric>
#include <sstream>

#include "core/parallel.h"

namespace voxplan::bench {

TimingSummary Summarize(std::vector<double> values_ms) {
  TimingSummary s;
  if (values_ms.empty()) return s;
  std::sort(values_ms.begin(), values_ms.end());
  // Linear interpolation between closest ranks.
  auto quantile = [&](double q) {
    const double pos = q * double(values_ms.size() - 1);
    const size_t lo = size_t(std::floor(pos));
    const size_t hi = std::min(lo + 1, values_ms.size() - 1);
    return values_ms[lo] + (pos - double(lo)) * (values_ms[hi] - values_ms[lo]);
  };
  s.median = quantile(0.5);
  s.p90 = quantile(0.9);
  s.total = std::accumulate(values_ms.begin(), values_ms.end(), 0.0);
  s.mean = s.total / double(values_ms.size());
  return s;
}

double PeakRssMb() {
  rusage usage{};
  if (getrusage(RUSAGE_SELF, &usage) != 0) return 0.0;
  return RoundTo(double(usage.ru_maxrss) / 1024.0, 1);  // ru_maxrss is KiB on Linux
}

double RoundTo(double value, int decimals) {
  const double scale = std::pow(10.0, decimals);
  return std::round(value * scale) / scale;
}

double Mib(size_t bytes) { return RoundTo(double(bytes) / (1024.0 * 1024.0), 3); }

std::string Cell(const std::optional<double>& v, int decimals) {
  if (!v) return "-";
  std::ostringstream s;
  s << std::fixed << std::setprecision(decimals) << *v;
  return s.str();
}

int Nproc() {
  cpu_set_t set;
  CPU_ZERO(&set);
  if (sched_getaffinity(0, sizeof(set), &set) == 0) return CPU_COUNT(&set);
  return HardwareThreads();
}

std::string CpuModel() {
  std::ifstream in("/proc/cpuinfo");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("model name", 0) == 0) {
      const size_t colon = line.find(':');
      if (colon != std::string::npos) {
        std::string model = line.substr(colon + 1);
        model.erase(0, model.find_first_not_of(" \t"));
        return model;
      }
    }
  }
  return "unknown";
}

}  // namespace voxplan::bench
