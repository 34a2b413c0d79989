// voxplan.Dataset (the io readers as an iterable of frames), voxplan.Frame, open_dataset, and
// fuse: the library pipeline (pipeline/fuse_dataset.h) that `voxplan fuse` runs, with its
// parameters and defaults, and FuseResult.write for the CLI's output files.
#include "io/dataset.h"

#include <pybind11/stl.h>
#include <tbb/task_group.h>

#include <atomic>
#include <exception>
#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/bounds.h"
#include "core/parallel.h"
#include "core/summary.h"
#include "io/frame_list.h"
#include "io/output_transaction.h"
#include "pipeline/fuse_dataset.h"
#include "pipeline/fuse_outputs.h"
#include "python/src/objects.h"

namespace voxplan::python {

namespace {

namespace fs = std::filesystem;

std::string PathString(const py::handle& path) {
  return py::str(py::module_::import("os").attr("fspath")(path)).cast<std::string>();
}

struct PyDataset {
  std::shared_ptr<const Dataset> dataset;
  std::string path;  // as given
};

struct PyFrame {
  Frame frame;
  PinholeCamera camera;
};

const uint32_t* FrameRgbx(py::handle base, size_t* pixels) {
  if (!py::isinstance<PyFrame>(base)) return nullptr;
  const ColorImage& c = base.cast<const PyFrame&>().frame.color;
  *pixels = c.data.size();
  return c.data.data();
}

std::unique_ptr<PyFrame> LoadFrame(const Dataset& dataset, size_t i) {
  auto out = std::make_unique<PyFrame>();
  out->camera = dataset.info().camera;
  py::gil_scoped_release release;
  out->frame = ValueOrThrow(dataset.Load(i));
  return out;
}

// The frames a selection picks, as `voxplan fuse --start --stride --frames` picks them.
std::vector<size_t> SelectFrames(size_t num_frames, int64_t start, int64_t stride, int64_t count) {
  if (Status s = bounds::CheckRange("start", double(start), 0, double(bounds::kFramesMax)); !s.ok())
    throw py::value_error(s.message());
  if (Status s = bounds::CheckRange("stride", double(stride), 1, double(bounds::kFramesMax));
      !s.ok())
    throw py::value_error(s.message());
  if (Status s = bounds::CheckRange("frames", double(count), 0, double(bounds::kFramesMax));
      !s.ok())
    throw py::value_error(s.message());
  std::vector<size_t> indices;
  for (size_t i = size_t(start); i < num_frames; i += size_t(stride)) {
    if (count > 0 && indices.size() == size_t(count)) break;
    indices.push_back(i);
  }
  return indices;
}

// Iterates frames `indices` of a dataset in order. Up to `prefetch` frames ahead are decoded on
// worker tasks (Dataset::Load is safe for different frames at once) while Python works on the
// current one, as `voxplan fuse` decodes ahead of its integration (core/parallel.h
// ProduceAhead): each frame is made once, by a worker or by the Python thread when it needs the
// frame before a worker took it (and while it waits, it makes the next waiting one), so a busy
// machine never leaves it idle. 0, or a thread limit of one, loads each frame when asked for.
// A frame that fails to load raises when reached.
class PyFrameIterator {
 public:
  static constexpr size_t kDefaultPrefetch = 3;
  static constexpr size_t kMaxPrefetch = 64;

  PyFrameIterator(std::shared_ptr<const Dataset> dataset, std::vector<size_t> indices,
                  size_t prefetch)
      : s_(std::make_unique<State>()) {
    if (prefetch > kMaxPrefetch)
      throw py::value_error("prefetch must be at most " + std::to_string(kMaxPrefetch) +
                            " frames, got " + std::to_string(prefetch));
    s_->dataset = std::move(dataset);
    s_->indices = std::move(indices);
    s_->ahead = prefetch;
    s_->state.reset(new std::atomic<uint8_t>[s_->indices.size()]);
    for (size_t i = 0; i < s_->indices.size(); ++i) s_->state[i].store(kWaiting);
    s_->slots.resize(prefetch + 1);
  }
  PyFrameIterator(PyFrameIterator&&) = default;
  ~PyFrameIterator() {
    if (!s_ || s_->scheduled == 0) return;
    // Every task handed out ends before the state it points at goes: the loads in flight
    // finish, the tasks not started yet see `stop` and do nothing.
    py::gil_scoped_release release;
    s_->stop.store(true);
    s_->group.wait();
  }

  size_t size() const { return s_->indices.size(); }

