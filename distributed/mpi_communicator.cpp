#include "distributed/mpi_communicator.h"

#include <mpi.h>

#include <algorithm>
#include <cstdlib>

namespace voxplan {

namespace {

constexpr size_t kChunkBytes = size_t(1) << 30;
constexpr int kInternalTag = 32000;  // below MPI's guaranteed tag upper bound (32767)

Status Check(int rc, const char* what) {
  if (rc == MPI_SUCCESS) return Status::Ok();
  char text[MPI_MAX_ERROR_STRING];
  int len = 0;
  MPI_Error_string(rc, text, &len);
  return IoError(std::string("MPI ") + what + " failed: " + std::string(text, size_t(len)));
}

// Sends or receives `n` bytes at `data` in chunks, as one logical message.
Status SendChunks(const uint8_t* data, size_t n, int to, int tag) {
  for (size_t off = 0; off < n; off += kChunkBytes) {
    const int count = int(std::min(kChunkBytes, n - off));
    VOXPLAN_RETURN_IF_ERROR(
        Check(MPI_Send(data + off, count, MPI_BYTE, to, tag, MPI_COMM_WORLD), "send"));
  }
  return Status::Ok();
}
Status ReceiveChunks(uint8_t* data, size_t n, int from, int tag) {
  for (size_t off = 0; off < n; off += kChunkBytes) {
    const int count = int(std::min(kChunkBytes, n - off));
    VOXPLAN_RETURN_IF_ERROR(
        Check(MPI_Recv(data + off, count, MPI_BYTE, from, tag, MPI_COMM_WORLD, MPI_STATUS_IGNORE),
              "receive"));
  }
  return Status::Ok();
}

// Finalises MPI at exit when this process initialised it.
void FinalizeAtExit() {
  int finalized = 0;
  MPI_Finalized(&finalized);
  if (!finalized) MPI_Finalize();
}

}  // namespace

Result<std::unique_ptr<MpiCommunicator>> MpiCommunicator::World() {
  int initialized = 0;
  MPI_Initialized(&initialized);
  if (!initialized) {
    int provided = 0;
    VOXPLAN_RETURN_IF_ERROR(
        Check(MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided), "init"));
    std::atexit(FinalizeAtExit);
    // Errors come back as codes, turned into Status here, instead of aborting every rank.
    MPI_Comm_set_errhandler(MPI_COMM_WORLD, MPI_ERRORS_RETURN);
  }
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  if (size > kMaxRanks)
    return InvalidArgument("at most " + std::to_string(kMaxRanks) + " ranks, got " +
                           std::to_string(size));
  return std::unique_ptr<MpiCommunicator>(new MpiCommunicator(rank, size));
}

MpiCommunicator::~MpiCommunicator() = default;

Status MpiCommunicator::Broadcast(Bytes& bytes, int root) {
  uint64_t n = bytes.size();
  VOXPLAN_RETURN_IF_ERROR(Check(MPI_Bcast(&n, 1, MPI_UINT64_T, root, MPI_COMM_WORLD), "bcast"));
  if (rank_ != root) bytes.resize(size_t(n));
  for (size_t off = 0; off < n; off += kChunkBytes) {
    const int count = int(std::min<uint64_t>(kChunkBytes, n - off));
    VOXPLAN_RETURN_IF_ERROR(
        Check(MPI_Bcast(bytes.data() + off, count, MPI_BYTE, root, MPI_COMM_WORLD), "bcast"));
  }
  return Status::Ok();
}

Result<std::vector<Bytes>> MpiCommunicator::Gather(const Bytes& bytes, int root) {
  uint64_t n = bytes.size();
  std::vector<uint64_t> sizes(static_cast<size_t>(size_), 0);
  VOXPLAN_RETURN_IF_ERROR(
      Check(MPI_Gather(&n, 1, MPI_UINT64_T, sizes.data(), 1, MPI_UINT64_T, root, MPI_COMM_WORLD),
            "gather"));
  std::vector<Bytes> out;
  if (rank_ != root) {
    VOXPLAN_RETURN_IF_ERROR(SendChunks(bytes.data(), bytes.size(), root, kInternalTag));
    return out;
  }
  out.resize(static_cast<size_t>(size_));
  for (int r = 0; r < size_; ++r) {
    if (r == root) {
      out[size_t(r)] = bytes;
      continue;
    }
    out[size_t(r)].resize(size_t(sizes[size_t(r)]));
    VOXPLAN_RETURN_IF_ERROR(
        ReceiveChunks(out[size_t(r)].data(), out[size_t(r)].size(), r, kInternalTag));
  }
  return out;
}

