// voxplan.Volume (integrate, extract_mesh, raycast, point queries, save / load), voxplan.Mesh,
// voxplan.RaycastImages, read_mesh and evaluate_mesh.
#include <pybind11/stl.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <mutex>
#include <sstream>
#include <string>

#include "core/bounds.h"
#include "core/parallel.h"
#include "core/queries.h"
#include "core/stopwatch.h"
#include "eval/eval_mesh.h"
#include "fusion/mesh_extract.h"
#include "io/map_io.h"
#include "io/mesh_io.h"
#include "io/sharded_map.h"
#include "python/src/objects.h"

namespace voxplan::python {

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

std::string PathString(const py::handle& path) {
  return py::str(py::module_::import("os").attr("fspath")(path)).cast<std::string>();
}

IntegrateParams MakeIntegrateParams(float min_depth, float max_depth, float max_weight,
                                    const std::string& weighting, const std::string& kernel,
                                    bool integrate_color) {
  IntegrateParams p;
  p.min_depth_m = min_depth;
  p.max_depth_m = max_depth;
  p.max_weight = max_weight;
  p.weighting = ParseWeighting(weighting);
  p.kernel = ParseKernel(kernel);
  p.integrate_color = integrate_color;
  ThrowIfError(p.Validate());
  return p;
}

std::unique_ptr<PyVolume> NewVolume(float voxel_size, float trunc, uint64_t max_memory,
                                    const IntegrateParams& params) {
  const VolumeParams vp{voxel_size, trunc, max_memory};
  ThrowIfError(vp.Validate());
  return std::make_unique<PyVolume>(TsdfVolume(vp), params);
}

py::dict StatsDict(const IntegrateStats& s, const DepthInput& depth, const ColorInput& color) {
  py::dict d;
  d["blocks_in_band"] = s.blocks_in_band;
  d["blocks_allocated"] = s.blocks_allocated;
  d["blocks_refused"] = s.blocks_refused;
  d["valid_pixels"] = s.valid_pixels;
  d["allocate_ms"] = s.allocate_ms;
  d["update_ms"] = s.update_ms;
  d["depth_copied"] = depth.copied;
  d["color_copied"] = color.copied;
  return d;
}

// Fills per-point outputs in parallel with the GIL released and the volume shared-locked.
template <typename F>
void ForEachPoint(const PyVolume& v, const py::array_t<float, py::array::c_style>& points, F&& f) {
  const size_t n = size_t(points.shape(0));
  const float* p = points.data();
  py::gil_scoped_release release;
  std::shared_lock lock(v.mutex);
  ParallelFor(n, 4096, [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i)
      f(i, Eigen::Vector3f(p[3 * i], p[3 * i + 1], p[3 * i + 2]));
  });
}

py::dict ValuesDict(const PyVolume& v, const py::handle& points_in, bool interpolate,
                    float min_weight) {
  const auto points = PointsFromArray(points_in);
  const py::ssize_t n = points.shape(0);
  py::array_t<float> tsdf(n), weight(n), rgb({n, py::ssize_t(3)});
  float *t = tsdf.mutable_data(), *w = weight.mutable_data(), *c = rgb.mutable_data();
  ForEachPoint(v, points, [&](size_t i, const Eigen::Vector3f& p) {
    const std::optional<VoxelValue> value =
        interpolate ? Interpolate(v.volume, p, min_weight) : VoxelAtPoint(v.volume, p);
    t[i] = value ? value->tsdf_m : kNaN;
    w[i] = value ? value->weight : 0.f;
    for (int k = 0; k < 3; ++k) c[3 * i + size_t(k)] = value ? value->rgb[k] : kNaN;
  });
  py::dict d;
  d["tsdf"] = tsdf;
  d["weight"] = weight;
  d["color"] = rgb;
  return d;
}

py::array MeshVertices(const py::object& self) {
  Mesh& m = self.cast<PyMesh&>().mesh;
  return ViewArray(reinterpret_cast<const float*>(m.positions.data()),
                   {py::ssize_t(m.positions.size()), 3}, {sizeof(Eigen::Vector3f), sizeof(float)},
                   self);
}

