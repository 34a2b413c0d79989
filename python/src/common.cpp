#include "python/src/common.h"

#include <unistd.h>

#include <algorithm>
#include <cstring>
#include <fstream>
#include <mutex>
#include <sstream>

#include "core/bounds.h"

namespace voxplan::python {

namespace {

PyObject* warning_category = nullptr;  // voxplan.VoxplanWarning, alive as long as the module

std::string ShapeText(const py::array& a) {
  std::ostringstream s;
  s << "(";
  for (py::ssize_t i = 0; i < a.ndim(); ++i) s << (i ? ", " : "") << a.shape(i);
  s << (a.ndim() == 1 ? ",)" : ")");
  return s.str();
}

std::string DtypeText(const py::array& a) { return py::str(a.dtype()).cast<std::string>(); }

[[noreturn]] void TypeError(const std::string& message) { throw py::type_error(message); }
[[noreturn]] void ValueError(const std::string& message) { throw py::value_error(message); }

// Any array-like as an ndarray (no copy for ndarrays).
py::array AsArray(const py::handle& h, const char* what) {
  if (py::isinstance<py::array>(h)) return py::reinterpret_borrow<py::array>(h);
  try {
    return py::module_::import("numpy").attr("asarray")(h).cast<py::array>();
  } catch (const py::error_already_set&) {
    TypeError(std::string(what) + " must be a numpy array");
  }
}

template <typename T>
bool Is(const py::array& a) {
  return py::isinstance<py::array_t<T>>(a);
}

bool CContiguousAligned(const py::array& a, size_t alignment) {
  return (a.flags() & py::array::c_style) && reinterpret_cast<uintptr_t>(a.data()) % alignment == 0;
}

std::vector<RgbxOwnerLookup>& RgbxOwners() {
  static std::vector<RgbxOwnerLookup> owners;
  return owners;
}

// The pixels of the RGBX buffer `a` views when its owner (the end of its base chain) is one of
// voxplan's objects and the view covers whole packed pixels inside it; else nullptr.
const uint32_t* OwnedRgbxPixels(const py::array& a, int width, int height) {
  if (a.strides(2) != 1 || a.strides(1) != 4 || a.strides(0) != py::ssize_t(4) * width)
    return nullptr;
  const auto* data = static_cast<const unsigned char*>(a.data());
  if (reinterpret_cast<uintptr_t>(data) % 4 != 0) return nullptr;
  py::handle base = a.base();
  while (base && py::isinstance<py::array>(base))
    base = py::reinterpret_borrow<py::array>(base).base();
  if (!base) return nullptr;
  for (RgbxOwnerLookup find : RgbxOwners()) {
    size_t pixels = 0;
    const uint32_t* begin = find(base, &pixels);
    if (!begin) continue;
    const auto* first = reinterpret_cast<const unsigned char*>(begin);
    const auto* last = reinterpret_cast<const unsigned char*>(begin + pixels);
    const size_t bytes = size_t(width) * size_t(height) * 4;
    if (data >= first && data + bytes <= last && (data - first) % 4 == 0)
      return reinterpret_cast<const uint32_t*>(data);
  }
  return nullptr;
}

}  // namespace

void RegisterErrors(py::module_& m) {
  warning_category =
      PyErr_NewExceptionWithDoc("voxplan.VoxplanWarning",
                                "Warnings of voxplan's readers and pipelines (frames skipped, a "
                                "depth scale that looks wrong, ...).",
                                PyExc_UserWarning, nullptr);
  m.add_object("VoxplanWarning", py::handle(warning_category));
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const StatusError& e) {
      PyObject* type = PyExc_RuntimeError;
      switch (e.status().code()) {
        case StatusCode::kInvalidArgument:
        case StatusCode::kCorruptData:
        case StatusCode::kUnsupported:
          type = PyExc_ValueError;
          break;
        case StatusCode::kNotFound:
          type = PyExc_FileNotFoundError;
          break;
        case StatusCode::kIoError:
          type = PyExc_OSError;
          break;
        case StatusCode::kCancelled:
          type = PyExc_KeyboardInterrupt;
          break;
        default:
          break;
      }
      PyErr_SetString(type, e.status().message().c_str());
    }
  });
}

void Warn(const std::string& message) {
  if (PyErr_WarnEx(warning_category ? warning_category : PyExc_UserWarning, message.c_str(), 1) < 0)
    throw py::error_already_set();
}