  std::unique_ptr<PyFrame> Next() {
    State& s = *s_;
    if (s.next >= s.indices.size()) throw py::stop_iteration();
    auto out = std::make_unique<PyFrame>();
    out->camera = s.dataset->info().camera;
    std::optional<Result<Frame>> frame;
    {
      py::gil_scoped_release release;
      std::lock_guard lock(s.next_mutex);  // one caller at a time, should threads share it
      if (s.next >= s.indices.size()) throw py::stop_iteration();
      const size_t k = s.next++;
      if (s.ahead == 0 || MaxThreads() == 1) {
        if (s.Claim(k)) s.Make(k);
      } else {
        for (; s.scheduled < s.indices.size() && s.scheduled <= k + s.ahead; ++s.scheduled) {
          State* state = &s;
          const size_t i = s.scheduled;
          s.group.run([state, i] {
            if (!state->stop.load(std::memory_order_relaxed) && state->Claim(i)) state->Make(i);
          });
        }
        if (s.Claim(k)) s.Make(k);
        for (size_t j = k + 1; j < s.scheduled && s.state[k].load() != kDone; ++j)
          if (s.Claim(j)) s.Make(j);
      }
      for (uint8_t st; (st = s.state[k].load(std::memory_order_acquire)) != kDone;)
        s.state[k].wait(st, std::memory_order_acquire);
      Slot& slot = s.slots[k % s.slots.size()];
      if (slot.error) std::rethrow_exception(std::exchange(slot.error, nullptr));
      frame = std::move(slot.frame);
      slot.frame.reset();
      if (s.next == s.indices.size()) s.group.wait();  // the last: no task left behind
    }
    out->frame = ValueOrThrow(std::move(*frame));
    return out;
  }

 private:
  enum : uint8_t { kWaiting, kRunning, kDone };
  struct Slot {  // frame i's in slot i % (ahead + 1)
    std::optional<Result<Frame>> frame;
    std::exception_ptr error;
  };
  struct State {
    std::shared_ptr<const Dataset> dataset;
    std::vector<size_t> indices;
    size_t ahead = 0;
    size_t next = 0;       // the next frame returned
    size_t scheduled = 0;  // frames handed to worker tasks: [0, scheduled)
    std::unique_ptr<std::atomic<uint8_t>[]> state;
    std::vector<Slot> slots;
    std::atomic<bool> stop{false};
    std::mutex next_mutex;
    tbb::task_group group;