std::vector<Eigen::Vector3f> Vector3fs(const py::array_t<float, py::array::c_style>& a) {
  std::vector<Eigen::Vector3f> out(size_t(a.shape(0)));
  const float* p = a.data();
  for (size_t i = 0; i < out.size(); ++i) out[i] = {p[3 * i], p[3 * i + 1], p[3 * i + 2]};
  return out;
}

std::unique_ptr<PyMesh> MeshFromArrays(const py::handle& vertices, const py::handle& triangles,
                                       const py::handle& colors, const py::handle& normals) {
  auto out = std::make_unique<PyMesh>();
  Mesh& mesh = out->mesh;
  const auto v = PointsFromArray(vertices);
  mesh.positions = Vector3fs(v);
  auto t = py::array::ensure(triangles);
  if (!t || t.ndim() != 2 || t.shape(1) != 3 ||
      (t.dtype().kind() != 'i' && t.dtype().kind() != 'u'))
    throw py::value_error("triangles must be an (M, 3) integer array");
  auto ti = py::array_t<int64_t, py::array::c_style | py::array::forcecast>::ensure(t);
  mesh.triangles.resize(size_t(ti.shape(0)));
  const int64_t* tp = ti.data();
  for (size_t i = 0; i < mesh.triangles.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      const int64_t index = tp[3 * i + size_t(k)];
      if (index < 0 || uint64_t(index) >= mesh.positions.size())
        throw py::value_error("triangle " + std::to_string(i) + " has vertex index " +
                              std::to_string(index) + ", out of range for " +
                              std::to_string(mesh.positions.size()) + " vertices");
      mesh.triangles[i][size_t(k)] = uint32_t(index);
    }
  }
  if (!colors.is_none()) {
    auto c = py::array_t<uint8_t, py::array::c_style | py::array::forcecast>::ensure(colors);
    if (!c || c.ndim() != 2 || c.shape(1) != 3 || size_t(c.shape(0)) != mesh.positions.size())
      throw py::value_error("colors must be an (N, 3) uint8 array, one row per vertex");
    mesh.colors.resize(mesh.positions.size());
    std::memcpy(mesh.colors.data(), c.data(), mesh.colors.size() * 3);
  }
  if (!normals.is_none()) {
    const auto nrm = PointsFromArray(normals);
    if (size_t(nrm.shape(0)) != mesh.positions.size())
      throw py::value_error("normals must be an (N, 3) array, one row per vertex");
    mesh.normals = Vector3fs(nrm);
  }
  return out;
}

// A Mesh object or a mesh file (read as `voxplan eval mesh` reads it).
Mesh MeshArgument(const py::handle& h, const MeshReadOptions& options) {
  if (py::isinstance<PyMesh>(h)) return h.cast<const PyMesh&>().mesh;
  const std::string path = PathString(h);
  py::gil_scoped_release release;
  return ValueOrThrow(ReadMesh(path, options));
}

UpAxis ParseUp(const std::string& up) {
  if (up == "z") return UpAxis::kZ;
  if (up == "y") return UpAxis::kY;
  throw py::value_error("up must be 'z' or 'y', got '" + up + "'");
}

const uint32_t* RaycastRgbx(py::handle base, size_t* pixels) {
  if (!py::isinstance<PyRaycast>(base)) return nullptr;
  const ColorImage& c = base.cast<const PyRaycast&>().images.color;
  *pixels = c.data.size();
  return c.data.data();
}

}  // namespace

Weighting ParseWeighting(const std::string& name) {
  if (name == "constant") return Weighting::kConstant;
  if (name == "depth") return Weighting::kDepthDependent;
  throw py::value_error("weighting must be 'constant' or 'depth' (1/z^2), got '" + name + "'");
}

Kernel ParseKernel(const std::string& name) {
  if (name == "auto") return Kernel::kAuto;
  if (name == "scalar") return Kernel::kScalar;
  if (name == "simd") return Kernel::kSimd;
  throw py::value_error("kernel must be 'auto', 'scalar' or 'simd', got '" + name + "'");
}

