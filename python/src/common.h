#pragma once
// What every part of the bindings shares: Status errors as Python exceptions, numpy arrays in
// (views where the layout allows, else one documented conversion) and out (owning their memory
// or viewing an owner's), cameras and poses as numpy matrices, thread limits.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <cstdint>
#include <mutex>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/camera.h"
#include "core/image.h"
#include "core/pose.h"
#include "core/status.h"
#include "fusion/integrate_view.h"

namespace voxplan::python {

namespace py = pybind11;

// A failed Status on its way to Python: the translator registered by RegisterErrors raises it
// as the exception its code maps to, with the library's message. Throwable with the GIL
// released (the translator runs once it is held again).
class StatusError : public std::exception {
 public:
  explicit StatusError(Status status) : status_(std::move(status)) {}
  const Status& status() const { return status_; }
  const char* what() const noexcept override { return status_.message().c_str(); }

 private:
  Status status_;
};

// kInvalidArgument, kCorruptData, kUnsupported -> ValueError; kNotFound -> FileNotFoundError;
// kIoError -> OSError; kCancelled -> KeyboardInterrupt; the rest -> RuntimeError.
void RegisterErrors(py::module_& m);

inline void ThrowIfError(const Status& status) {
  if (!status.ok()) throw StatusError(status);
}
template <typename T>
T ValueOrThrow(Result<T>&& result) {
  if (!result.ok()) throw StatusError(result.status());
  return std::move(result).value();
}

// voxplan.VoxplanWarning with `message` (the GIL must be held); raises if a filter made it an
// error.
void Warn(const std::string& message);

// --- numpy in --------------------------------------------------------------------------------

// Pixels handed to IntegrateFrame: a view of the caller's array, or of `owned` when it had to
// be converted (then `copied`).
struct DepthInput {
  ImageView<float> view;
  DepthImage owned;
  bool copied = false;
  py::object keep;  // the array viewed
};
struct ColorInput {
  ImageView<uint32_t> view;
  ColorImage owned;
  bool copied = false;
  py::object keep;
};

// depth: (H, W) float32 metres, read in place when C-contiguous; any other float32 layout is
// copied; uint16 (or uint32) raw units are converted with `depth_scale` (units per metre, which
// must be given then). Other dtypes and shapes raise TypeError / ValueError naming `what`.
DepthInput DepthFromArray(const py::handle& depth, std::optional<double> depth_scale,
                          const char* what = "depth");
// color: None (no colour), (H, W, 4) uint8 RGBX or RGBA (alpha ignored) or (H, W) uint32 packed
// RGBX, read in place when C-contiguous; the (H, W, 3) views of voxplan's own RGBX buffers
// (Frame.color, RaycastImages.colors) in place too; any other (H, W, 3) uint8 is converted.
ColorInput ColorFromArray(const py::handle& color, const char* what = "color");

// K: a 3x3 matrix [[fx, 0, cx], [0, fy, cy], [0, 0, 1]] or (fx, fy, cx, cy); with the image size.
PinholeCamera CameraFromK(const py::handle& K, int width, int height);
// T_W_C: 4x4 camera-to-world, float64 (float32 is widened); refused unless rigid
// (ValidatePoseMatrix's message).
Pose3d PoseFromArray(const py::handle& T, const char* what = "T_W_C");
// (N, 3) points as float32, converted from any real dtype; ValueError for another shape.
py::array_t<float, py::array::c_style> PointsFromArray(const py::handle& points);

// --- numpy out -------------------------------------------------------------------------------

py::array_t<double> KFromCamera(const PinholeCamera& camera);
py::array_t<double> PoseToArray(const Eigen::Matrix4d& T);

// An array over `data` whose memory `base` keeps alive (a view of an owner's buffer).
template <typename T>
py::array ViewArray(const T* data, std::vector<py::ssize_t> shape,
                    std::vector<py::ssize_t> strides_bytes, py::handle base) {
  return py::array(py::dtype::of<T>(), std::move(shape), std::move(strides_bytes), data, base);
}

// An array owning `values` (moved into a capsule, no copy), with `shape` over its elements'
// scalars: Scalar is the element type of the array (float for Eigen::Vector3f, ...).
template <typename Scalar, typename V>
py::array OwnedArray(V&& values, std::vector<py::ssize_t> shape) {
  using Vec = std::decay_t<V>;
  auto* owned = new Vec(std::forward<V>(values));
  py::capsule base(owned, [](void* p) { delete static_cast<Vec*>(p); });
  const auto* data = reinterpret_cast<const Scalar*>(owned->data());
  return py::array(py::dtype::of<Scalar>(), std::move(shape), data, base);
}

// An (H, W, 3) uint8 view of packed RGBX pixels (strides 4W, 4, 1): no copy; ColorFromArray
// reads such views in place again. `base` owns the pixels.
py::array RgbxAsRgbView(const uint32_t* pixels, int width, int height, py::handle base);

// Registers an owner of RGBX buffers whose (H, W, 3) views ColorFromArray may read in place:
// `find` returns the pixels and their count when `base` is such an owner, else nullptr.
using RgbxOwnerLookup = const uint32_t* (*)(py::handle base, size_t* pixels);
void RegisterRgbxOwner(RgbxOwnerLookup find);

// Held by every binding that writes files: io's output transaction (FuseResult.write) is one
// per process, and a write on another Python thread must not stage into it.
std::mutex& WriteMutex();

// --- parameters ------------------------------------------------------------------------------

// The fuse, bench and demo commands' default memory budget: half the machine's memory (or of
// the cgroup's memory.max where that is lower), as apps/voxplan/cli_bounds.cpp computes it.
uint64_t DefaultMemoryBudgetBytes();

// `threads` (worker threads, 0: all hardware threads) within core/bounds.h's range, else
// ValueError naming `name`.
int CheckThreads(int threads, const char* name = "threads");

}  // namespace voxplan::python
