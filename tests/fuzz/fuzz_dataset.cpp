// The dataset readers (io/dataset.h OpenDataset, then Dataset::Load) on one fuzzed file in an
// otherwise valid dataset folder: the first byte picks the file (a frame list, a trajectory, a
// camera or intrinsics file, an association file, in each layout), the rest is its content. The
// folders are written once with tiny images; each run replaces one file and puts it back after.
// An opened dataset must describe its images, and each frame load must succeed or fail cleanly.
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <vector>

#include "io/dataset.h"
#include "io/image_io.h"
#include "tests/fuzz/dataset_scaffold.h"
#include "tests/fuzz/fuzz_support.h"

namespace {

using namespace voxplan;
using namespace voxplan::fuzz;
namespace fs = std::filesystem;

fs::path RoleDir(size_t role) { return fuzz::ScratchDir() / ("role" + std::to_string(role)); }

void WriteScaffolds() {
  const std::vector<uint16_t> depth(12, 1500);  // 4x3, 1.5 m at scale 1000
  const std::vector<uint8_t> color(36, 128);
  for (size_t r = 0; r < kNumRoles; ++r) {
    const fs::path dir = RoleDir(r);
    for (const auto& [d, c] : Images(kRoles[r].layout)) {
      fs::create_directories((dir / d).parent_path());
      fs::create_directories((dir / c).parent_path());
      if (!WritePngRaw((dir / d).string(), 4, 3, 1, 16, depth.data()).ok()) std::abort();
      if (!WritePngRaw((dir / c).string(), 4, 3, 3, 8, color.data()).ok()) std::abort();
    }
    for (const FileSpec& f : Files(kRoles[r].layout)) fuzz::WriteText(dir / f.name, f.content);
  }
}

void CheckDataset(const Dataset& dataset) {
  const DatasetInfo& info = dataset.info();
  if (info.num_frames == 0 || info.camera.width != 4 || info.camera.height != 3) std::abort();
  for (size_t i = 0; i < info.num_frames && i < 3; ++i) {
    const Result<Frame> frame = dataset.Load(i);
    if (!frame.ok()) continue;
    if (frame->depth.width != 4 || frame->depth.height != 3) std::abort();
    if (frame->T_W_C && !frame->T_W_C->matrix().allFinite()) std::abort();
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const bool written = (WriteScaffolds(), true);
  (void)written;
  if (size < 1) return 0;
  const size_t r = data[0] % kNumRoles;
  const fs::path file = RoleDir(r) / kRoles[r].fuzzed;
  fuzz::WriteBytes(file, data + 1, size - 1);
  const Result<std::unique_ptr<Dataset>> dataset = OpenDataset(RoleDir(r).string());
  if (dataset.ok()) CheckDataset(**dataset);
  fuzz::WriteText(file, DefaultContent(kRoles[r]));
  return 0;
}
