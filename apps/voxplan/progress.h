#pragma once
// Progress of a long command on stderr: a redrawn bar on a terminal, else a plain line every
// ~10 % so logs stay short; warnings print without tearing the bar.
#include <cstddef>
#include <string>

namespace voxplan::cli {

class Progress {
 public:
  // unit names what is counted in the plain lines ("frames", "steps").
  Progress(std::string label, size_t total, std::string unit = "frames");
  void Update(size_t done);
  // Prints a warning without tearing the bar.
  void Warn(const std::string& message);
  void Finish();

 private:
  void ClearBar();
  std::string label_;
  size_t total_;
  std::string unit_;
  bool tty_;
  bool bar_drawn_ = false;
  int last_decile_ = -1;
  int last_percent_ = -1;
};

}  // namespace voxplan::cli
