#pragma once
// Rendered views to render_000.png, render_001.png, ... in a folder, all or nothing: a failed
// run leaves neither files nor folders it made. The PNG encoder is passed in (io's
// WriteColorPng), since viewer sits beside io and does not link it.
#include <functional>
#include <string>
#include <vector>

#include "core/image.h"
#include "core/status.h"

namespace voxplan {

using PngWriter = std::function<Status(const std::string& path, const ColorImage& image)>;

// "render_007.png": the name of view k.
std::string ViewFileName(size_t k);

// Creates `out_dir` (and missing parents) unless it is a folder, then writes every image.
// Returns the paths written, in order; on failure removes the files it added (not those it
// would have replaced: write_png's atomic writes left them as they were) and the folders it
// created, and returns the error, naming the folder or file. Inside an OutputTransaction
// (io/output_transaction.h) nothing is in place before its Commit.
Result<std::vector<std::string>> WriteViewFiles(const std::string& out_dir,
                                                const std::vector<ColorImage>& images,
                                                const PngWriter& write_png);

}  // namespace voxplan
