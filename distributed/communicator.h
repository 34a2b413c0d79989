#pragma once
// What sharded fusion and the task farm need from a group of processes, as bytes: one rank's
// buffer to all, everyone's to one, everyone's to everyone, and an agreement on failure. The
// serial communicator (one rank) runs the same code paths in one process; MpiCommunicator
// (distributed/mpi_communicator.h, when MPI was found) runs them over MPI_COMM_WORLD. Every
// call is collective: all ranks make it, in the same order, from one thread each.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/status.h"

namespace voxplan {

using Bytes = std::vector<uint8_t>;

class Communicator {
 public:
  virtual ~Communicator() = default;
  virtual int rank() const = 0;
  virtual int size() const = 0;
  bool is_root() const { return rank() == 0; }

  // Root's `bytes` to every rank (resized there).
  virtual Status Broadcast(Bytes& bytes, int root) = 0;
  // Every rank's `bytes` to root, in rank order (empty elsewhere).
  virtual Result<std::vector<Bytes>> Gather(const Bytes& bytes, int root) = 0;
  // to[r] goes to rank r; returns what every rank sent this one, in rank order.
  virtual Result<std::vector<Bytes>> AllToAll(const std::vector<Bytes>& to) = 0;
  // The largest of every rank's `value` (agreeing on a flag, a count or an error).
  virtual Result<uint64_t> AllMax(uint64_t value) = 0;
  // Task farm (distributed/task_farm.h): point to point, tagged.
  virtual Status Send(const Bytes& bytes, int to, int tag) = 0;
  // From any rank when `from` < 0; sets *source and *tag to what arrived.
  virtual Result<Bytes> Receive(int from, int* source, int* tag) = 0;
  // Whether a message waits (from any rank), without blocking; sets *source and *tag.
  virtual Result<bool> Poll(int* source, int* tag) = 0;
};

// One process: broadcasts keep their bytes, gathers return their own.
class SerialCommunicator final : public Communicator {
 public:
  int rank() const override { return 0; }
  int size() const override { return 1; }
  Status Broadcast(Bytes&, int) override { return Status::Ok(); }
  Result<std::vector<Bytes>> Gather(const Bytes& bytes, int) override {
    return std::vector<Bytes>{bytes};
  }
  Result<std::vector<Bytes>> AllToAll(const std::vector<Bytes>& to) override { return to; }
  Result<uint64_t> AllMax(uint64_t value) override { return value; }
  Status Send(const Bytes&, int, int) override {
    return Unsupported("a serial run has no other rank to send to");
  }
  Result<Bytes> Receive(int, int*, int*) override {
    return Unsupported("a serial run has no other rank to receive from");
  }
  Result<bool> Poll(int*, int*) override { return false; }
};

inline constexpr int kMaxRanks = 4096;

// Agrees on a failure: every rank passes its own status; all get the first failing rank's
// code and, on the others, "rank R stopped (<kOtherRankStopped>)". A communication failure is
// returned as it is.
inline constexpr const char* kOtherRankStopped = "its message is printed with its rank";
Status AgreeOnStatus(Communicator& comm, const Status& local);

// Whether this process was started by mpirun (its environment says so), and whether this build
// has MPI at all.
bool LaunchedByMpirun();
bool MpiAvailable();
// MPI_COMM_WORLD when launched by mpirun (initialising MPI once; finalised at exit), else a
// serial communicator. Under mpirun without MPI in the build: Unsupported, saying how to fix it.
Result<std::unique_ptr<Communicator>> WorldCommunicator();

}  // namespace voxplan
