// ScanNet .sens files (io/sens_file.h) as `fuse` and `info` read them: the header and frame
// index (ReadSensIndex), then the dataset over it (OpenDataset, Dataset::Load: zlib or raw depth,
// JPEG, PNG or raw colour brought into the depth camera). An accepted index lies inside the
// file and matches its header; everything else is tests/fuzz/dataset_check.h.
#include <cstdint>
#include <cstdlib>
#include <string>

#include "io/dataset.h"
#include "io/sens_file.h"
#include "tests/fuzz/dataset_check.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace voxplan;
  const std::string path = fuzz::InputFile(data, size, "scan.sens");
  const Result<SensIndex> index = ReadSensIndex(path);
  if (!index.ok()) {
    fuzz::CheckNamesFile(index.status(), path);
  } else {
    const SensHeader& h = index->header;
    if (index->file_bytes != size || index->frames.empty() || h.depth_width <= 0 ||
        h.depth_height <= 0)
      std::abort();
    for (const SensFrameRecord& f : index->frames)
      if (f.color_offset + f.color_bytes > size || f.depth_offset + f.depth_bytes > size ||
          f.color_offset + f.color_bytes != f.depth_offset || f.depth_bytes == 0)
        std::abort();
  }
  const Result<std::unique_ptr<Dataset>> dataset = OpenDataset(path);
  if (dataset.ok() && (!index.ok() || (*dataset)->info().num_frames != index->frames.size() ||
                       (*dataset)->info().camera.width != index->header.depth_width ||
                       (*dataset)->info().camera.height != index->header.depth_height))
    std::abort();
  fuzz::CheckDatasetFile(dataset, path);
  return 0;
}
