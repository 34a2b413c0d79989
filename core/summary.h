#pragma once
// Numbers as voxplan reports them: the median, 90th percentile, mean and total of a series
// (timings, mostly), rounding to a number of decimals for JSON outputs, memory in MiB.
#include <cstddef>
#include <vector>

namespace voxplan {

struct TimingSummary {
  double median = 0.0, p90 = 0.0, mean = 0.0, total = 0.0;
};
// Percentiles interpolate linearly between closest ranks; all 0 for an empty series.
TimingSummary Summarize(std::vector<double> values);

double RoundTo(double value, int decimals);

double Mib(size_t bytes);  // to 0.001 MiB
double PeakRssMb();        // the process's peak resident memory, MiB to 0.1 (getrusage)

}  // namespace voxplan
