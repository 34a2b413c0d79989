// voxplan bench fusion|raycast|mesh: times integration, ray casting and meshing on a dataset for
// a list of thread counts, optionally beside Open3D (bench/open3d_fusion.py) on identical frames.
#include <fcntl.h>
#include <sched.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <sstream>

#include "apps/voxplan/cli_common.h"
#include "core/parallel.h"
#include "core/raycast.h"
#include "core/volume.h"
#include "fusion/integrate.h"
#include "fusion/mesh_extract.h"
#include "io/dataset.h"
#include "io/frame_list.h"
#include "pipeline/fuse_dataset.h"

extern char** environ;

namespace voxplan::cli {

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

enum class BenchMode { kFusion, kRaycast, kMesh };

const std::map<std::string, Kernel> kKernels = {
    {"auto", Kernel::kAuto}, {"scalar", Kernel::kScalar}, {"simd", Kernel::kSimd}};

constexpr int kRaycastViews = 10;  // poses spread over the sequence
constexpr int kRaycastRounds = 3;  // each pose cast this many times
constexpr int kMaxThreadCount = 4096;
constexpr const char* kPython = "/usr/bin/python3";
constexpr const char* kSetupHint =
    "install Open3D for /usr/bin/python3 with scripts/setup-deps --bench";

struct BenchOptions {
  DatasetInput in;
  double voxel_size_m = 0.01;
  double trunc_m = 0.04;
  std::string threads;  // "1,2"; empty: 1 and all hardware threads
  int repeat = 3;
  std::string kernel = "auto";
  bool vs_open3d = false;
  std::string json_path;
};

struct Row {
  int threads = 0;
  std::optional<double> integrate_median, integrate_p90, load_median, raycast_median, mesh_ms;
  std::optional<double> mesh_update_median;  // incremental meshing of one frame's changes
  std::vector<double> integrate_repeat_medians;
  double raycast_hit_fraction = 0.0;
  size_t mesh_triangles = 0, blocks = 0, voxels = 0;
  double bytes_per_voxel = 0.0, map_mb = 0.0, peak_rss_mb = 0.0;
  json open3d_legacy, open3d_vbg;  // the script's JSON per path, null when not run
};

Result<std::vector<int>> ParseThreadList(const std::string& text) {
  std::vector<int> threads;
  if (text.empty()) {
    threads = {1, HardwareThreads()};
  } else {
    std::stringstream stream(text);
    std::string item;
    while (std::getline(stream, item, ',')) {
      int value = 0;
      size_t used = 0;
      try {
        value = std::stoi(item, &used);
      } catch (const std::exception&) {
        used = 0;
      }
      if (item.empty() || used != item.size() || value < 1 || value > kMaxThreadCount) {
        return InvalidArgument("--threads wants a comma-separated list of thread counts (1 to " +
                               std::to_string(kMaxThreadCount) + "), got '" + text + "'");
      }
      threads.push_back(value);
    }
    if (threads.empty() || text.back() == ',') {
      return InvalidArgument("--threads wants a comma-separated list of thread counts, got '" +
                             text + "'");
    }
  }
  // Ascending, so the last row is the largest count (the top-level numbers).
  std::sort(threads.begin(), threads.end());
  threads.erase(std::unique(threads.begin(), threads.end()), threads.end());
  return threads;
}

int Nproc() {
  cpu_set_t set;
  CPU_ZERO(&set);
  if (sched_getaffinity(0, sizeof(set), &set) == 0) return CPU_COUNT(&set);
  return HardwareThreads();
}

std::string CpuModel() {
  std::ifstream in("/proc/cpuinfo");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("model name", 0) == 0) {
      const size_t colon = line.find(':');
      if (colon != std::string::npos) {
        std::string model = line.substr(colon + 1);
        model.erase(0, model.find_first_not_of(" \t"));
        return model;
      }
    }
  }
  return "unknown";
}

json OptionalMs(const std::optional<double>& v) { return v ? json(RoundTo(*v, 3)) : json(nullptr); }

std::optional<double> JsonNumber(const json& j, const std::string& key) {
  if (!j.is_object() || !j.contains(key) || !j.at(key).is_number()) return std::nullopt;
  return j.at(key).get<double>();
}

