#pragma once
// Small file helpers shared by every writer and reader in io/ (and the CLI).
#include <functional>
#include <string>
#include <string_view>

#include "core/status.h"

namespace voxplan {

// Calls write(tmp_path) with a temporary path in the target's folder (same extension), then
// renames it over `path`. On any failure the temporary file is removed and `path` is untouched.
// While an OutputTransaction (io/output_transaction.h) is open, the finished temporary file is
// handed to it instead and renamed at its Commit. The temporary file is named
// `<path>.tmp-<pid>-<n><extension>` and listed in io/temp_files.h until renamed or removed.
Status WriteAtomically(const std::string& path,
                       const std::function<Status(const std::string&)>& write);

// Writes `data` to `path` in one go (not atomic: use inside WriteAtomically's callback).
Status WriteStringToFile(const std::string& path, std::string_view data);

// WriteAtomically of WriteStringToFile: `data` replaces `path` whole or not at all.
Status WriteFileAtomically(const std::string& path, std::string_view data);

// The extension of `path` in lower case, with its dot (".ply"), or "".
std::string LowerExtension(const std::string& path);

// Reads a whole file; the error names the file.
Result<std::string> ReadFileToString(const std::string& path);

}  // namespace voxplan
