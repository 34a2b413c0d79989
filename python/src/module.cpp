// The extension module voxplan._voxplan; python/voxplan/__init__.py re-exports it as voxplan.
#include <pybind11/pybind11.h>

#include "core/parallel.h"
#include "core/raycast.h"
#include "fusion/integrate.h"
#include "python/src/objects.h"

namespace voxplan::python {
namespace {

// The limit set_threads set; never destroyed at exit (TBB may be gone by then).
ThreadLimit* thread_limit = nullptr;

void SetThreads(int threads) {
  CheckThreads(threads);
  delete thread_limit;  // first: TBB takes the smallest of the active limits
  thread_limit = nullptr;
  if (threads > 0) thread_limit = new ThreadLimit(threads);
}

}  // namespace
}  // namespace voxplan::python

PYBIND11_MODULE(_voxplan, m) {
  using namespace voxplan;
  using namespace voxplan::python;
  m.doc() =
      "voxplan: CPU voxel-hashing TSDF fusion, ray casting, meshing, dataset readers, "
      "mesh evaluation and planner-driven exploration, over numpy arrays.";
  m.attr("__version__") = VOXPLAN_VERSION;
  RegisterErrors(m);
  m.def("set_threads", &SetThreads, py::arg("threads"),
        "Caps the worker threads of every later call (0: all hardware threads), as the CLI's "
        "--threads; fuse and explore take threads= for one call.");
  m.def("get_threads", &MaxThreads, "The worker threads calls may use now.");
  m.def("simd_available", &SimdKernelAvailable,
        "Whether the AVX2 integration kernel runs on this CPU (kernel='auto' picks it then).");
  BindVolume(m);
  BindDataset(m);
  BindExplore(m);
}