std::optional<double> Ratio(const std::optional<double>& num, const std::optional<double>& den) {
  if (!num || !den || *den <= 0.0) return std::nullopt;
  return *num / *den;
}

std::optional<double> Min(const std::optional<double>& a, const std::optional<double>& b) {
  if (a && b) return std::min(*a, *b);
  return a ? a : b;
}

json Rounded2(const std::optional<double>& v) { return v ? json(RoundTo(*v, 2)) : json(nullptr); }

// Runs argv with extra environment entries (no shell), stdout captured, stderr passed through.
// Returns the exit status (as waitpid gives it) or an error when it could not be started.
Result<int> Spawn(const std::vector<std::string>& argv, const std::vector<std::string>& extra_env,
                  std::string* out, bool quiet = false) {
  std::vector<std::string> env_strings;
  for (char** e = environ; *e != nullptr; ++e) {
    const std::string entry(*e);
    const std::string name = entry.substr(0, entry.find('='));
    const bool overridden = std::any_of(extra_env.begin(), extra_env.end(), [&](const auto& x) {
      return x.substr(0, x.find('=')) == name;
    });
    if (!overridden) env_strings.push_back(entry);
  }
  env_strings.insert(env_strings.end(), extra_env.begin(), extra_env.end());
  std::vector<char*> envp, args;
  for (std::string& s : env_strings) envp.push_back(s.data());
  envp.push_back(nullptr);
  std::vector<std::string> argv_copy = argv;
  for (std::string& s : argv_copy) args.push_back(s.data());
  args.push_back(nullptr);

  int pipe_fds[2];
  if (pipe(pipe_fds) != 0) return IoError(std::string("pipe: ") + std::strerror(errno));
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addclose(&actions, pipe_fds[0]);
  posix_spawn_file_actions_adddup2(&actions, pipe_fds[1], STDOUT_FILENO);
  posix_spawn_file_actions_addclose(&actions, pipe_fds[1]);
  if (quiet) posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, "/dev/null", O_WRONLY, 0);
  pid_t pid = 0;
  const int rc = posix_spawn(&pid, args[0], &actions, nullptr, args.data(), envp.data());
  posix_spawn_file_actions_destroy(&actions);
  close(pipe_fds[1]);
  if (rc != 0) {
    close(pipe_fds[0]);
    return IoError("cannot run " + argv[0] + ": " + std::strerror(rc));
  }
  char buffer[4096];
  ssize_t n = 0;
  while ((n = read(pipe_fds[0], buffer, sizeof(buffer))) != 0) {
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) break;
    out->append(buffer, size_t(n));
  }
  close(pipe_fds[0]);
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  return status;
}

// The frame list in a private temporary file, removed when this goes out of scope.
class TempFrameList {
 public:
  ~TempFrameList() {
    if (!path_.empty()) std::remove(path_.c_str());
  }
  Status Write(const json& list) {
    std::string pattern = (fs::temp_directory_path() / "voxplan-bench-frames-XXXXXX").string();
    const int fd = mkstemp(pattern.data());
    if (fd < 0) return IoError("cannot create a temporary file in " + pattern);
    path_ = pattern;
    const std::string text = list.dump() + "\n";
    size_t written = 0;
    while (written < text.size()) {
      const ssize_t n = write(fd, text.data() + written, text.size() - written);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) {
        close(fd);
        return IoError("cannot write " + path_ + ": " + std::strerror(errno));
      }
      written += size_t(n);
    }
    if (close(fd) != 0) return IoError("cannot write " + path_);
    return Status::Ok();
  }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

std::string ScriptPath() { return std::string(VOXPLAN_SOURCE_DIR) + "/bench/open3d_fusion.py"; }

// Refuses --vs-open3d before any work when the interpreter, Open3D or the script is missing.
Status CheckOpen3d() {
  if (access(kPython, X_OK) != 0)
    return NotFound(std::string(kPython) + " not found; " + kSetupHint);
  if (!fs::exists(ScriptPath())) return NotFound("Open3D script not found: " + ScriptPath());
  std::string out;
  Result<int> status = Spawn({kPython, "-c", "import open3d"}, {}, &out, /*quiet=*/true);
  if (!status.ok()) return NotFound(status.status().message() + "; " + kSetupHint);
  if (!WIFEXITED(*status) || WEXITSTATUS(*status) != 0) {
    return NotFound(std::string(kPython) + " cannot import open3d; " + kSetupHint);
  }
  return Status::Ok();
}

