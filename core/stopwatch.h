#pragma once
// The project's one wall-clock timer (std::chrono::steady_clock), for the timings libraries
// report and front ends print. Timings are reported, never used to decide anything.
#include <chrono>

namespace voxplan {

class Stopwatch {
 public:
  Stopwatch() : start_(std::chrono::steady_clock::now()) {}
  double ElapsedMs() const {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start_)
        .count();
  }
  double ElapsedS() const { return ElapsedMs() / 1000.0; }
  void Restart() { start_ = std::chrono::steady_clock::now(); }

 private:
  std::chrono::steady_clock::time_point start_;
};

}  // namespace voxplan