const char* KernelOptionName(Kernel k) {
  return k == Kernel::kScalar ? "scalar" : k == Kernel::kSimd ? "simd" : "auto";
}

const char* WeightingName(Weighting w) {
  return w == Weighting::kDepthDependent ? "depth" : "constant";
}

py::object WrapVolume(TsdfVolume volume, const IntegrateParams& params, WorldUp up) {
  return py::cast(std::make_unique<PyVolume>(std::move(volume), params, up));
}

void BindVolume(py::module_& m) {
  RegisterRgbxOwner(&RaycastRgbx);

  py::class_<PyMesh>(m, "Mesh", R"doc(
A triangle mesh: vertices (N, 3) float32 metres, triangles (M, 3) uint32 (counter-clockwise seen
from outside), per-vertex colors (N, 3) uint8 and unit normals (N, 3) float32, either None when
absent. The arrays are views of the mesh's own memory (no copy): they keep the mesh alive, and
writing into them changes it.
)doc")
      .def(py::init(&MeshFromArrays), py::arg("vertices"), py::arg("triangles"),
           py::arg("colors") = py::none(), py::arg("normals") = py::none(),
           "A mesh from arrays (copied): vertices (N, 3), triangles (M, 3) integer indices, "
           "optional colors (N, 3) uint8 and normals (N, 3).")
      .def_property_readonly("vertices", &MeshVertices, "(N, 3) float32 vertex positions")
      .def_property_readonly(
          "triangles",
          [](const py::object& self) {
            Mesh& mesh = self.cast<PyMesh&>().mesh;
            return ViewArray(reinterpret_cast<const uint32_t*>(mesh.triangles.data()),
                             {py::ssize_t(mesh.triangles.size()), 3}, {12, 4}, self);
          },
          "(M, 3) uint32 vertex indices")
      .def_property_readonly(
          "colors",
          [](const py::object& self) -> py::object {
            Mesh& mesh = self.cast<PyMesh&>().mesh;
            if (mesh.colors.empty()) return py::none();
            return ViewArray(reinterpret_cast<const uint8_t*>(mesh.colors.data()),
                             {py::ssize_t(mesh.colors.size()), 3}, {3, 1}, self);
          },
          "(N, 3) uint8 RGB per vertex, or None")
      .def_property_readonly(
          "normals",
          [](const py::object& self) -> py::object {
            Mesh& mesh = self.cast<PyMesh&>().mesh;
            if (mesh.normals.empty()) return py::none();
            return ViewArray(reinterpret_cast<const float*>(mesh.normals.data()),
                             {py::ssize_t(mesh.normals.size()), 3}, {12, 4}, self);
          },
          "(N, 3) float32 unit normals per vertex, or None")
      .def_property_readonly("num_vertices", [](const PyMesh& s) { return s.mesh.num_vertices(); })
      .def_property_readonly("num_triangles",
                             [](const PyMesh& s) { return s.mesh.num_triangles(); })
      .def(
          "save",
          [](const PyMesh& self, const py::object& path) {
            const std::string p = PathString(path);
            py::gil_scoped_release release;
            std::lock_guard write_lock(WriteMutex());
            ThrowIfError(WriteMesh(self.mesh, p));
          },
          py::arg("path"),
          "Writes the mesh by extension: .ply (binary, coloured), .obj, .glb, .stl; through a "
          "temporary file renamed into place, as `voxplan fuse --mesh` writes it.")
      .def("__repr__", [](const PyMesh& s) {
        return "<voxplan.Mesh " + std::to_string(s.mesh.num_vertices()) + " vertices, " +
               std::to_string(s.mesh.num_triangles()) + " triangles>";
      });

  py::class_<PyRaycast>(m, "RaycastImages", R"doc(
What Volume.raycast sees per pixel, as arrays viewing the images' own memory (no copy):
depth (H, W) float32 metres along the optical axis (0 where no surface was hit), vertices and
normals (H, W, 3) float32 in world coordinates (NaN where no hit), colors (H, W, 3) uint8 (a view
of packed RGBX pixels, strides (4W, 4, 1); 0 where no hit), status (H, W) uint8
(voxplan.RAY_UNOBSERVED, RAY_HIT, RAY_FREE).
)doc")
      .def_property_readonly(
          "depth",
          [](const py::object& self) {
            const DepthImage& d = self.cast<PyRaycast&>().images.depth;
            return ViewArray(d.data.data(), {d.height, d.width},
                             {py::ssize_t(sizeof(float)) * d.width, sizeof(float)}, self);
          },
          "(H, W) float32 depth in metres, 0 where no surface was hit")
      .def_property_readonly(
          "vertices",
          [](const py::object& self) {
            const auto& v = self.cast<PyRaycast&>().images.vertex_W;
            return ViewArray(reinterpret_cast<const float*>(v.data.data()), {v.height, v.width, 3},
                             {py::ssize_t(12) * v.width, 12, 4}, self);
          },
          "(H, W, 3) float32 hit points in world coordinates, NaN where no hit")
      .def_property_readonly(
          "normals",
          [](const py::object& self) {
            const auto& v = self.cast<PyRaycast&>().images.normal_W;
            return ViewArray(reinterpret_cast<const float*>(v.data.data()), {v.height, v.width, 3},
                             {py::ssize_t(12) * v.width, 12, 4}, self);
          },
          "(H, W, 3) float32 unit outward normals in world coordinates, NaN where no hit")
      .def_property_readonly(
          "colors",
          [](const py::object& self) {
            const ColorImage& c = self.cast<PyRaycast&>().images.color;
            return RgbxAsRgbView(c.data.data(), c.width, c.height, self);
          },
          "(H, W, 3) uint8 interpolated voxel colour (a view of RGBX pixels), 0 where no hit")
      .def_property_readonly(
          "status",
          [](const py::object& self) {
            const auto& s = self.cast<PyRaycast&>().images.status;
            return ViewArray(s.data.data(), {s.height, s.width}, {py::ssize_t(s.width), 1}, self);
          },
          "(H, W) uint8 ray status: RAY_UNOBSERVED, RAY_HIT or RAY_FREE");
  m.attr("RAY_UNOBSERVED") = int(RayStatus::kUnobserved);
  m.attr("RAY_HIT") = int(RayStatus::kHit);
  m.attr("RAY_FREE") = int(RayStatus::kFree);
  m.attr("UNOBSERVED") = int(VoxelState::kUnobserved);
  m.attr("FREE") = int(VoxelState::kFree);
  m.attr("OCCUPIED") = int(VoxelState::kOccupied);

  py::class_<PyVolume>(m, "Volume", R"doc(
A sparse TSDF volume of 8^3 voxel blocks (voxel hashing) and the parameters frames are fused
with. Methods that do real work (integrate, extract_mesh, raycast, the point queries, save)
release the GIL; a volume may be shared by Python threads (integrate takes it exclusively).
)doc")
      .def(py::init([](float voxel_size, float trunc, float min_depth, float max_depth,
                       float max_weight, const std::string& weighting, const std::string& kernel,
                       bool integrate_color, uint64_t max_memory) {
             return NewVolume(voxel_size, trunc, max_memory,
                              MakeIntegrateParams(min_depth, max_depth, max_weight, weighting,
                                                  kernel, integrate_color));
           }),
           py::arg("voxel_size") = 0.01f, py::arg("trunc") = 0.04f, py::kw_only(),
           py::arg("min_depth") = 0.1f, py::arg("max_depth") = 3.0f, py::arg("max_weight") = 64.0f,
           py::arg("weighting") = "constant", py::arg("kernel") = "auto",
           py::arg("integrate_color") = true, py::arg("max_memory") = 0, R"doc(
voxel_size, trunc: voxel edge and truncation distance in metres (trunc 1 to 64 voxels).
min_depth, max_depth: depth range fused, metres. max_weight: per-voxel weight cap.
weighting: 'constant' or 'depth' (1/z^2). kernel: 'auto' (AVX2 where the CPU has it), 'scalar'
or 'simd'. integrate_color: fuse colour when a frame has it. max_memory: budget of the map in
bytes (0: none); past it no new blocks are allocated (counted in blocks_refused).
The defaults are `voxplan fuse`'s.)doc")
      .def_property_readonly("voxel_size",
                             [](const PyVolume& v) { return v.volume.voxel_size_m(); })
      .def_property_readonly("trunc", [](const PyVolume& v) { return v.volume.trunc_m(); })
      .def_property(
          "up", [](const PyVolume& v) { return std::string(WorldUpName(v.up)); },
          [](PyVolume& v, const std::string& up) { v.up = ValueOrThrow(ParseWorldUp(up)); },
          "The world's up axis the map file records: 'unknown' (read as +z), '+x', '-x', '+y', "
          "'-y', '+z' or '-z' ('x', 'y', 'z' are accepted). fuse() sets it from the dataset "
          "(Dataset.up), load() from the file; `voxplan render` orbits about it.")
      .def_property_readonly("max_memory",
                             [](const PyVolume& v) { return v.volume.params().max_memory_bytes; })
      .def_property(
          "min_depth", [](const PyVolume& v) { return v.integrate.min_depth_m; },
          [](PyVolume& v, float x) { v.integrate.min_depth_m = x; }, "fused depth range, metres")
      .def_property(
          "max_depth", [](const PyVolume& v) { return v.integrate.max_depth_m; },
          [](PyVolume& v, float x) { v.integrate.max_depth_m = x; })
      .def_property(
          "max_weight", [](const PyVolume& v) { return v.integrate.max_weight; },
          [](PyVolume& v, float x) { v.integrate.max_weight = x; })
      .def_property(
          "weighting", [](const PyVolume& v) { return WeightingName(v.integrate.weighting); },
          [](PyVolume& v, const std::string& w) { v.integrate.weighting = ParseWeighting(w); })
      .def_property(
          "kernel", [](const PyVolume& v) { return KernelOptionName(v.integrate.kernel); },
          [](PyVolume& v, const std::string& k) { v.integrate.kernel = ParseKernel(k); })
      .def_property(
          "integrate_color", [](const PyVolume& v) { return v.integrate.integrate_color; },
          [](PyVolume& v, bool c) { v.integrate.integrate_color = c; })
      .def_property_readonly("num_blocks",
                             [](const PyVolume& v) {
                               std::shared_lock lock(v.mutex);
                               return v.volume.num_blocks();
                             })
      .def_property_readonly("num_voxels",
                             [](const PyVolume& v) {
                               std::shared_lock lock(v.mutex);
                               return v.volume.num_voxels();
                             })
      .def_property_readonly(
          "memory_bytes",
          [](const PyVolume& v) {
            std::shared_lock lock(v.mutex);
            return v.volume.MemoryBytes();
          },
          "bytes the map holds (pool chunks and hash table)")
      .def_property_readonly(
          "blocks_refused", [](const PyVolume& v) { return v.volume.blocks_refused(); },
          "new blocks the memory budget refused so far")
      .def(
          "integrate",
          [](PyVolume& self, const py::handle& depth, const py::handle& color, const py::handle& K,
             const py::handle& T_W_C, std::optional<double> depth_scale) {
            DepthInput d = DepthFromArray(depth, depth_scale);
            ColorInput c = ColorFromArray(color);
            const PinholeCamera camera = CameraFromK(K, d.view.width, d.view.height);
            // As the pipeline does (pipeline/fuse_dataset.cpp): a double pose cast to float.
            const Pose3f pose(PoseFromArray(T_W_C).cast<float>());
            IntegrateStats stats;
            {
              py::gil_scoped_release release;
              std::unique_lock lock(self.mutex);
              stats = ValueOrThrow(
                  IntegrateFrame(d.view, c.view, camera, pose, self.integrate, self.volume));
            }
            return StatsDict(stats, d, c);
          },
          py::arg("depth"), py::arg("color"), py::arg("K"), py::arg("T_W_C"), py::kw_only(),
          py::arg("depth_scale") = py::none(), R"doc(
Fuses one RGB-D frame.

depth: (H, W) float32 metres (0 = invalid), read in place when C-contiguous (other float32
layouts are copied first); or uint16 raw units with depth_scale (units per metre), converted.
color: None, (H, W, 4) uint8 RGBX/RGBA or (H, W) uint32 packed RGBX, read in place when
C-contiguous; (H, W, 3) uint8 is packed into RGBX (a copy) unless it is one of voxplan's own
colour views (Frame.color, RaycastImages.colors), which are read in place.
K: 3x3 intrinsics (fy may be negative) or (fx, fy, cx, cy). T_W_C: 4x4 camera-to-world
(OpenCV axes: x right, y down, z forward), rigid.
Returns the frame's stats: blocks_in_band, blocks_allocated, blocks_refused, valid_pixels,
allocate_ms, update_ms, depth_copied, color_copied. Raises ValueError with the library's message
for bad parameters, sizes and poses, TypeError for wrong dtypes.)doc")
      .def(
          "extract_mesh",
          [](const PyVolume& self, float min_weight, bool with_color) {
            auto out = std::make_unique<PyMesh>();
            {
              py::gil_scoped_release release;
              std::shared_lock lock(self.mutex);
              out->mesh = ExtractMesh(self.volume, MeshParams{min_weight, with_color});
            }
            return out;
          },
          py::arg("min_weight") = 0.5f, py::arg("with_color") = true,
          "Marching cubes over the volume (parallel, deterministic): voxels with less weight "
          "than min_weight count as unobserved. The same mesh as `voxplan fuse --mesh` / "
          "`voxplan mesh` give.")
      .def(
          "raycast",
          [](const PyVolume& self, const py::handle& K, const py::handle& T_W_C, int width,
             int height, float min_depth, float max_depth, float min_weight,
             bool stop_at_back_faces, bool with_color, bool with_normals) {
            if (Status s = bounds::CheckImageSize("raycast image", width, height); !s.ok())
              throw py::value_error(s.message());
            const PinholeCamera camera = CameraFromK(K, width, height);
            const Pose3f pose(PoseFromArray(T_W_C).cast<float>());
            RaycastParams params;
            params.min_depth_m = min_depth;
            params.max_depth_m = max_depth;
            params.min_weight = min_weight;
            params.stop_at_back_faces = stop_at_back_faces;
            params.with_color = with_color;
            params.with_normals = with_normals;
            if (!(min_depth >= 0.f && min_depth < max_depth && max_depth <= bounds::kDepthMaxM))
              throw py::value_error(
                  "raycast depth range must satisfy 0 <= min_depth < max_depth "
                  "<= " +
                  std::to_string(int(bounds::kDepthMaxM)) + " m");
            auto out = std::make_unique<PyRaycast>();
            py::gil_scoped_release release;
            std::shared_lock lock(self.mutex);
            Raycast(self.volume, camera, pose, params, out->images);
            return out;
          },
          py::arg("K"), py::arg("T_W_C"), py::arg("width"), py::arg("height"), py::kw_only(),
          py::arg("min_depth") = 0.1f, py::arg("max_depth") = 5.0f, py::arg("min_weight") = 0.5f,
          py::arg("stop_at_back_faces") = true, py::arg("with_color") = true,
          py::arg("with_normals") = true, R"doc(
Ray casts the volume from a camera (K as for integrate, image width x height, T_W_C
camera-to-world): depth, vertices, normals, colours and ray status per pixel, as
RaycastImages. stop_at_back_faces=False marches on through surfaces seen from behind (a room
seen from outside).)doc")
      .def(
          "interpolate",
          [](const PyVolume& self, const py::handle& points, float min_weight) {
            return ValuesDict(self, points, true, min_weight);
          },
          py::arg("points"), py::arg("min_weight") = 1e-3f,
          "Trilinear TSDF, weight and colour at (N, 3) world points: a dict of tsdf (N,) metres, "
          "weight (N,), color (N, 3) float 0..255; NaN (weight 0) unless all 8 surrounding "
          "voxels are observed with at least min_weight.")
      .def(
          "voxel_values",
          [](const PyVolume& self, const py::handle& points) {
            return ValuesDict(self, points, false, 0.f);
          },
          py::arg("points"),
          "The stored voxel containing each (N, 3) world point: a dict of tsdf (N,) metres, "
          "weight (N,), color (N, 3); NaN (weight 0) where its block is not allocated.")
      .def(
          "tsdf",
          [](const PyVolume& self, const py::handle& points, float min_weight) {
            const py::dict values = ValuesDict(self, points, true, min_weight);
            return py::object(values["tsdf"]);
          },
          py::arg("points"), py::arg("min_weight") = 1e-3f,
          "Interpolated signed distance (metres, truncated) at (N, 3) world points; NaN where "
          "not observed. Positive in front of surfaces, negative behind.")
      .def(
          "state",
          [](const PyVolume& self, const py::handle& points_in, float min_weight,
             float occupied_max_sdf_vox) {
            const auto points = PointsFromArray(points_in);
            py::array_t<uint8_t> out(points.shape(0));
            uint8_t* o = out.mutable_data();
            const VoxelStateParams params{min_weight, occupied_max_sdf_vox};
            ForEachPoint(self, points, [&](size_t i, const Eigen::Vector3f& p) {
              o[i] = uint8_t(StateAt(self.volume, p, params));
            });
            return out;
          },
          py::arg("points"), py::arg("min_weight") = 0.5f, py::arg("occupied_max_sdf_vox") = 0.5f,
          "The state of the voxel containing each (N, 3) world point, (N,) uint8: UNOBSERVED, "
          "FREE or OCCUPIED (core/voxel_state.h's rule).")
      .def(
          "gradient",
          [](const PyVolume& self, const py::handle& points_in) {
            const auto points = PointsFromArray(points_in);
            py::array_t<float> out({points.shape(0), py::ssize_t(3)});
            float* o = out.mutable_data();
            ForEachPoint(self, points, [&](size_t i, const Eigen::Vector3f& p) {
              const std::optional<Eigen::Vector3f> g = Gradient(self.volume, p);
              for (int k = 0; k < 3; ++k) o[3 * i + size_t(k)] = g ? (*g)[k] : kNaN;
            });
            return out;
          },
          py::arg("points"),
          "TSDF gradient by central differences at (N, 3) world points, (N, 3) float32 (NaN "
          "where undefined); normalised, the outward surface normal.")
      .def(
          "block_indices",
          [](const PyVolume& self) {
            std::vector<BlockIndex> blocks;
            {
              std::shared_lock lock(self.mutex);
              blocks = self.volume.SortedBlockIndices();
            }
            static_assert(sizeof(BlockIndex) == 3 * sizeof(int32_t));
            const py::ssize_t n = py::ssize_t(blocks.size());
            return OwnedArray<int32_t>(std::move(blocks), {n, 3});
          },
          "(B, 3) int32 indices of the allocated blocks (x, y, z; a block spans 8 voxels), in "
          "map-file order.")
      .def(
          "clear",
          [](PyVolume& self) {
            std::unique_lock lock(self.mutex);
            self.volume.Clear();
          },
          "Removes every block.")
      .def(
          "save",
          [](const PyVolume& self, const py::object& path) {
            const std::string p = PathString(path);
            const WorldUp up = self.up;  // set under the GIL
            py::gil_scoped_release release;
            std::lock_guard write_lock(WriteMutex());
            std::shared_lock lock(self.mutex);
            ThrowIfError(SaveMap(self.volume, p, up));
          },
          py::arg("path"),
          "Writes the map (.vpmap: voxel size, truncation, the up axis Volume.up, the blocks in "
          "sorted order, a checksum) through a temporary file renamed into place; the same bytes "
          "as `voxplan fuse --map` for the same volume and up axis.")
      .def_static(
          "load",
          [](const py::object& path) {
            const std::string p = PathString(path);
            std::optional<TsdfVolume> volume;
            WorldUp up = WorldUp::kUnknown;
            {
              py::gil_scoped_release release;
              volume.emplace(ValueOrThrow(LoadAnyMap(p, &up)));  // plain or sharded
            }
            return WrapVolume(std::move(*volume), IntegrateParams{}, up);
          },
          py::arg("path"),
          "Reads a .vpmap map file (checked: magic, version, parameters, checksum), version 1 "
          "or 2; Volume.up is the recorded up axis ('unknown' for version 1); integration "
          "parameters start at their defaults. FileNotFoundError / ValueError name the file.")
      .def("__repr__", [](const PyVolume& v) {
        std::shared_lock lock(v.mutex);
        std::ostringstream s;
        s << "<voxplan.Volume voxel_size=" << v.volume.voxel_size_m()
          << " trunc=" << v.volume.trunc_m() << ", " << v.volume.num_blocks() << " blocks>";
        return s.str();
      });

  m.def(
      "read_mesh",
      [](const py::object& path, float scale, const std::string& up) {
        MeshReadOptions options;
        options.scale = scale;
        options.up = ParseUp(up);
        auto out = std::make_unique<PyMesh>();
        out->mesh = MeshArgument(path, options);
        return out;
      },
      py::arg("path"), py::kw_only(), py::arg("scale") = 1.0f, py::arg("up") = "z",
      "Reads a mesh file (.ply by voxplan's validating reader; .obj .glb .stl .dae by assimp), "
      "all its meshes merged; scale multiplies coordinates, up='y' rotates a Y-up file into "
      "voxplan's Z-up world. ValueError / FileNotFoundError name the file.");

  m.def(
      "evaluate_mesh",
      [](const py::handle& reconstruction, const py::handle& ground_truth, double threshold,
         double samples_per_m2, uint64_t seed, const std::string& gt_up, float gt_scale) {
        const Mesh rec = MeshArgument(reconstruction, {});
        const Mesh gt = MeshArgument(ground_truth, {gt_scale, ParseUp(gt_up)});
        MeshEvalParams params;
        params.threshold_m = float(threshold);
        params.samples_per_m2 = float(samples_per_m2);
        params.seed = seed;
        if (!(threshold > 0.0 && std::isfinite(threshold)))
          throw py::value_error("threshold must be a positive number of metres");
        if (!(samples_per_m2 > 0.0 && std::isfinite(samples_per_m2)))
          throw py::value_error("samples_per_m2 must be positive");
        const Stopwatch clock;
        std::optional<MeshEvalResult> r;
        {
          py::gil_scoped_release release;
          r.emplace(ValueOrThrow(EvaluateMesh(rec, gt, params)));
        }
        py::dict d;
        d["accuracy_mean_m"] = r->accuracy_mean_m;
        d["accuracy_rms_m"] = r->accuracy_rms_m;
        d["accuracy_median_m"] = r->accuracy_median_m;
        d["completeness"] = r->completeness;
        d["completeness_percent"] = 100.0 * r->completeness;
        d["threshold_m"] = threshold;
        d["samples_per_m2"] = samples_per_m2;
        d["seed"] = seed;
        d["reconstruction_samples"] = r->reconstruction_samples;
        d["ground_truth_samples"] = r->ground_truth_samples;
        d["reconstruction_area_m2"] = r->reconstruction_area_m2;
        d["ground_truth_area_m2"] = r->ground_truth_area_m2;
        d["eval_ms"] = clock.ElapsedMs();
        return d;
      },
      py::arg("reconstruction"), py::arg("ground_truth"), py::kw_only(),
      py::arg("threshold") = 0.05, py::arg("samples_per_m2") = 10000.0, py::arg("seed") = 1,
      py::arg("gt_up") = "z", py::arg("gt_scale") = 1.0f, R"doc(
Accuracy and completeness of a reconstruction against ground truth, as `voxplan eval mesh`
(Dong et al. 2019, area-weighted samples): accuracy = distances from samples on the
reconstruction to the ground truth (mean, RMS, median, metres); completeness = share of
ground-truth samples within threshold of the reconstruction (0..1). Each mesh is a Mesh or a
mesh file (the ground truth read with gt_scale and gt_up). Returns a dict with the CLI's keys.)doc");
}

}  // namespace voxplan::python