DepthInput DepthFromArray(const py::handle& depth, std::optional<double> depth_scale,
                          const char* what) {
  py::array a = AsArray(depth, what);
  if (a.ndim() != 2)
    ValueError(std::string(what) + " must be an (H, W) array, got shape " + ShapeText(a));
  const int height = int(a.shape(0)), width = int(a.shape(1));
  if (Status s = bounds::CheckImageSize(what, a.shape(1), a.shape(0)); !s.ok())
    ValueError(s.message());
  DepthInput in;
  if (Is<float>(a)) {
    if (depth_scale)
      ValueError(std::string(what) + " is float32 metres: depth_scale applies to integer depth");
    if (!CContiguousAligned(a, alignof(float))) {
      a = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(a);
      in.copied = true;
    }
    in.view = {static_cast<const float*>(a.data()), width, height};
    in.keep = a;
    return in;
  }
  const bool u16 = Is<uint16_t>(a);
  const bool u32 = Is<uint32_t>(a);
  if (!u16 && !u32)
    TypeError(std::string(what) + " must be float32 metres or uint16 raw units (with " +
              "depth_scale), got " + DtypeText(a));
  if (!depth_scale)
    TypeError(std::string(what) + " is " + DtypeText(a) +
              " raw units: give depth_scale (units per metre, e.g. 1000 or 5000)");
  if (Status s = bounds::CheckRange("depth_scale", *depth_scale, bounds::kDepthScaleMin,
                                    bounds::kDepthScaleMax);
      !s.ok())
    ValueError(s.message());
  // As io/image_io.cpp's ReadDepthPng converts, so the values match a decoded PNG's.
  const double inv_scale = 1.0 / *depth_scale;
  in.owned = DepthImage(width, height);
  auto convert = [&](auto tag) {
    using T = decltype(tag);
    auto u = a.unchecked<T, 2>();
    for (int v = 0; v < height; ++v)
      for (int x = 0; x < width; ++x) in.owned.at(x, v) = float(double(u(v, x)) * inv_scale);
  };
  if (u16) {
    convert(uint16_t{});
  } else {
    convert(uint32_t{});
  }
  in.view = ViewOf(in.owned);
  in.copied = true;
  return in;
}

ColorInput ColorFromArray(const py::handle& color, const char* what) {
  ColorInput in;
  if (color.is_none()) return in;
  py::array a = AsArray(color, what);
  const bool u8 = Is<uint8_t>(a);
  if (a.ndim() == 2 && Is<uint32_t>(a)) {
    if (!CContiguousAligned(a, alignof(uint32_t))) {
      a = py::array_t<uint32_t, py::array::c_style | py::array::forcecast>::ensure(a);
      in.copied = true;
    }
    in.view = {static_cast<const uint32_t*>(a.data()), int(a.shape(1)), int(a.shape(0))};
    in.keep = a;
    return in;
  }
  if (a.ndim() != 3 || (a.shape(2) != 3 && a.shape(2) != 4))
    ValueError(std::string(what) + " must be an (H, W, 3) or (H, W, 4) uint8 array, got shape " +
               ShapeText(a));
  if (!u8) TypeError(std::string(what) + " must be uint8, got " + DtypeText(a));
  const int height = int(a.shape(0)), width = int(a.shape(1));
  if (Status s = bounds::CheckImageSize(what, width, height); !s.ok()) ValueError(s.message());
  if (a.shape(2) == 4 && CContiguousAligned(a, alignof(uint32_t))) {
    in.view = {static_cast<const uint32_t*>(a.data()), width, height};
    in.keep = a;
    return in;
  }
  if (a.shape(2) == 3) {
    if (const uint32_t* pixels = OwnedRgbxPixels(a, width, height)) {
      in.view = {pixels, width, height};
      in.keep = a;
      return in;
    }
  }
  // Packed into RGBX: one pass over the pixels.
  in.owned = ColorImage(width, height);
  auto u = a.unchecked<uint8_t, 3>();
  for (int v = 0; v < height; ++v)
    for (int x = 0; x < width; ++x) in.owned.at(x, v) = PackRgb(u(v, x, 0), u(v, x, 1), u(v, x, 2));
  in.view = ViewOf(in.owned);
  in.copied = true;
  return in;
}

