#include "io/file_util.h"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <system_error>

#include "io/output_transaction.h"
#include "io/temp_files.h"

namespace voxplan {

namespace fs = std::filesystem;

namespace {

// Same folder so the final rename stays on one file system and is atomic; same extension so
// writers that choose a format by extension still see the right one.
std::string TempPathFor(const std::string& path) {
  static std::atomic<uint64_t> counter{0};
  const fs::path p(path);
  return path + ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(counter++) +
         p.extension().string();
}

}  // namespace

Status WriteAtomically(const std::string& path,
                       const std::function<Status(const std::string&)>& write) {
  if (path.empty()) return InvalidArgument("cannot write to an empty path");
  const std::string tmp = TempPathFor(path);
  // Remembered before it exists, so a signal at any point removes it.
  const int slot = RememberTempFile(tmp);
  if (slot < 0) return IoError("writing " + path + ": too many temporary files in flight");
  std::error_code ec;
  const auto discard = [&] {
    fs::remove(tmp, ec);
    ForgetTempFile(slot);
  };
  const Status written = write(tmp);
  if (!written.ok()) {
    discard();
    return written.WithContext("writing " + path);
  }
  if (!fs::is_regular_file(tmp, ec)) {
    discard();
    return IoError("writing " + path + ": the writer produced no file");
  }
  if (OutputTransaction::StageInOpenTransaction(tmp, slot, path)) return Status::Ok();
  fs::rename(tmp, path, ec);
  if (ec) {
    const std::string why = ec.message();
    discard();
    return IoError("writing " + path + ": cannot rename the temporary file into place: " + why);
  }
  ForgetTempFile(slot);
  return Status::Ok();
}

Status WriteStringToFile(const std::string& path, std::string_view data) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) return IoError("cannot open " + path + " for writing: " + std::strerror(errno));
  const size_t n = data.empty() ? 0 : std::fwrite(data.data(), 1, data.size(), f);
  const int write_errno = errno;
  const bool closed = std::fclose(f) == 0;
  if (n != data.size() || !closed)
    return IoError("cannot write " + path + ": " +
                   std::strerror(n != data.size() ? write_errno : errno));
  return Status::Ok();
}

std::string LowerExtension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return char(std::tolower(c)); });
  return ext;
}

Result<std::string> ReadFileToString(const std::string& path) {
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  if (!fs::exists(st)) return NotFound("no such file: " + path);
  if (fs::is_directory(st)) return InvalidArgument(path + " is a folder, not a file");
  std::ifstream in(path, std::ios::binary);
  if (!in) return IoError("cannot open " + path + ": " + std::strerror(errno));
  std::string data;
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  in.seekg(0, std::ios::beg);
  if (size > 0) {
    data.resize(size_t(size));
    in.read(data.data(), size);
    if (in.gcount() != size) return IoError("cannot read " + path + ": short read");
  }
  return data;
}

Status WriteFileAtomically(const std::string& path, std::string_view data) {
  return WriteAtomically(
      path, [&](const std::string& tmp_path) { return WriteStringToFile(tmp_path, data); });
}

}  // namespace voxplan