    bool Claim(size_t i) {
      uint8_t waiting = kWaiting;
      return state[i].compare_exchange_strong(waiting, kRunning, std::memory_order_acquire);
    }
    void Make(size_t i) {  // a claimed frame
      Slot& slot = slots[i % slots.size()];
      try {
        slot.frame.emplace(dataset->Load(indices[i]));
      } catch (...) {
        slot.error = std::current_exception();
      }
      state[i].store(kDone, std::memory_order_release);
      state[i].notify_all();
    }
  };
  std::unique_ptr<State> s_;  // on the heap: tasks point at it while the iterator moves
};

std::unique_ptr<PyDataset> OpenDatasetPy(const py::object& path_in, const std::string& format,
                                         const py::object& intrinsics,
                                         std::optional<double> depth_scale, double max_pose_gap) {
  const std::string path = PathString(path_in);
  DatasetOptions options;
  options.format = ValueOrThrow(ParseDatasetFormat(format));
  if (!intrinsics.is_none()) {
    // (fx, fy, cx, cy) or a 3x3 K; the size comes from the images, so it is checked after.
    auto k = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(intrinsics);
    PinholeCamera camera;
    if (k && k.ndim() == 1 && k.shape(0) == 4) {
      camera.fx = float(k.at(0));
      camera.fy = float(k.at(1));
      camera.cx = float(k.at(2));
      camera.cy = float(k.at(3));
    } else if (k && k.ndim() == 2 && k.shape(0) == 3 && k.shape(1) == 3) {
      camera.fx = float(k.at(0, 0));
      camera.fy = float(k.at(1, 1));
      camera.cx = float(k.at(0, 2));
      camera.cy = float(k.at(1, 2));
    } else {
      throw py::value_error("intrinsics must be (fx, fy, cx, cy) or a 3x3 matrix");
    }
    options.intrinsics = camera;
  }
  if (depth_scale) {
    ThrowIfError(bounds::CheckRange("depth_scale", *depth_scale, bounds::kDepthScaleMin,
                                    bounds::kDepthScaleMax));
    options.depth_scale = *depth_scale;
  }
  if (!(max_pose_gap > 0.0)) throw py::value_error("max_pose_gap must be > 0 seconds");
  options.max_pose_gap_s = max_pose_gap;
  std::error_code ec;
  if (!fs::exists(path, ec)) throw StatusError(NotFound("dataset not found: " + path));
  std::unique_ptr<Dataset> opened;
  {
    py::gil_scoped_release release;
    Result<std::unique_ptr<Dataset>> r = OpenDataset(path, options);
    if (!r.ok()) throw StatusError(r.status().Naming(path));
    opened = std::move(r).value();
  }
  const DatasetInfo& info = opened->info();
  if (Status s = bounds::CheckIntrinsics(info.camera); !s.ok()) {
    const std::string& source = info.intrinsics_source.empty() ? path : info.intrinsics_source;
    throw py::value_error((options.intrinsics ? std::string("intrinsics") : source) + ": " +
                          s.message());
  }
  for (const std::string& w : info.warnings) Warn(w);
  auto out = std::make_unique<PyDataset>();
  out->dataset = std::move(opened);
  out->path = path;
  return out;
}

const char* PoseRejectionName(PoseRejection r) {
  switch (r) {
    case PoseRejection::kBadValues:
      return "bad_values";
    case PoseRejection::kGroundTruthGap:
      return "ground_truth_gap";
    case PoseRejection::kNone:
      break;
  }
  return "";
}

// --- fuse ------------------------------------------------------------------------------------

struct PyFuseResult {
  py::object volume;  // voxplan.Volume
  FuseReport report;
  FuseParams params;
  FrameListParams list;  // camera and parameters, for the frame list
  std::string dataset, format;
  std::string depth_encoding;  // DatasetInfo's: "16-bit PNG", "32-bit float TIFF", ...
  bool depth_metres = false;   // float depth: depth_scale does not apply
  std::string on_memory_limit;
  int threads = 0;
  std::vector<std::string> warnings;
};

template <typename T, typename F>
py::array PerFrame(const FuseReport& r, F&& get) {
  std::vector<T> values;
  values.reserve(r.frames.size());
  for (const FusedFrame& f : r.frames) values.push_back(get(f));
  const py::ssize_t n = py::ssize_t(values.size());
  return OwnedArray<T>(std::move(values), {n});
}

py::array Doubles(std::vector<double> values) {
  const py::ssize_t n = py::ssize_t(values.size());
  return OwnedArray<double>(std::move(values), {n});
}

size_t FramesSkipped(const FuseReport& r) {
  return r.skipped_no_pose + r.skipped_no_depth + r.skipped_bad_pose + r.skipped_pose_gap;
}

double Fps(const FuseReport& r) { return r.loop_s > 0 ? double(r.frames.size()) / r.loop_s : 0.0; }

// The stats object of `voxplan fuse` (its last stdout line) for the parts a run in Python has.
py::dict FuseStats(const PyFuseResult& s) {
  const FuseReport& r = s.report;
  const PyVolume& v = s.volume.cast<const PyVolume&>();
  const TimingSummary load_t = Summarize(r.load_ms), integrate_t = Summarize(r.integrate_ms),
                      frame_t = Summarize(r.frame_ms);
  py::dict j;
  j["command"] = "fuse";
  j["dataset"] = s.dataset;
  j["format"] = s.format;
  j["frames"] = r.frames.size();
  j["frames_selected"] = r.frames_selected;
  j["frames_skipped"] = FramesSkipped(r);
  j["frames_skipped_no_pose"] = r.skipped_no_pose;
  j["frames_skipped_bad_pose"] = r.skipped_bad_pose;
  j["frames_skipped_pose_gap"] = r.skipped_pose_gap;
  j["frames_skipped_no_depth"] = r.skipped_no_depth;
  j["tracking"] = s.params.track;
  j["frames_lost"] = r.frames_lost;
  j["track_ms_median"] = RoundTo(Summarize(r.track_ms).median, 3);
  j["voxel_size_m"] = s.list.voxel_size_m;
  j["trunc_m"] = s.list.trunc_m;
  j["min_depth_m"] = s.list.min_depth_m;
  j["max_depth_m"] = s.list.max_depth_m;
  j["max_weight"] = s.params.integrate.max_weight;
  j["weighting"] = WeightingName(s.params.integrate.weighting);
  j["threads"] = s.threads;
  j["kernel"] = KernelName(ResolveKernel(s.params.integrate.kernel));
  j["depth_scale"] = s.list.depth_scale;
  j["depth_encoding"] =
      s.depth_encoding.empty() ? py::object(py::none()) : py::object(py::str(s.depth_encoding));
  j["depth_scale_applies"] = !s.depth_metres;
  j["depth_median_first_frames_m"] = RoundTo(r.first_frames_median_depth_m, 4);
  j["depth_scale_suggested"] =
      r.suggested_depth_scale > 0.0 ? py::object(py::float_(r.suggested_depth_scale)) : py::none();
  j["integrate_ms_median"] = RoundTo(integrate_t.median, 3);
  j["integrate_ms_p90"] = RoundTo(integrate_t.p90, 3);
  j["integrate_ms_mean"] = RoundTo(integrate_t.mean, 3);
  j["load_ms_median"] = RoundTo(load_t.median, 3);
  j["load_ms_p90"] = RoundTo(load_t.p90, 3);
  j["frame_ms_median"] = RoundTo(frame_t.median, 3);
  j["frame_ms_p90"] = RoundTo(frame_t.p90, 3);
  j["loop_s"] = RoundTo(r.loop_s, 3);
  j["fps"] = RoundTo(Fps(r), 2);
  {
    std::shared_lock lock(v.mutex);
    j["blocks"] = v.volume.num_blocks();
    j["voxels"] = v.volume.num_voxels();
    j["bytes_per_voxel"] = TsdfVolume::BytesPerVoxel();
    j["map_mb"] = Mib(v.volume.MemoryBytes());
    j["max_memory_mb"] = Mib(v.volume.params().max_memory_bytes);
  }
  j["on_memory_limit"] = s.on_memory_limit;
  j["blocks_refused"] = r.blocks_refused;
  j["frames_over_budget"] = r.frames_over_budget;
  return j;
}

// Calls into Python from the pipeline's observers (on the thread that runs FuseDataset, with
// the GIL released): the GIL is taken for each call; the first Python error stops the run and
// is raised once FuseDataset has returned.
class PythonObserver {
 public:
  explicit PythonObserver(py::object progress) : progress_(std::move(progress)) {}

