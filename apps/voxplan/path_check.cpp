#include "apps/voxplan/path_check.h"

#include <sys/stat.h>

#include <filesystem>
#include <map>
#include <system_error>
#include <utility>

#include "apps/voxplan/cli_common.h"

namespace voxplan::cli {

namespace {

namespace fs = std::filesystem;

// What identifies a file: its inode when it exists, else its resolved path.
struct FileKey {
  bool exists = false;
  dev_t dev = 0;
  ino_t ino = 0;
  std::string resolved;
  bool operator<(const FileKey& o) const {
    if (exists != o.exists) return exists < o.exists;
    if (exists) return std::pair(dev, ino) < std::pair(o.dev, o.ino);
    return resolved < o.resolved;
  }
};

FileKey KeyOf(const std::string& path) {
  FileKey key;
  struct stat st {};
  if (::stat(path.c_str(), &st) == 0) {
    key.exists = true;
    key.dev = st.st_dev;
    key.ino = st.st_ino;
    return key;
  }
  // A dangling symbolic link names the file it would create.
  std::error_code ec;
  fs::path target = path;
  for (int hops = 0; hops < 40 && fs::is_symlink(fs::symlink_status(target, ec)); ++hops) {
    const fs::path link = fs::read_symlink(target, ec);
    if (ec) break;
    target = link.is_absolute() ? link : target.parent_path() / link;
  }
  const fs::path absolute = fs::absolute(target, ec);
  const fs::path resolved = ec ? fs::path(path) : fs::weakly_canonical(absolute, ec);
  key.resolved = (ec ? absolute : resolved).lexically_normal().string();
  return key;
}

// `error: <file>: <reason>`, the file as the later option gave it.
std::string Collision(const PathUse& first, const PathUse& later, const char* what) {
  const std::string alias = first.path == later.path ? "" : " (" + first.path + ")";
  return later.path + ": " + first.option + " and " + later.option + " are the same file" + alias +
         ": " + what;
}

}  // namespace

std::string FindPathCollision(const std::vector<PathUse>& outputs,
                              const std::vector<PathUse>& inputs) {
  std::map<FileKey, const PathUse*> written;
  for (const PathUse& out : outputs) {
    if (out.path.empty()) continue;
    const auto [it, added] = written.emplace(KeyOf(out.path), &out);
    if (!added) return Collision(*it->second, out, "one output would overwrite the other");
  }
  for (const PathUse& in : inputs) {
    if (in.path.empty()) continue;
    const auto it = written.find(KeyOf(in.path));
    if (it != written.end())
      return Collision(*it->second, in, "an output would overwrite an input");
  }
  return {};
}

int RefusePathCollisions(const std::vector<PathUse>& outputs, const std::vector<PathUse>& inputs) {
  const std::string collision = FindPathCollision(outputs, inputs);
  return collision.empty() ? kExitOk : Fail(collision, kExitUsage);
}

void AddInputs(std::vector<PathUse>& inputs, const std::string& option,
               const std::vector<std::string>& files) {
  for (const std::string& f : files) inputs.push_back({option, f});
}

}  // namespace voxplan::cli