PinholeCamera CameraFromK(const py::handle& K, int width, int height) {
  py::array_t<double, py::array::c_style | py::array::forcecast> k;
  try {
    k = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(AsArray(K, "K"));
  } catch (const py::error_already_set&) {
    TypeError("K must be a 3x3 matrix or (fx, fy, cx, cy)");
  }
  if (!k) TypeError("K must be a 3x3 matrix or (fx, fy, cx, cy) of numbers");
  PinholeCamera camera;
  camera.width = width;
  camera.height = height;
  if (k.ndim() == 2 && k.shape(0) == 3 && k.shape(1) == 3) {
    auto m = k.unchecked<2>();
    camera.fx = float(m(0, 0));
    camera.fy = float(m(1, 1));
    camera.cx = float(m(0, 2));
    camera.cy = float(m(1, 2));
  } else if (k.ndim() == 1 && k.shape(0) == 4) {
    auto v = k.unchecked<1>();
    camera.fx = float(v(0));
    camera.fy = float(v(1));
    camera.cx = float(v(2));
    camera.cy = float(v(3));
  } else {
    ValueError("K must be a 3x3 matrix or (fx, fy, cx, cy), got shape " + ShapeText(k));
  }
  if (Status s = bounds::CheckIntrinsics(camera); !s.ok()) ValueError("K: " + s.message());
  return camera;
}

Pose3d PoseFromArray(const py::handle& T, const char* what) {
  auto t = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(AsArray(T, what));
  if (!t) TypeError(std::string(what) + " must be a 4x4 matrix of numbers");
  if (t.ndim() != 2 || t.shape(0) != 4 || t.shape(1) != 4)
    ValueError(std::string(what) + " must be a 4x4 matrix, got shape " + ShapeText(t));
  Eigen::Matrix4d m;
  auto u = t.unchecked<2>();
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) m(r, c) = u(r, c);
  if (Status s = ValidatePoseMatrix(m); !s.ok()) ValueError(std::string(what) + ": " + s.message());
  Pose3d pose = Pose3d::Identity();
  pose.matrix() = m;
  return pose;
}

py::array_t<float, py::array::c_style> PointsFromArray(const py::handle& points) {
  py::array a = AsArray(points, "points");
  if (!(a.ndim() == 2 && a.shape(1) == 3) && !(a.ndim() == 1 && a.shape(0) == 3))
    ValueError("points must be an (N, 3) array, got shape " + ShapeText(a));
  const char kind = a.dtype().kind();
  if (kind != 'f' && kind != 'i' && kind != 'u')
    TypeError("points must be real numbers, got " + DtypeText(a));
  auto f = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(a);
  if (f.ndim() == 1) f = f.reshape({py::ssize_t(1), py::ssize_t(3)});
  return f;
}

py::array_t<double> KFromCamera(const PinholeCamera& camera) {
  py::array_t<double> k({3, 3});
  auto m = k.mutable_unchecked<2>();
  const double values[3][3] = {{camera.fx, 0, camera.cx}, {0, camera.fy, camera.cy}, {0, 0, 1}};
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) m(r, c) = values[r][c];
  return k;
}

py::array_t<double> PoseToArray(const Eigen::Matrix4d& T) {
  py::array_t<double> out({4, 4});
  auto m = out.mutable_unchecked<2>();
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) m(r, c) = T(r, c);
  return out;
}

py::array RgbxAsRgbView(const uint32_t* pixels, int width, int height, py::handle base) {
  return ViewArray(reinterpret_cast<const uint8_t*>(pixels), {height, width, 3},
                   {py::ssize_t(4) * width, 4, 1}, base);
}

void RegisterRgbxOwner(RgbxOwnerLookup find) { RgbxOwners().push_back(find); }

std::mutex& WriteMutex() {
  static std::mutex mutex;
  return mutex;
}

uint64_t DefaultMemoryBudgetBytes() {
  const long pages = ::sysconf(_SC_PHYS_PAGES), page = ::sysconf(_SC_PAGESIZE);
  uint64_t total = pages > 0 && page > 0 ? uint64_t(pages) * uint64_t(page) : uint64_t(8) << 30;
  std::ifstream cgroup("/sys/fs/cgroup/memory.max");
  uint64_t limit = 0;
  if (cgroup >> limit && limit > 0) total = std::min(total, limit);
  return std::clamp(total / 2, bounds::kMemoryMinBytes, bounds::kMemoryMaxBytes);
}

int CheckThreads(int threads, const char* name) {
  if (Status s = bounds::CheckRange(name, threads, 0, bounds::kThreadsMax); !s.ok())
    ValueError(s.message());
  return threads;
}

}  // namespace voxplan::python