Result<json> RunOpen3d(const std::string& list_path, const std::string& path, int threads,
                       int repeat, const std::string& raycast_poses) {
  std::string out;
  // ACTIVE: Open3D's OpenMP loops stall on small machines with the default passive wait.
  Result<int> status =
      Spawn({kPython, ScriptPath(), list_path, "--path", path, "--repeat", std::to_string(repeat),
             "--raycast-poses", raycast_poses},
            {"OMP_WAIT_POLICY=ACTIVE", "OMP_NUM_THREADS=" + std::to_string(threads)}, &out);
  if (!status.ok()) return status.status();
  if (!WIFEXITED(*status) || WEXITSTATUS(*status) != 0) {
    return Status(StatusCode::kInternal,
                  ScriptPath() + " --path " + path + " failed (exit " +
                      std::to_string(WIFEXITED(*status) ? WEXITSTATUS(*status) : -1) + ")");
  }
  std::string line, last;
  std::istringstream lines(out);
  while (std::getline(lines, line))
    if (!line.empty()) last = line;
  json j = json::parse(last, nullptr, /*allow_exceptions=*/false);
  if (!j.is_object()) {
    return Status(StatusCode::kInternal,
                  ScriptPath() + " --path " + path + ": last stdout line is not JSON: " + last);
  }
  return j;
}

// Indexes (into the integrated frames) of up to kRaycastViews poses spread over the sequence.
std::vector<size_t> RaycastPoseIndexes(size_t n) {
  std::vector<size_t> indexes;
  const size_t m = std::min<size_t>(kRaycastViews, n);
  for (size_t k = 0; k < m; ++k) {
    indexes.push_back(m == 1 ? 0 : size_t(std::llround(double(k) * double(n - 1) / double(m - 1))));
  }
  indexes.erase(std::unique(indexes.begin(), indexes.end()), indexes.end());
  return indexes;
}

std::string Cell(const std::optional<double>& v, int decimals = 2) {
  if (!v) return "-";
  std::ostringstream s;
  s << std::fixed << std::setprecision(decimals) << *v;
  return s.str();
}

const char* ModeName(BenchMode mode) {
  switch (mode) {
    case BenchMode::kFusion:
      return "fusion";
    case BenchMode::kRaycast:
      return "raycast";
    case BenchMode::kMesh:
      return "mesh";
  }
  return "?";
}

