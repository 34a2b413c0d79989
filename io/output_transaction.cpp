#include "io/output_transaction.h"

#include <cassert>
#include <filesystem>
#include <system_error>

#include "io/temp_files.h"

namespace voxplan {

namespace fs = std::filesystem;

namespace {

std::mutex g_open_mutex;
OutputTransaction* g_open = nullptr;

}  // namespace

OutputTransaction::OutputTransaction() {
  const std::lock_guard<std::mutex> lock(g_open_mutex);
  assert(g_open == nullptr && "one output transaction at a time");
  g_open = this;
}

OutputTransaction::~OutputTransaction() {
  if (open_) Rollback();
}

void OutputTransaction::WatchFolder(const std::string& dir) {
  std::error_code ec;
  fs::path top = fs::absolute(dir, ec).lexically_normal();
  if (ec || fs::exists(top, ec)) return;
  while (top.has_parent_path() && top.parent_path() != top && !fs::exists(top.parent_path(), ec))
    top = top.parent_path();
  const std::lock_guard<std::mutex> lock(mutex_);
  created_folders_.push_back({top.string(), RememberTempFolder(top.string())});
}

bool OutputTransaction::StageInOpenTransaction(const std::string& tmp, int slot,
                                               const std::string& target) {
  const std::lock_guard<std::mutex> open_lock(g_open_mutex);
  if (g_open == nullptr) return false;
  const std::lock_guard<std::mutex> lock(g_open->mutex_);
  g_open->staged_.push_back({tmp, target, slot});
  return true;
}

Status OutputTransaction::Commit() {
  std::vector<Staged> staged;
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    staged.swap(staged_);
  }
  // A folder in a target's place would stop the renames half-way: refuse before the first.
  Status result = Status::Ok();
  for (const Staged& s : staged) {
    std::error_code ec;
    if (fs::is_directory(s.target, ec)) {
      result = IoError("writing " + s.target + ": a folder is in the way");
      break;
    }
  }
  for (const Staged& s : staged) {
    std::error_code ec;
    if (result.ok()) {
      fs::rename(s.tmp, s.target, ec);
      if (!ec) {
        ForgetTempFile(s.slot);
        continue;
      }
      result = IoError("writing " + s.target +
                       ": cannot rename the temporary file into place: " + ec.message());
    }
    fs::remove(s.tmp, ec);
    ForgetTempFile(s.slot);
  }
  std::vector<Folder> folders;
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    folders.swap(created_folders_);
  }
  for (const Folder& dir : folders) ForgetTempFolder(dir.slot);  // they hold outputs now
  Close();
  return result;
}

void OutputTransaction::Rollback() {
  std::vector<Staged> staged;
  std::vector<Folder> folders;
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    staged.swap(staged_);
    folders.swap(created_folders_);
  }
  std::error_code ec;
  for (const Staged& s : staged) {
    fs::remove(s.tmp, ec);
    ForgetTempFile(s.slot);
  }
  // Created by this run, so everything in them is this run's.
  for (const Folder& dir : folders) {
    fs::remove_all(dir.path, ec);
    ForgetTempFolder(dir.slot);
  }
  Close();
}

size_t OutputTransaction::staged() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  return staged_.size();
}

void OutputTransaction::Close() {
  const std::lock_guard<std::mutex> lock(g_open_mutex);
  if (g_open == this) g_open = nullptr;
  open_ = false;
}

}  // namespace voxplan
