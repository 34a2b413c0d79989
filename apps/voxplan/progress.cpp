#include "apps/voxplan/progress.h"

#include <unistd.h>

#include <cstdio>
#include <iostream>

#include "apps/voxplan/cli_common.h"

namespace voxplan::cli {

Progress::Progress(std::string label, size_t total, std::string unit)
    : label_(std::move(label)),
      total_(total),
      unit_(std::move(unit)),
      tty_(::isatty(STDERR_FILENO) == 1) {}

void Progress::Update(size_t done) {
  if (total_ == 0) return;
  const int percent = int(100 * done / total_);
  if (tty_) {
    if (percent == last_percent_) return;
    last_percent_ = percent;
    constexpr int kWidth = 30;
    const int filled = percent * kWidth / 100;
    std::fprintf(stderr, "\r%s [%s%s] %3d%% (%zu/%zu)", label_.c_str(),
                 std::string(size_t(filled), '#').c_str(),
                 std::string(size_t(kWidth - filled), '.').c_str(), percent, done, total_);
    std::fflush(stderr);
    bar_drawn_ = true;
    return;
  }
  const int decile = percent / 10;
  if (decile == last_decile_ || (decile == 0 && done < total_)) return;
  last_decile_ = decile;
  std::fprintf(stderr, "%s: %zu/%zu %s (%d%%)\n", label_.c_str(), done, total_, unit_.c_str(),
               percent);
}

void Progress::ClearBar() {
  if (!bar_drawn_) return;
  std::fprintf(stderr, "\r\033[K");
  bar_drawn_ = false;
  last_percent_ = -1;  // redraw on the next update
}

void Progress::Warn(const std::string& message) {
  ClearBar();
  cli::Warn(message);
}

void Progress::Finish() {
  if (tty_ && bar_drawn_) {
    std::fprintf(stderr, "\n");
    bar_drawn_ = false;
  }
}

}  // namespace voxplan::cli
