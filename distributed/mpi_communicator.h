#pragma once
// Communicator over MPI_COMM_WORLD (built when CMake finds MPI). MPI is initialised once, on
// first use, with MPI_THREAD_FUNNELED: voxplan's worker threads never call MPI, only the thread
// that created the communicator does. Messages of any size travel in chunks of at most 1 GiB
// (MPI counts are ints).
#include <memory>

#include "distributed/communicator.h"

namespace voxplan {

class MpiCommunicator final : public Communicator {
 public:
  static Result<std::unique_ptr<MpiCommunicator>> World();
  ~MpiCommunicator() override;

  int rank() const override { return rank_; }
  int size() const override { return size_; }
  Status Broadcast(Bytes& bytes, int root) override;
  Result<std::vector<Bytes>> Gather(const Bytes& bytes, int root) override;
  Result<std::vector<Bytes>> AllToAll(const std::vector<Bytes>& to) override;
  Result<uint64_t> AllMax(uint64_t value) override;
  Status Send(const Bytes& bytes, int to, int tag) override;
  Result<Bytes> Receive(int from, int* source, int* tag) override;
  Result<bool> Poll(int* source, int* tag) override;

 private:
  MpiCommunicator(int rank, int size) : rank_(rank), size_(size) {}
  int rank_ = 0, size_ = 1;
};

}  // namespace voxplan