  FuseObserver Observer() {
    FuseObserver o;
    if (!progress_.is_none()) {
      o.progress = [this](size_t done, size_t total) {
        py::gil_scoped_acquire gil;
        if (error_) return;
        try {
          progress_(done, total);
        } catch (py::error_already_set& e) {
          error_.emplace(std::move(e));
        }
      };
    }
    o.warning = [this](const std::string& message) {
      std::lock_guard lock(mutex_);
      warnings_.push_back(message);
    };
    // Ctrl-C (and any signal Python handles) ends the run after the current frame.
    o.stop_requested = [this] {
      py::gil_scoped_acquire gil;
      if (!error_ && PyErr_CheckSignals() != 0) error_.emplace();
      return error_.has_value();
    };
    return o;
  }

  // With the GIL held: the Python error that stopped the run, if any, raised.
  void RaiseIfError() {
    if (error_) {
      py::error_already_set e = std::move(*error_);
      error_.reset();
      throw e;
    }
  }
  std::vector<std::string> TakeWarnings() {
    std::lock_guard lock(mutex_);
    return std::move(warnings_);
  }

 private:
  py::object progress_;
  std::optional<py::error_already_set> error_;
  std::mutex mutex_;
  std::vector<std::string> warnings_;
};

OnMemoryLimit ParseOnMemoryLimit(const std::string& name) {
  if (name == "drop") return OnMemoryLimit::kDrop;
  if (name == "fail") return OnMemoryLimit::kFail;
  throw py::value_error("on_memory_limit must be 'drop' or 'fail', got '" + name + "'");
}

std::unique_ptr<PyFuseResult> Fuse(const py::object& dataset_in, double voxel_size, double trunc,
                                   double min_depth, double max_depth, int64_t frames,
                                   int64_t start, int64_t stride, const std::string& weighting,
                                   const std::string& kernel, double max_weight,
                                   std::optional<uint64_t> max_memory,
                                   const std::string& on_memory_limit, bool track,
                                   double photometric_weight, std::optional<int> threads,
                                   const py::object& progress) {
  py::object dataset_object = dataset_in;
  if (!py::isinstance<PyDataset>(dataset_object))
    dataset_object = py::cast(OpenDatasetPy(dataset_in, "auto", py::none(), std::nullopt, 0.1));
  const PyDataset& ds = dataset_object.cast<const PyDataset&>();
  const Dataset& dataset = *ds.dataset;
  const DatasetInfo& info = dataset.info();

  // As `voxplan fuse` sets them up (apps/voxplan/cmd_fuse.cpp).
  const VolumeParams volume_params{float(voxel_size), float(trunc),
                                   max_memory ? *max_memory : DefaultMemoryBudgetBytes()};
  ThrowIfError(volume_params.Validate());
  FuseParams fuse;
  IntegrateParams& params = fuse.integrate;
  params.min_depth_m = float(min_depth);
  params.max_depth_m = float(max_depth);
  params.max_weight = float(max_weight);
  params.weighting = ParseWeighting(weighting);
  params.kernel = ParseKernel(kernel);
  ThrowIfError(fuse.Validate());
  fuse.track = track;
  fuse.on_memory_limit = ParseOnMemoryLimit(on_memory_limit);
  if (!(photometric_weight >= 0.0 && photometric_weight <= 1000.0))
    throw py::value_error("photometric_weight must be in [0, 1000]");
  fuse.tracking.photometric_weight = float(photometric_weight);
  fuse.tracking.raycast.max_depth_m = float(max_depth);
  fuse.tracking.raycast.min_depth_m = float(min_depth);
  const std::vector<size_t> indices = SelectFrames(info.num_frames, start, stride, frames);
  if (indices.empty())
    throw py::value_error("no frames selected: the dataset has " + std::to_string(info.num_frames) +
                          " frames" + (start > 0 ? " and start is " + std::to_string(start) : ""));
  if (threads) CheckThreads(*threads);

  auto result = std::make_unique<PyFuseResult>();
  result->params = fuse;
  result->list = {info.camera, info.depth_scale, voxel_size, trunc, min_depth, max_depth};
  result->dataset = ds.path;
  result->format = DatasetFormatName(info.format);
  result->depth_encoding = info.depth_encoding;
  result->depth_metres = info.depth_metres;
  result->on_memory_limit = on_memory_limit;
  PythonObserver python(progress);
  const FuseObserver observer = python.Observer();
  std::optional<TsdfVolume> volume;
  std::optional<Result<FuseReport>> fused;
  {
    py::gil_scoped_release release;
    std::optional<ThreadLimit> limit;
    if (threads) limit.emplace(*threads);
    result->threads = MaxThreads();
    volume.emplace(volume_params);
    fused.emplace(FuseDataset(dataset, indices, fuse, *volume, observer));
  }
  python.RaiseIfError();
  result->warnings = python.TakeWarnings();
  for (const std::string& w : result->warnings) Warn(w);
  if (!fused->ok()) throw StatusError(fused->status());
  result->report = std::move(*fused).value();
  if (result->report.frames.empty())
    throw StatusError(Status(StatusCode::kInternal, "no frame was integrated (" +
                                                        std::to_string(indices.size()) +
                                                        " selected, all skipped): " + ds.path));
  result->volume =
      WrapVolume(std::move(*volume), params, FusedWorldUp(info, result->report, fuse.track));
  return result;
}

}  // namespace

void BindDataset(py::module_& m) {
  RegisterRgbxOwner(&FrameRgbx);

  py::class_<PyFrame>(m, "Frame", R"doc(
One RGB-D frame as the dataset reader decoded it. depth and color are views of the decoded
images (no copy) and keep the frame alive; Volume.integrate reads both in place.
)doc")
      .def_property_readonly(
          "index", [](const PyFrame& f) { return f.frame.index; },
          "0-based position in the sequence")
      .def_property_readonly(
          "timestamp", [](const PyFrame& f) { return f.frame.timestamp; },
          "seconds (frame id or index / 30 Hz where the dataset has none)")
      .def_property_readonly(
          "depth",
          [](const py::object& self) {
            const DepthImage& d = self.cast<PyFrame&>().frame.depth;
            return ViewArray(d.data.data(), {d.height, d.width},
                             {py::ssize_t(sizeof(float)) * d.width, sizeof(float)}, self);
          },
          "(H, W) float32 depth in metres, 0 = invalid")
      .def_property_readonly(
          "color",
          [](const py::object& self) -> py::object {
            const ColorImage& c = self.cast<PyFrame&>().frame.color;
            if (c.empty()) return py::none();
            return RgbxAsRgbView(c.data.data(), c.width, c.height, self);
          },
          "(H, W, 3) uint8 RGB (a view of packed RGBX pixels, strides (4W, 4, 1)), or None")
      .def_property_readonly(
          "T_W_C",
          [](const PyFrame& f) -> py::object {
            if (!f.frame.T_W_C) return py::none();
            return PoseToArray(f.frame.T_W_C->matrix());
          },
          "4x4 float64 camera-to-world pose (OpenCV axes), or None when the frame has none")
      .def_property_readonly(
          "K", [](const PyFrame& f) { return KFromCamera(f.camera); },
          "3x3 float64 intrinsics of the dataset")
      .def_property_readonly("width", [](const PyFrame& f) { return f.frame.depth.width; })
      .def_property_readonly("height", [](const PyFrame& f) { return f.frame.depth.height; })
      .def_property_readonly("depth_path", [](const PyFrame& f) { return f.frame.depth_path; })
      .def_property_readonly("color_path", [](const PyFrame& f) { return f.frame.color_path; })
      .def_property_readonly(
          "pose_rejected",
          [](const PyFrame& f) { return PoseRejectionName(f.frame.pose_rejected); },
          "why a listed pose was dropped: '' (none), 'bad_values' or 'ground_truth_gap'")
      .def_property_readonly("pose_rejected_why",
                             [](const PyFrame& f) { return f.frame.pose_rejected_why; })
      .def("__repr__", [](const PyFrame& f) {
        return "<voxplan.Frame " + std::to_string(f.frame.index) + " " +
               std::to_string(f.frame.depth.width) + "x" + std::to_string(f.frame.depth.height) +
               (f.frame.T_W_C ? "" : " without pose") + ">";
      });

  py::class_<PyFrameIterator>(m, "FrameIterator",
                              "Loads the frames of a selection in order, decoding a few ahead on "
                              "background threads (with the GIL released).")
      .def("__iter__", [](py::object self) { return self; })
      .def("__next__", &PyFrameIterator::Next)
      .def("__len__", &PyFrameIterator::size);

  py::class_<PyDataset>(m, "Dataset", R"doc(
An RGB-D dataset (TUM, ICL-NUIM, Redwood/Open3D, 7-Scenes, 3DMatch, Replica, ...) read by
voxplan's readers: len(dataset) frames, dataset[i] decodes frame i, iterating yields them in
order (decoded a few ahead on background threads, the GIL released). Open one with
voxplan.open_dataset.
)doc")
      .def("__len__", [](const PyDataset& d) { return d.dataset->info().num_frames; })
      .def(
          "__getitem__",
          [](const PyDataset& d, int64_t i) {
            const int64_t n = int64_t(d.dataset->info().num_frames);
            if (i < 0) i += n;
            if (i < 0 || i >= n)
              throw py::index_error("frame index out of range (" + std::to_string(n) + " frames)");
            return LoadFrame(*d.dataset, size_t(i));
          },
          py::arg("index"))
      .def("__iter__",
           [](const PyDataset& d) {
             return PyFrameIterator(d.dataset, SelectFrames(d.dataset->info().num_frames, 0, 1, 0),
                                    PyFrameIterator::kDefaultPrefetch);
           })
      .def(
          "frames",
          [](const PyDataset& d, int64_t start, int64_t stride, int64_t count, size_t prefetch) {
            return PyFrameIterator(d.dataset,
                                   SelectFrames(d.dataset->info().num_frames, start, stride, count),
                                   prefetch);
          },
          py::kw_only(), py::arg("start") = 0, py::arg("stride") = 1, py::arg("count") = 0,
          py::arg("prefetch") = PyFrameIterator::kDefaultPrefetch,
          "The frames start, start + stride, ... (at most count; 0: all), as `voxplan fuse "
          "--start --stride --frames` selects them; up to `prefetch` frames ahead are decoded "
          "on background threads while the current one is used (0: none).")
      .def_property_readonly("path", [](const PyDataset& d) { return d.path; })
      .def_property_readonly("root", [](const PyDataset& d) { return d.dataset->info().root; })
      .def_property_readonly(
          "format", [](const PyDataset& d) { return DatasetFormatName(d.dataset->info().format); })
      .def_property_readonly(
          "K", [](const PyDataset& d) { return KFromCamera(d.dataset->info().camera); })
      .def_property_readonly("width",
                             [](const PyDataset& d) { return d.dataset->info().camera.width; })
      .def_property_readonly("height",
                             [](const PyDataset& d) { return d.dataset->info().camera.height; })
      .def_property_readonly(
          "depth_scale", [](const PyDataset& d) { return d.dataset->info().depth_scale; },
          "depth units per metre of the raw 16-bit images (float TIFF / EXR depth is metres: "
          "see depth_encoding)")
      .def_property_readonly(
          "depth_encoding",
          [](const PyDataset& d) -> py::object {
            const std::string& e = d.dataset->info().depth_encoding;
            return e.empty() ? py::object(py::none()) : py::object(py::str(e));
          },
          "what the depth files hold: '16-bit PNG', '16-bit TIFF' (units of 1 / depth_scale), "
          "'32-bit float TIFF', '32-bit float EXR', '16-bit float EXR' (metres: depth_scale "
          "does not apply); None for the formats in one file (.sens, .bag)")
      .def_property_readonly("has_color",
                             [](const PyDataset& d) { return d.dataset->info().has_color; })
      .def_property_readonly("intrinsics_source",
                             [](const PyDataset& d) { return d.dataset->info().intrinsics_source; })
      .def_property_readonly("pose_source",
                             [](const PyDataset& d) { return d.dataset->info().pose_source; })
      .def_property_readonly(
          "up", [](const PyDataset& d) { return std::string(WorldUpName(d.dataset->info().up)); },
          "the world's up axis ('+y', '+z', ..., 'unknown'): the format's convention, else "
          "estimated from the poses (up_source says which)")
      .def_property_readonly("up_source",
                             [](const PyDataset& d) { return d.dataset->info().up_source; })
      .def_property_readonly("warnings",
                             [](const PyDataset& d) { return d.dataset->info().warnings; })
      .def_property_readonly(
          "input_files", [](const PyDataset& d) { return d.dataset->InputFiles(); },
          "every file the reader reads")
      .def("__repr__", [](const PyDataset& d) {
        const DatasetInfo& i = d.dataset->info();
        return "<voxplan.Dataset " + std::string(DatasetFormatName(i.format)) + " " + i.root +
               ", " + std::to_string(i.num_frames) + " frames " + std::to_string(i.camera.width) +
               "x" + std::to_string(i.camera.height) + ">";
      });

  m.def("open_dataset", &OpenDatasetPy, py::arg("path"), py::kw_only(), py::arg("format") = "auto",
        py::arg("intrinsics") = py::none(), py::arg("depth_scale") = py::none(),
        py::arg("max_pose_gap") = 0.1, R"doc(
Opens an RGB-D dataset folder (or a one-file sequence) as `voxplan fuse` does: the format
('auto', 'tum', 'icl', 'redwood', '7scenes', '3dmatch', 'replica', ...) detected from its files;
intrinsics (fx, fy, cx, cy) and depth_scale (units per metre) from the dataset unless given;
max_pose_gap: timestamped ground truth is not interpolated across longer gaps (seconds).
The reader's warnings are issued as voxplan.VoxplanWarning (and kept in Dataset.warnings).
Raises FileNotFoundError for a missing path, ValueError for a malformed dataset, each naming
the file.)doc");

  py::class_<PyFuseResult>(m, "FuseResult", R"doc(
What voxplan.fuse returns: the fused volume, the frames integrated and the counts and timings
of `voxplan fuse`'s stats.
)doc")
      .def_readonly("volume", &PyFuseResult::volume, "the fused voxplan.Volume")
      .def_property_readonly(
          "frames", [](const PyFuseResult& r) { return r.report.frames.size(); },
          "frames integrated")
      .def_property_readonly("frames_selected",
                             [](const PyFuseResult& r) { return r.report.frames_selected; })
      .def_property_readonly("frames_skipped",
                             [](const PyFuseResult& r) { return FramesSkipped(r.report); })
      .def_property_readonly("frames_lost",
                             [](const PyFuseResult& r) { return r.report.frames_lost; })
      .def_property_readonly("blocks_refused",
                             [](const PyFuseResult& r) { return r.report.blocks_refused; })
      .def_property_readonly(
          "loop_s", [](const PyFuseResult& r) { return r.report.loop_s; },
          "seconds of the whole frame loop (decoding included)")
      .def_property_readonly("fps", [](const PyFuseResult& r) { return Fps(r.report); })
      .def_property_readonly(
          "frame_indices",
          [](const PyFuseResult& r) {
            return PerFrame<int64_t>(r.report,
                                     [](const FusedFrame& f) { return int64_t(f.index); });
          },
          "(N,) int64 dataset index of each integrated frame")
      .def_property_readonly("timestamps",
                             [](const PyFuseResult& r) {
                               return PerFrame<double>(
                                   r.report, [](const FusedFrame& f) { return f.timestamp_s; });
                             })
      .def_property_readonly(
          "poses",
          [](const PyFuseResult& r) {
            std::vector<double> values;
            for (const FusedFrame& f : r.report.frames) {
              const Eigen::Matrix4d T = f.T_W_C.matrix().cast<double>();
              for (int i = 0; i < 4; ++i)
                for (int j = 0; j < 4; ++j) values.push_back(T(i, j));
            }
            const py::ssize_t n = py::ssize_t(r.report.frames.size());
            return OwnedArray<double>(std::move(values), {n, 4, 4});
          },
          "(N, 4, 4) float64 pose each frame was integrated at (camera-to-world)")
      .def_property_readonly("depth_paths",
                             [](const PyFuseResult& r) {
                               std::vector<std::string> p;
                               for (const FusedFrame& f : r.report.frames)
                                 p.push_back(f.depth_path);
                               return p;
                             })
      .def_property_readonly("color_paths",
                             [](const PyFuseResult& r) {
                               std::vector<std::string> p;
                               for (const FusedFrame& f : r.report.frames)
                                 p.push_back(f.color_path);
                               return p;
                             })
      .def_property_readonly(
          "load_ms", [](const PyFuseResult& r) { return Doubles(r.report.load_ms); },
          "(N,) decoding time per integrated frame, ms")
      .def_property_readonly(
          "integrate_ms", [](const PyFuseResult& r) { return Doubles(r.report.integrate_ms); },
          "(N,) integration time per integrated frame, ms")
      .def_property_readonly("frame_ms",
                             [](const PyFuseResult& r) { return Doubles(r.report.frame_ms); })
      .def_property_readonly("track_ms",
                             [](const PyFuseResult& r) { return Doubles(r.report.track_ms); })
      .def_readonly("warnings", &PyFuseResult::warnings,
                    "the pipeline's warnings (also issued as voxplan.VoxplanWarning)")
      .def("stats", &FuseStats,
           "The stats dict of `voxplan fuse` (frames, skips, timings' medians, map size, ...).")
      .def(
          "write",
          [](const PyFuseResult& r, const py::object& mesh, const py::object& map,
             const py::object& trajectory, const py::object& frame_list,
             float mesh_min_weight) -> py::object {
            const auto path = [](const py::object& p) {
              return p.is_none() ? std::string() : PathString(p);
            };
            const PyVolume& v = r.volume.cast<const PyVolume&>();
            FuseOutputPaths paths{path(mesh), path(map), path(trajectory), path(frame_list)};
            paths.map_up = v.up;  // read under the GIL, as it is set
            auto out = std::make_unique<PyMesh>();
            {
              py::gil_scoped_release release;
              std::lock_guard write_lock(WriteMutex());
              std::shared_lock lock(v.mutex);
              OutputTransaction written;  // every file lands, or none
              MeshParams mesh_params;
              mesh_params.min_weight = mesh_min_weight;
              FuseOutputs outputs =
                  ValueOrThrow(WriteFuseOutputs(paths, v.volume, r.report, mesh_params, r.list));
              ThrowIfError(written.Commit());
              out->mesh = std::move(outputs.mesh);
            }
            if (paths.mesh.empty()) return py::none();
            return py::cast(std::move(out));
          },
          py::kw_only(), py::arg("mesh") = py::none(), py::arg("map") = py::none(),
          py::arg("trajectory") = py::none(), py::arg("frame_list") = py::none(),
          py::arg("mesh_min_weight") = 0.5f, R"doc(
Writes what `voxplan fuse --mesh --map --trajectory --frame-list` writes, byte for byte: the
mesh (.ply .obj .glb .stl), the map (.vpmap), the poses used (TUM format) and the frame list
(JSON); every file lands or none. Returns the Mesh when one was written, else None.)doc")
      .def("__repr__", [](const PyFuseResult& r) {
        return "<voxplan.FuseResult " + std::to_string(r.report.frames.size()) + " of " +
               std::to_string(r.report.frames_selected) + " frames integrated in " +
               std::to_string(r.report.loop_s) + " s>";
      });

  m.def("fuse", &Fuse, py::arg("dataset"), py::kw_only(), py::arg("voxel_size") = 0.01,
        py::arg("trunc") = 0.04, py::arg("min_depth") = 0.1, py::arg("max_depth") = 3.0,
        py::arg("frames") = 0, py::arg("start") = 0, py::arg("stride") = 1,
        py::arg("weighting") = "constant", py::arg("kernel") = "auto", py::arg("max_weight") = 64.0,
        py::arg("max_memory") = py::none(), py::arg("on_memory_limit") = "drop",
        py::arg("track") = false, py::arg("photometric_weight") = 0.0,
        py::arg("threads") = py::none(), py::arg("progress") = py::none(), R"doc(
Fuses a dataset (a Dataset or a path, opened with the defaults) with the library pipeline that
`voxplan fuse` runs, with the same parameters and defaults, so the same call gives the same map
and mesh bytes: frames start, start + stride, ... (at most `frames`; 0: all); frames without
valid depth or a trustworthy pose are skipped and counted; track=True estimates poses by
frame-to-model ICP. max_memory: the map's budget in bytes (None: half the machine's memory, as
the CLI), on_memory_limit 'drop' or 'fail'. threads: worker threads for this call (None: the
current limit, see set_threads). progress(done, total) is called after every selected frame
(with the GIL); an exception it raises, or Ctrl-C, stops the run after the current frame and
is raised. The GIL is released while fusing. Warnings are issued as voxplan.VoxplanWarning.
Raises RuntimeError when no frame was integrated.)doc");
}

}  // namespace voxplan::python
