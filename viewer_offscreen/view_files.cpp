// WriteViewFiles: remember the topmost folder this run creates, write, undo on failure.
#include "viewer_offscreen/view_files.h"

#include <cstdio>
#include <filesystem>

namespace voxplan {

namespace {

namespace fs = std::filesystem;

// Removes what this run wrote, so a failed run leaves nothing behind.
void CleanUp(const std::vector<std::string>& added, const fs::path& created_dir) {
  std::error_code ec;
  for (const std::string& path : added) fs::remove(path, ec);
  if (!created_dir.empty()) fs::remove_all(created_dir, ec);
}

}  // namespace

std::string ViewFileName(size_t k) {
  char name[32];
  std::snprintf(name, sizeof(name), "render_%03zu.png", k);
  return name;
}

Result<std::vector<std::string>> WriteViewFiles(const std::string& out_dir,
                                                const std::vector<ColorImage>& images,
                                                const PngWriter& write_png) {
  std::error_code ec;
  const fs::path dir(out_dir);
  fs::path created_dir;
  if (!fs::is_directory(dir, ec)) {
    // Remember the topmost folder this run creates, to remove it again on failure.
    fs::path top = dir;
    while (top.has_parent_path() && !top.parent_path().empty() &&
           !fs::exists(top.parent_path(), ec))
      top = top.parent_path();
    if (!fs::create_directories(dir, ec) || ec) {
      return IoError("cannot create output folder " + out_dir + ": " + ec.message());
    }
    created_dir = top;
  }
  std::vector<std::string> written, added;  // added: written where no file was before
  for (size_t k = 0; k < images.size(); ++k) {
    const std::string path = (dir / ViewFileName(k)).string();
    const bool existed = fs::exists(path, ec);
    if (Status s = write_png(path, images[k]); !s.ok()) {
      CleanUp(added, created_dir);
      return s.Naming(path);
    }
    written.push_back(path);
    if (!existed) added.push_back(path);
  }
  return written;
}

}  // namespace voxplan
