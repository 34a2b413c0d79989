#pragma once
// What the fuzz targets share. The loaders take paths, so each run writes its input to a file in
// a scratch folder of this process's own ($TMPDIR/voxplan-fuzz-<pid>, removed at exit; fork mode
// gives every worker its own).
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

namespace voxplan::fuzz {

namespace fs = std::filesystem;

inline const fs::path& ScratchDir() {
  static const fs::path dir = [] {
    const fs::path d = fs::temp_directory_path() / ("voxplan-fuzz-" + std::to_string(getpid()));
    fs::create_directories(d);
    std::atexit([] {
      std::error_code ec;
      fs::remove_all(ScratchDir(), ec);
    });
    return d;
  }();
  return dir;
}

// Writes the bytes to `path` (replacing it); aborts on failure, which is the harness's fault.
inline void WriteBytes(const fs::path& path, const uint8_t* data, size_t size) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f || std::fwrite(data, 1, size, f) != size || std::fclose(f) != 0) std::abort();
}
inline void WriteText(const fs::path& path, const std::string& text) {
  WriteBytes(path, reinterpret_cast<const uint8_t*>(text.data()), text.size());
}

// The input as the file ScratchDir()/name.
inline std::string InputFile(const uint8_t* data, size_t size, const std::string& name) {
  const fs::path path = ScratchDir() / name;
  WriteBytes(path, data, size);
  return path.string();
}

}  // namespace voxplan::fuzz
