#pragma once
// The C++ objects behind voxplan's Python classes, shared by the files that bind them.
#include <memory>
#include <shared_mutex>
#include <utility>

#include "core/mesh.h"
#include "core/raycast.h"
#include "core/volume.h"
#include "fusion/integrate.h"
#include "io/world_up.h"
#include "python/src/common.h"

namespace voxplan::python {

// voxplan.Volume: the TSDF volume, the integration parameters it is fused with and the world's
// up axis its map file records. The lock lets Python threads share a volume with the GIL
// released: integrate, clear and load take it exclusively, every read shared.
struct PyVolume {
  PyVolume(TsdfVolume v, const IntegrateParams& p, WorldUp u = WorldUp::kUnknown)
      : volume(std::move(v)), integrate(p), up(u) {}
  TsdfVolume volume;
  IntegrateParams integrate;
  WorldUp up = WorldUp::kUnknown;
  mutable std::shared_mutex mutex;
};

// voxplan.Mesh.
struct PyMesh {
  Mesh mesh;
};

// voxplan.RaycastImages.
struct PyRaycast {
  RaycastImages images;
};

// The bindings of each part, called by the module in this order.
void BindVolume(py::module_& m);   // Volume, Mesh, RaycastImages, read_mesh, evaluate_mesh
void BindDataset(py::module_& m);  // Dataset, Frame, open_dataset, fuse, FuseResult
void BindExplore(py::module_& m);  // explore, ExploreResult, planners

// A Python Volume adopting `volume` (fuse's, explore's, a loaded map) and its up axis.
py::object WrapVolume(TsdfVolume volume, const IntegrateParams& params,
                      WorldUp up = WorldUp::kUnknown);
// "constant" / "depth"; "auto" / "scalar" / "simd": ValueError otherwise.
Weighting ParseWeighting(const std::string& name);
Kernel ParseKernel(const std::string& name);
const char* WeightingName(Weighting w);
const char* KernelOptionName(Kernel k);  // as ParseKernel reads it

}  // namespace voxplan::python