int RunBench(const BenchOptions& o, BenchMode mode) {
  // Everything the arguments alone can refuse is refused before the dataset is read.
  Result<std::vector<int>> thread_list = ParseThreadList(o.threads);
  if (!thread_list.ok()) return Fail(thread_list.status().message(), kExitUsage);
  if (o.trunc_m < o.voxel_size_m) return Fail("--trunc must be at least --voxel-size", kExitUsage);
  if (o.in.max_depth_m <= o.in.min_depth_m) {
    return Fail("--max-depth must be greater than --min-depth", kExitUsage);
  }
  if (o.vs_open3d) {
    if (Status s = CheckOpen3d(); !s.ok()) return Fail("--vs-open3d: " + s.message());
  }

  OpenedDataset opened;
  if (int code = OpenDatasetInput(o.in, {}, &opened); code != kExitOk) return code;
  const Dataset& dataset = *opened.dataset;
  const DatasetInfo& info = dataset.info();
  const std::vector<size_t>& indices = opened.indices;

  IntegrateParams params;
  params.min_depth_m = float(o.in.min_depth_m);
  params.max_depth_m = float(o.in.max_depth_m);
  params.kernel = kKernels.at(o.kernel);
  const VolumeParams volume_params{float(o.voxel_size_m), float(o.trunc_m)};
  RaycastParams raycast_params;
  raycast_params.max_depth_m = float(o.in.max_depth_m);
  raycast_params.simd = params.kernel != Kernel::kScalar;
  const char* kernel_name = KernelName(ResolveKernel(params.kernel));
  const char* raycast_kernel_name =
      raycast_params.simd && RaycastSimdAvailable() ? "avx2" : "scalar";

  std::cerr << "bench " << ModeName(mode) << ": " << info.root << " ("
            << DatasetFormatName(info.format) << "), " << indices.size() << " frames, voxel "
            << o.voxel_size_m << " m, trunc " << o.trunc_m << " m, threads " << o.threads
            << (o.threads.empty() ? "1,all" : "") << ", " << o.repeat << " repeats, kernel "
            << kernel_name << " (raycast " << raycast_kernel_name << ")" << std::endl;

  // Recorded on the first pass only: the frames integrated, in order, and the skipped ones.
  std::vector<FusedFrame> records;
  size_t skipped_no_pose = 0, skipped_no_depth = 0;
  bool first_pass = true;
  FuseParams fuse_params;
  fuse_params.integrate = params;
  // Streams every selected frame into `volume` (decode timed apart from integration).
  // With `mesher`, each frame's changed blocks (found untimed) are meshed again, timed.
  auto fuse = [&](TsdfVolume& volume, std::vector<double>* integrate_ms,
                  std::vector<double>* load_ms, IncrementalMesher* mesher = nullptr,
                  std::vector<double>* mesh_update_ms = nullptr) -> Status {
    FuseObserver observer;
    if (mesher) {
      observer.integrated = [&](const Frame& frame, const Pose3f& T_W_C, TsdfVolume& v) {
        const std::vector<BlockIndex> changed =
            BlocksInTruncationBand(frame.depth, info.camera, T_W_C, params, v.params());
        const Stopwatch mesh_clock;
        mesher->Update(v, changed);
        mesh_update_ms->push_back(mesh_clock.ElapsedMs());
        return Status::Ok();
      };
    }
    Result<FuseReport> report = FuseDataset(dataset, indices, fuse_params, volume, observer);
    if (!report.ok()) return report.status();
    if (integrate_ms)
      integrate_ms->insert(integrate_ms->end(), report->integrate_ms.begin(),
                           report->integrate_ms.end());
    if (load_ms) load_ms->insert(load_ms->end(), report->load_ms.begin(), report->load_ms.end());
    if (first_pass) {
      records = report->frames;
      skipped_no_pose = report->skipped_no_pose;
      skipped_no_depth = report->skipped_no_depth;
    }
    first_pass = false;
    return Status::Ok();
  };
  auto time_raycasts = [&](const TsdfVolume& volume, int rounds, Row& row) {
    std::vector<double> ms;
    RaycastImages images;
    size_t hits = 0, pixels = 0;
    const std::vector<size_t> poses = RaycastPoseIndexes(records.size());
    for (int r = 0; r < rounds; ++r) {
      for (size_t k : poses) {
        const Stopwatch clock;
        Raycast(volume, info.camera, records[k].T_W_C, raycast_params, images);
        ms.push_back(clock.ElapsedMs());
        if (r == 0) {
          pixels += images.status.data.size();
          hits += size_t(std::count(images.status.data.begin(), images.status.data.end(),
                                    uint8_t(RayStatus::kHit)));
        }
      }
    }
    row.raycast_median = Summarize(ms).median;
    row.raycast_hit_fraction = pixels ? double(hits) / double(pixels) : 0.0;
  };
  auto record_map = [&](const TsdfVolume& volume, Row& row) {
    row.blocks = volume.num_blocks();
    row.voxels = volume.num_voxels();
    row.bytes_per_voxel = row.voxels ? double(volume.MemoryBytes()) / double(row.voxels) : 0.0;
    row.map_mb = Mib(volume.MemoryBytes());
  };

  std::vector<Row> rows;
  for (int threads : *thread_list) {
    ThreadLimit limit(threads);
    Row row;
    row.threads = threads;
    std::cerr << "threads " << threads << ":" << std::flush;
    if (mode == BenchMode::kFusion) {
      std::vector<double> p90s, load_all, mesh_ms, mesh_update_ms;
      for (int r = 0; r < o.repeat; ++r) {
        auto volume = std::make_unique<TsdfVolume>(volume_params);
        std::vector<double> integrate_ms;
        // The first repeat also keeps a mesh up to date frame by frame.
        IncrementalMesher mesher;
        if (Status s = fuse(*volume, &integrate_ms, &load_all, r == 0 ? &mesher : nullptr,
                            &mesh_update_ms);
            !s.ok()) {
          std::cerr << "\n";
          return Fail(s.message());
        }
        if (integrate_ms.empty()) {
          std::cerr << "\n";
          return Fail("no frame was integrated (all skipped): " + o.in.dataset);
        }
        const TimingSummary t = Summarize(integrate_ms);
        row.integrate_repeat_medians.push_back(t.median);
        p90s.push_back(t.p90);
        const Stopwatch mesh_clock;
        const Mesh mesh = ExtractMesh(*volume);
        mesh_ms.push_back(mesh_clock.ElapsedMs());
        row.mesh_triangles = mesh.num_triangles();
        std::cerr << " integrate " << Cell(t.median) << " ms" << std::flush;
        if (r + 1 == o.repeat) {
          time_raycasts(*volume, kRaycastRounds, row);
          record_map(*volume, row);
        }
      }
      row.integrate_median = Summarize(row.integrate_repeat_medians).median;
      row.integrate_p90 = Summarize(p90s).median;
      row.load_median = Summarize(load_all).median;
      row.mesh_ms = Summarize(mesh_ms).median;
      row.mesh_update_median = Summarize(mesh_update_ms).median;
    } else {
      // Fused once per thread count, untimed; only the part under test is timed.
      auto volume = std::make_unique<TsdfVolume>(volume_params);
      if (Status s = fuse(*volume, nullptr, nullptr); !s.ok()) {
        std::cerr << "\n";
        return Fail(s.message());
      }
      if (records.empty()) return Fail("no frame was integrated (all skipped): " + o.in.dataset);
      record_map(*volume, row);
      if (mode == BenchMode::kRaycast) {
        time_raycasts(*volume, std::max(o.repeat, kRaycastRounds), row);
      } else {
        std::vector<double> mesh_ms;
        for (int r = 0; r < o.repeat; ++r) {
          const Stopwatch mesh_clock;
          const Mesh mesh = ExtractMesh(*volume);
          mesh_ms.push_back(mesh_clock.ElapsedMs());
          row.mesh_triangles = mesh.num_triangles();
        }
        row.mesh_ms = Summarize(mesh_ms).median;
      }
    }
    row.peak_rss_mb = PeakRssMb();
    std::cerr << " raycast " << Cell(row.raycast_median) << " ms, mesh " << Cell(row.mesh_ms)
              << " ms (incremental " << Cell(row.mesh_update_median) << " ms/frame)" << std::endl;
    rows.push_back(std::move(row));
  }

  const std::vector<size_t> raycast_poses = RaycastPoseIndexes(records.size());
  if (o.vs_open3d) {
    // Exactly the poses voxplan integrated, as `fuse --frame-list` writes them.
    std::vector<FrameListEntry> frames;
    for (const FusedFrame& r : records)
      frames.push_back({r.depth_path, r.color_path, r.T_W_C.matrix().cast<double>()});
    // The layout of `fuse --frame-list`, plus a VBG capacity sized from voxplan's map: VBG
    // allocates and touches all of it up front, so a guess would decide its RSS.
    const FrameListParams list_params{info.camera, info.depth_scale, o.voxel_size_m,
                                      o.trunc_m,   o.in.min_depth_m, o.in.max_depth_m};
    json list = json::parse(FrameListJson(list_params, frames, -1));
    list["vbg_block_count"] = std::max<size_t>(1024, rows.back().blocks * 5 / 4);
    TempFrameList list_file;
    if (Status s = list_file.Write(list); !s.ok()) return Fail(s.message());
    std::string poses_arg;
    for (size_t k : raycast_poses) poses_arg += (poses_arg.empty() ? "" : ",") + std::to_string(k);
    for (Row& row : rows) {
      // Ray casting exists only on the VBG path; the legacy run would add nothing.
      const std::vector<std::string> paths = mode == BenchMode::kRaycast
                                                 ? std::vector<std::string>{"vbg"}
                                                 : std::vector<std::string>{"legacy", "vbg"};
      for (const std::string& path : paths) {
        std::cerr << "open3d " << path << ", " << row.threads << " threads" << std::endl;
        Result<json> result = RunOpen3d(list_file.path(), path, row.threads, o.repeat, poses_arg);
        if (!result.ok()) return Fail(result.status().message());
        (path == "legacy" ? row.open3d_legacy : row.open3d_vbg) = *result;
      }
    }
  }

  // Rows as JSON, with Open3D's numbers and the ratios (> 1: voxplan is faster).
  json rows_json = json::array();
  for (const Row& row : rows) {
    const auto legacy_ms = JsonNumber(row.open3d_legacy, "open3d_legacy_ms_median");
    const auto vbg_ms = JsonNumber(row.open3d_vbg, "open3d_vbg_ms_median");
    const auto o3d_raycast = JsonNumber(row.open3d_vbg, "open3d_vbg_raycast_ms_median");
    const auto legacy_mesh = JsonNumber(row.open3d_legacy, "open3d_legacy_mesh_ms");
    const auto vbg_mesh = JsonNumber(row.open3d_vbg, "open3d_vbg_mesh_ms");
    const auto legacy_rss = JsonNumber(row.open3d_legacy, "open3d_legacy_peak_rss_mb");
    const auto vbg_rss = JsonNumber(row.open3d_vbg, "open3d_vbg_peak_rss_mb");
    const auto o3d_integrate = Min(legacy_ms, vbg_ms);
    const bool vbg_faster = vbg_ms && (!legacy_ms || *vbg_ms <= *legacy_ms);
    json r;
    r["threads"] = row.threads;
    r["integrate_ms_median"] = OptionalMs(row.integrate_median);
    r["integrate_ms_p90"] = OptionalMs(row.integrate_p90);
    json repeats = json::array();
    for (double v : row.integrate_repeat_medians) repeats.push_back(RoundTo(v, 3));
    r["integrate_repeat_medians_ms"] = repeats;
    r["load_ms_median"] = OptionalMs(row.load_median);
    r["raycast_ms_median"] = OptionalMs(row.raycast_median);
    r["raycast_hit_fraction"] =
        row.raycast_median ? json(RoundTo(row.raycast_hit_fraction, 4)) : json(nullptr);
    r["mesh_ms"] = OptionalMs(row.mesh_ms);
    r["mesh_incremental_ms_median"] = OptionalMs(row.mesh_update_median);
    r["mesh_triangles"] = row.mesh_ms ? json(row.mesh_triangles) : json(nullptr);
    r["blocks"] = row.blocks;
    r["voxels"] = row.voxels;
    r["bytes_per_voxel"] = RoundTo(row.bytes_per_voxel, 3);
    r["payload_bytes_per_voxel"] = TsdfVolume::BytesPerVoxel();
    r["map_mb"] = row.map_mb;
    r["peak_rss_mb"] = row.peak_rss_mb;
    r["open3d_legacy_ms_median"] = OptionalMs(legacy_ms);
    r["open3d_vbg_ms_median"] = OptionalMs(vbg_ms);
    r["open3d_raycast_ms_median"] = OptionalMs(o3d_raycast);
    r["open3d_legacy_mesh_ms"] = OptionalMs(legacy_mesh);
    r["open3d_vbg_mesh_ms"] = OptionalMs(vbg_mesh);
    r["open3d_mesh_ms"] = OptionalMs(Min(legacy_mesh, vbg_mesh));
    r["open3d_legacy_peak_rss_mb"] = legacy_rss ? json(*legacy_rss) : json(nullptr);
    r["open3d_vbg_peak_rss_mb"] = vbg_rss ? json(*vbg_rss) : json(nullptr);
    r["open3d_faster_path"] = o3d_integrate ? json(vbg_faster ? "vbg" : "legacy") : json(nullptr);
    const auto faster_rss = vbg_faster ? vbg_rss : legacy_rss;
    r["open3d_peak_rss_mb"] = faster_rss ? json(*faster_rss) : json(nullptr);
    r["open3d_vbg_bytes_per_voxel"] =
        row.open3d_vbg.is_object() ? row.open3d_vbg.value("open3d_vbg_bytes_per_voxel", json())
                                   : json(nullptr);
    r["speedup_integrate"] = Rounded2(Ratio(o3d_integrate, row.integrate_median));
    r["speedup_raycast"] = Rounded2(Ratio(o3d_raycast, row.raycast_median));
    r["speedup_mesh"] = Rounded2(Ratio(Min(legacy_mesh, vbg_mesh), row.mesh_ms));
    r["open3d_legacy"] = row.open3d_legacy;
    r["open3d_vbg"] = row.open3d_vbg;
    rows_json.push_back(r);
  }

  json j;
  j["command"] = std::string("bench ") + ModeName(mode);
  j["dataset"] = o.in.dataset;
  j["format"] = DatasetFormatName(info.format);
  j["frames"] = records.size();
  j["frames_selected"] = indices.size();
  j["frames_skipped_no_pose"] = skipped_no_pose;
  j["frames_skipped_no_depth"] = skipped_no_depth;
  j["stride"] = o.in.stride;
  j["voxel_size_m"] = o.voxel_size_m;
  j["trunc_m"] = o.trunc_m;
  j["min_depth_m"] = o.in.min_depth_m;
  j["max_depth_m"] = o.in.max_depth_m;
  j["repeat"] = o.repeat;
  j["threads"] = *thread_list;
  j["kernel"] = kernel_name;
  j["raycast_kernel"] = raycast_kernel_name;
  j["raycast_views"] = raycast_poses.size();
  j["raycast_pose_indexes"] = raycast_poses;
  j["camera"] = {{"width", info.camera.width},           {"height", info.camera.height},
                 {"fx", ShortestDouble(info.camera.fx)}, {"fy", ShortestDouble(info.camera.fy)},
                 {"cx", ShortestDouble(info.camera.cx)}, {"cy", ShortestDouble(info.camera.cy)}};
  j["vs_open3d"] = o.vs_open3d;
  j["machine"] = {{"nproc", Nproc()}, {"cpu_model", CpuModel()}};
  // The top level repeats the largest thread count's row.
  const json& top = rows_json.back();
  for (const char* key : {"integrate_ms_median",
                          "integrate_ms_p90",
                          "load_ms_median",
                          "raycast_ms_median",
                          "raycast_hit_fraction",
                          "mesh_ms",
                          "mesh_incremental_ms_median",
                          "mesh_triangles",
                          "blocks",
                          "voxels",
                          "bytes_per_voxel",
                          "payload_bytes_per_voxel",
                          "map_mb",
                          "peak_rss_mb",
                          "open3d_legacy_ms_median",
                          "open3d_vbg_ms_median",
                          "open3d_raycast_ms_median",
                          "open3d_legacy_mesh_ms",
                          "open3d_vbg_mesh_ms",
                          "open3d_mesh_ms",
                          "open3d_faster_path",
                          "open3d_peak_rss_mb",
                          "open3d_legacy_peak_rss_mb",
                          "open3d_vbg_peak_rss_mb",
                          "open3d_vbg_bytes_per_voxel",
                          "speedup_integrate",
                          "speedup_raycast",
                          "speedup_mesh"}) {
    j[key] = top.at(key);
  }
  auto scaling = [&](const std::optional<double> Row::*field) -> json {
    if (rows.size() < 2 || rows.front().threads != 1) return nullptr;
    return Rounded2(Ratio(rows.front().*field, rows.back().*field));
  };
  j["thread_scaling_integrate"] = scaling(&Row::integrate_median);
  j["thread_scaling_raycast"] = scaling(&Row::raycast_median);
  j["thread_scaling_mesh"] = scaling(&Row::mesh_ms);
  if (o.vs_open3d && !rows.empty()) {
    const json& any = rows.back().open3d_vbg;
    j["open3d_version"] = any.is_object() ? any.value("open3d_version", json()) : json(nullptr);
  }
  j["rows"] = rows_json;
  j["json"] = o.json_path.empty() ? json(nullptr) : json(o.json_path);

  // The human table.
  std::ostringstream table;
  table << "\n"
        << std::setw(7) << "threads" << std::setw(11) << "integ med" << std::setw(9) << "p90"
        << std::setw(8) << "load" << std::setw(9) << "raycast" << std::setw(9) << "mesh"
        << std::setw(10) << "o3d leg" << std::setw(9) << "o3d vbg" << std::setw(9) << "o3d ray"
        << std::setw(9) << "o3d mesh" << std::setw(8) << "x integ" << std::setw(7) << "x ray"
        << std::setw(8) << "x mesh"
        << "   (ms; x = Open3D's faster path / voxplan)\n";
  for (const json& r : rows_json) {
    auto v = [&](const char* key) -> std::optional<double> { return JsonNumber(r, key); };
    table << std::setw(7) << r.at("threads").get<int>() << std::setw(11)
          << Cell(v("integrate_ms_median")) << std::setw(9) << Cell(v("integrate_ms_p90"))
          << std::setw(8) << Cell(v("load_ms_median")) << std::setw(9)
          << Cell(v("raycast_ms_median")) << std::setw(9) << Cell(v("mesh_ms")) << std::setw(10)
          << Cell(v("open3d_legacy_ms_median")) << std::setw(9) << Cell(v("open3d_vbg_ms_median"))
          << std::setw(9) << Cell(v("open3d_raycast_ms_median")) << std::setw(9)
          << Cell(v("open3d_mesh_ms")) << std::setw(8) << Cell(v("speedup_integrate"))
          << std::setw(7) << Cell(v("speedup_raycast")) << std::setw(8) << Cell(v("speedup_mesh"))
          << "\n";
  }
  table << "map: " << top.at("blocks") << " blocks, " << top.at("map_mb") << " MiB, "
        << top.at("bytes_per_voxel") << " bytes/voxel (payload " << TsdfVolume::BytesPerVoxel()
        << "), peak RSS " << top.at("peak_rss_mb") << " MiB";
  if (o.vs_open3d) table << "; Open3D peak RSS " << top.at("open3d_peak_rss_mb") << " MiB";
  std::cerr << table.str() << std::endl;

  if (!o.json_path.empty()) {
    if (Status s = WriteJsonFile(j, o.json_path); !s.ok()) {
      return Fail(MessageNaming(s, o.json_path));
    }
    std::cerr << "json: " << o.json_path << "\n";
  }
  PrintJsonLine(j);
  return kExitOk;
}

