#pragma once
// The outputs of one command, landing together or not at all. While a transaction is open,
// WriteAtomically (io/file_util.h) writes each file to its temporary path beside the target and
// leaves it there; Commit renames them all into place. Destroying an uncommitted transaction
// removes the temporary files and the folders the run created (those named to WatchFolder that
// did not exist yet), so a run that fails half-way through its outputs leaves nothing behind and
// every file it would have replaced untouched. The temporary files stay in io/temp_files.h's
// table until renamed, so a signal handler removes them too. One transaction at a time.
#include <mutex>
#include <string>
#include <vector>

#include "core/status.h"

namespace voxplan {

class OutputTransaction {
 public:
  OutputTransaction();   // becomes the open transaction
  ~OutputTransaction();  // rolls back unless committed
  OutputTransaction(const OutputTransaction&) = delete;
  OutputTransaction& operator=(const OutputTransaction&) = delete;

  // Remembers the topmost missing folder of `dir` (if any): a rollback removes it again.
  void WatchFolder(const std::string& dir);
  // Renames every staged file into place, in the order written, and closes the transaction. A
  // folder where a file should go fails it before any rename (nothing lands). A rename that
  // fails otherwise (rare: the temporary file already sits in the target's folder) stops there,
  // removes the rest and names the file; files renamed before it stay.
  Status Commit();
  // Removes every staged file and the watched folders it created; closes the transaction.
  void Rollback();
  size_t staged() const;

  // For WriteAtomically: hands the finished temporary file `tmp` (table slot `slot`) for
  // `target` to the open transaction. False when none is open: the caller renames it itself.
  static bool StageInOpenTransaction(const std::string& tmp, int slot, const std::string& target);

 private:
  struct Staged {
    std::string tmp, target;
    int slot = -1;
  };
  struct Folder {
    std::string path;
    int slot = -1;  // in io/temp_files.h's table
  };
  void Close();

  mutable std::mutex mutex_;
  std::vector<Staged> staged_;
  std::vector<Folder> created_folders_;
  bool open_ = true;
};

}  // namespace voxplan