Result<std::vector<Bytes>> MpiCommunicator::AllToAll(const std::vector<Bytes>& to) {
  if (int(to.size()) != size_) return InvalidArgument("AllToAll needs one buffer per rank");
  std::vector<uint64_t> send_sizes(static_cast<size_t>(size_)),
      recv_sizes(static_cast<size_t>(size_));
  for (int r = 0; r < size_; ++r) send_sizes[size_t(r)] = to[size_t(r)].size();
  VOXPLAN_RETURN_IF_ERROR(Check(MPI_Alltoall(send_sizes.data(), 1, MPI_UINT64_T, recv_sizes.data(),
                                             1, MPI_UINT64_T, MPI_COMM_WORLD),
                                "alltoall"));
  std::vector<Bytes> from(static_cast<size_t>(size_));
  from[size_t(rank_)] = to[size_t(rank_)];
  // Non-blocking, so that no pair of ranks waits on each other's send.
  std::vector<MPI_Request> requests;
  for (int r = 0; r < size_; ++r) {
    if (r == rank_) continue;
    from[size_t(r)].resize(size_t(recv_sizes[size_t(r)]));
    for (size_t off = 0; off < from[size_t(r)].size(); off += kChunkBytes) {
      requests.emplace_back();
      const int count = int(std::min(kChunkBytes, from[size_t(r)].size() - off));
      VOXPLAN_RETURN_IF_ERROR(Check(MPI_Irecv(from[size_t(r)].data() + off, count, MPI_BYTE, r,
                                              kInternalTag, MPI_COMM_WORLD, &requests.back()),
                                    "irecv"));
    }
  }
  for (int r = 0; r < size_; ++r) {
    if (r == rank_) continue;
    const Bytes& b = to[size_t(r)];
    for (size_t off = 0; off < b.size(); off += kChunkBytes) {
      requests.emplace_back();
      const int count = int(std::min(kChunkBytes, b.size() - off));
      VOXPLAN_RETURN_IF_ERROR(Check(MPI_Isend(b.data() + off, count, MPI_BYTE, r, kInternalTag,
                                              MPI_COMM_WORLD, &requests.back()),
                                    "isend"));
    }
  }
  VOXPLAN_RETURN_IF_ERROR(
      Check(MPI_Waitall(int(requests.size()), requests.data(), MPI_STATUSES_IGNORE), "waitall"));
  return from;
}

Result<uint64_t> MpiCommunicator::AllMax(uint64_t value) {
  uint64_t out = 0;
  VOXPLAN_RETURN_IF_ERROR(
      Check(MPI_Allreduce(&value, &out, 1, MPI_UINT64_T, MPI_MAX, MPI_COMM_WORLD), "allreduce"));
  return out;
}

Status MpiCommunicator::Send(const Bytes& bytes, int to, int tag) {
  uint64_t n = bytes.size();
  VOXPLAN_RETURN_IF_ERROR(Check(MPI_Send(&n, 1, MPI_UINT64_T, to, tag, MPI_COMM_WORLD), "send"));
  return SendChunks(bytes.data(), bytes.size(), to, tag);
}

Result<Bytes> MpiCommunicator::Receive(int from, int* source, int* tag) {
  uint64_t n = 0;
  MPI_Status st;
  VOXPLAN_RETURN_IF_ERROR(Check(MPI_Recv(&n, 1, MPI_UINT64_T, from < 0 ? MPI_ANY_SOURCE : from,
                                         MPI_ANY_TAG, MPI_COMM_WORLD, &st),
                                "receive"));
  if (source) *source = st.MPI_SOURCE;
  if (tag) *tag = st.MPI_TAG;
  Bytes bytes(static_cast<size_t>(n));
  VOXPLAN_RETURN_IF_ERROR(ReceiveChunks(bytes.data(), bytes.size(), st.MPI_SOURCE, st.MPI_TAG));
  return bytes;
}

Result<bool> MpiCommunicator::Poll(int* source, int* tag) {
  int flag = 0;
  MPI_Status st;
  VOXPLAN_RETURN_IF_ERROR(
      Check(MPI_Iprobe(MPI_ANY_SOURCE, MPI_ANY_TAG, MPI_COMM_WORLD, &flag, &st), "iprobe"));
  if (flag) {
    if (source) *source = st.MPI_SOURCE;
    if (tag) *tag = st.MPI_TAG;
  }
  return flag != 0;
}

}  // namespace voxplan
