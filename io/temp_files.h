#pragma once
// The temporary files in flight (written, not yet renamed into place or removed), kept where a
// signal handler can reach them: the CLI's handler calls RemoveTempFiles() before _exit, so an
// interrupted run leaves no partial file behind. Libraries never install handlers themselves.
#include <string>

namespace voxplan {

// At most this many temporary files are in flight at once (a render of 3600 views fits).
inline constexpr int kMaxTempFiles = 16384;
inline constexpr int kMaxTempFolders = 64;

// Remembers `path` until ForgetTempFile(slot); returns the slot, or -1 when all are taken (the
// caller then refuses the write: it could not be cleaned up on a signal).
int RememberTempFile(const std::string& path);
// The file was renamed into place or removed; a negative slot is ignored.
void ForgetTempFile(int slot);

// The same for a folder a run created and would remove again on failure (a few at a time).
int RememberTempFolder(const std::string& path);
void ForgetTempFolder(int slot);

// Unlinks every remembered file, then removes every remembered folder that is empty by then.
// Async-signal-safe: no allocation, no locks, only unlink(2).
void RemoveTempFiles();

// How many are remembered now (tests).
int TempFilesInFlight();

}  // namespace voxplan
