#pragma once
// The files a command reads and writes, checked before any work: two outputs that are one file,
// or an output that is one of the inputs, are refused (exit 2) with both options and the path.
// "One file" means the same path after resolving symbolic links and `.`/`..`, or, for files
// that exist, the same inode (so symbolic and hard links count).
#include <string>
#include <vector>

namespace voxplan::cli {

struct PathUse {
  std::string option;  // how the user named it: "--map", "the dataset", "--out (mesh.ply)"
  std::string path;    // empty: not given, ignored
};

// Empty when no two uses collide; else the message for the first collision found.
std::string FindPathCollision(const std::vector<PathUse>& outputs,
                              const std::vector<PathUse>& inputs);
// kExitOk, or prints the collision and returns kExitUsage.
int RefusePathCollisions(const std::vector<PathUse>& outputs, const std::vector<PathUse>& inputs);

// `files` as inputs, each named `option` (e.g. every file a dataset reads).
void AddInputs(std::vector<PathUse>& inputs, const std::string& option,
               const std::vector<std::string>& files);

}  // namespace voxplan::cli
