#include "distributed/communicator.h"

#include <cstdlib>

#if VOXPLAN_HAVE_MPI
#include "distributed/mpi_communicator.h"
#endif

namespace voxplan {

Status AgreeOnStatus(Communicator& comm, const Status& local) {
  // The lowest failing rank wins, so every rank names the same one: encode (rank, code) so that
  // the maximum picks the lowest rank with a failure.
  const uint64_t mine =
      local.ok() ? 0 : (uint64_t(kMaxRanks - comm.rank()) << 8) | uint64_t(local.code());
  Result<uint64_t> agreed = comm.AllMax(mine);
  if (!agreed.ok()) return agreed.status();
  if (*agreed == 0) return Status::Ok();
  if (!local.ok() && *agreed == mine) return local;
  const int failed_rank = int(kMaxRanks - (*agreed >> 8));
  return Status(StatusCode(*agreed & 0xff),
                "rank " + std::to_string(failed_rank) + " stopped (" + kOtherRankStopped + ")");
}

bool LaunchedByMpirun() {
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_RANK"})
    if (std::getenv(name)) return true;
  return false;
}

bool MpiAvailable() { return VOXPLAN_HAVE_MPI != 0; }

Result<std::unique_ptr<Communicator>> WorldCommunicator() {
  if (!LaunchedByMpirun()) return std::unique_ptr<Communicator>(new SerialCommunicator());
#if VOXPLAN_HAVE_MPI
  Result<std::unique_ptr<MpiCommunicator>> mpi = MpiCommunicator::World();
  if (!mpi.ok()) return mpi.status();
  return std::unique_ptr<Communicator>(std::move(*mpi));
#else
  return Unsupported(
      "this voxplan was built without MPI, but runs under mpirun: reinstall with "
      "scripts/setup-deps (libopenmpi-dev) and rebuild, or run it without mpirun");
#endif
}

}  // namespace voxplan
