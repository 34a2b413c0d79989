// A fixed table of pointers to heap copies of the paths: the handler only reads the pointers and
// calls unlink, so it allocates nothing; a copy is freed only while no handler is running.
#include "io/temp_files.h"

#include <unistd.h>

#include <atomic>
#include <cstring>

namespace voxplan {

namespace {

std::atomic<char*> g_slots[kMaxTempFiles];
std::atomic<char*> g_folders[kMaxTempFolders];
// Set for good once a handler starts removing: from then on nothing is freed (the process is
// about to exit), so the handler never reads a freed path.
std::atomic<bool> g_removing{false};
std::atomic<int> g_in_flight{0};

char* Copy(const std::string& path) {
  char* copy = new char[path.size() + 1];
  std::memcpy(copy, path.c_str(), path.size() + 1);
  return copy;
}

int Remember(std::atomic<char*>* slots, int n, const std::string& path) {
  char* copy = Copy(path);
  for (int i = 0; i < n; ++i) {
    char* expected = nullptr;
    if (slots[i].compare_exchange_strong(expected, copy)) return i;
  }
  delete[] copy;
  return -1;
}

bool Forget(std::atomic<char*>* slots, int n, int slot) {
  if (slot < 0 || slot >= n) return false;
  // Once RemoveTempFiles has begun (a signal: the process is about to exit) the handler may be
  // reading the copy: it stays in its slot, neither freed nor lost (leak checkers still reach it).
  if (g_removing.load()) return slots[slot].load() != nullptr;
  char* copy = slots[slot].exchange(nullptr);
  if (copy == nullptr) return false;
  delete[] copy;
  return true;
}

}  // namespace

int RememberTempFile(const std::string& path) {
  const int slot = Remember(g_slots, kMaxTempFiles, path);
  if (slot >= 0) ++g_in_flight;
  return slot;
}

void ForgetTempFile(int slot) {
  if (Forget(g_slots, kMaxTempFiles, slot)) --g_in_flight;
}

int RememberTempFolder(const std::string& path) {
  return Remember(g_folders, kMaxTempFolders, path);
}

void ForgetTempFolder(int slot) { Forget(g_folders, kMaxTempFolders, slot); }

void RemoveTempFiles() {
  g_removing.store(true);
  for (std::atomic<char*>& slot : g_slots) {
    const char* path = slot.load();
    if (path != nullptr) ::unlink(path);
  }
  for (int i = kMaxTempFolders - 1; i >= 0; --i) {
    const char* path = g_folders[i].load();
    if (path != nullptr) ::rmdir(path);
  }
}

int TempFilesInFlight() { return g_in_flight.load(); }

}  // namespace voxplan