void AddBenchOptions(CLI::App* sub, BenchOptions& o) {
  AddDatasetInputOptions(sub, o.in);
  sub->add_option("--voxel-size", o.voxel_size_m, "Voxel size in metres")
      ->check(Positive())
      ->capture_default_str();
  sub->add_option("--trunc", o.trunc_m, "Truncation distance in metres")
      ->check(Positive())
      ->capture_default_str();
  sub->add_option("--threads", o.threads,
                  "Comma-separated thread counts, one row each (default: 1 and all)");
  sub->add_option("--repeat", o.repeat, "Repeats per thread count (median reported)")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  sub->add_option("--kernel", o.kernel,
                  "Integration and ray-casting kernels: scalar reference or SIMD (auto: SIMD "
                  "where the CPU has AVX2)")
      ->check(CLI::IsMember({"auto", "scalar", "simd"}))
      ->capture_default_str();
  sub->add_flag("--vs-open3d", o.vs_open3d,
                "Also run Open3D (legacy and VoxelBlockGrid) on the same frames");
  sub->add_option("--json", o.json_path, "Write the result JSON")->check(OutputFileValidator());
}

}  // namespace

Command AddBenchCommand(CLI::App& app) {
  CLI::App* bench = app.add_subcommand("bench", "Benchmark fusion, ray casting and meshing");
  bench->require_subcommand(1);
  struct Parts {
    BenchOptions fusion, raycast, mesh;
    CLI::App *fusion_app = nullptr, *raycast_app = nullptr, *mesh_app = nullptr;
  };
  auto p = std::make_shared<Parts>();
  p->fusion_app = bench->add_subcommand(
      "fusion", "Time integration (per frame), ray casting and meshing per thread count");
  AddBenchOptions(p->fusion_app, p->fusion);
  p->raycast_app =
      bench->add_subcommand("raycast", "Fuse once per thread count (untimed), time ray casting");
  AddBenchOptions(p->raycast_app, p->raycast);
  p->mesh_app = bench->add_subcommand("mesh", "Fuse once per thread count (untimed), time meshing");
  AddBenchOptions(p->mesh_app, p->mesh);
  const Command maps = AddBenchMapsCommand(*bench);
  return {bench, [p, maps] {
            if (maps.app->parsed()) return maps.run();
            if (p->raycast_app->parsed()) return RunBench(p->raycast, BenchMode::kRaycast);
            if (p->mesh_app->parsed()) return RunBench(p->mesh, BenchMode::kMesh);
            return RunBench(p->fusion, BenchMode::kFusion);
          }};
}

}  // namespace voxplan::cli
