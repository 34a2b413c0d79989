#include "core/summary.h"

#include <sys/resource.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <numeric>

namespace voxplan {

TimingSummary Summarize(std::vector<double> values) {
  TimingSummary s;
  if (values.empty()) return s;
  std::sort(values.begin(), values.end());
  auto quantile = [&](double q) {
    const double pos = q * double(values.size() - 1);
    const size_t lo = size_t(std::floor(pos));
    const size_t hi = std::min(lo + 1, values.size() - 1);
    return values[lo] + (pos - double(lo)) * (values[hi] - values[lo]);
  };
  s.median = quantile(0.5);
  s.p90 = quantile(0.9);
  s.total = std::accumulate(values.begin(), values.end(), 0.0);
  s.mean = s.total / double(values.size());
  return s;
}

double RoundTo(double value, int decimals) {
  const double scale = std::pow(10.0, decimals);
  return std::round(value * scale) / scale;
}

double Mib(size_t bytes) { return RoundTo(double(bytes) / (1024.0 * 1024.0), 3); }

double PeakRssMb() {
  rusage usage{};
  if (getrusage(RUSAGE_SELF, &usage) != 0) return 0.0;
  return RoundTo(double(usage.ru_maxrss) / 1024.0, 1);  // ru_maxrss is KiB on Linux
}

}  // namespace voxplan
