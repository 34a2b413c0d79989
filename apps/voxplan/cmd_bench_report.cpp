// `voxplan bench fusion|raycast|mesh`'s JSON and table: the harness's rows with Open3D's numbers
// beside them, the ratios, and the top level that repeats the largest thread count's row.
#include "apps/voxplan/cmd_bench_report.h"

#include <algorithm>
#include <iomanip>
#include <optional>
#include <sstream>

#include "apps/voxplan/cli_common.h"
#include "bench/harness/measure.h"
#include "core/volume.h"
#include "io/text_file.h"

namespace voxplan::cli {

namespace {

using bench::Cell;
using bench::FusionBenchResult;
using bench::FusionBenchRow;
using nlohmann::json;

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

// The keys the top level repeats from the largest thread count's row.
constexpr const char* kTopLevelKeys[] = {"integrate_ms_median",
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
                                         "speedup_mesh"};

// A row as JSON, with Open3D's numbers and the ratios (> 1: voxplan is faster).
json RowJson(const FusionBenchRow& row) {
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
  r["open3d_vbg_bytes_per_voxel"] = row.open3d_vbg.is_object()
                                        ? row.open3d_vbg.value("open3d_vbg_bytes_per_voxel", json())
                                        : json(nullptr);
  r["speedup_integrate"] = Rounded2(Ratio(o3d_integrate, row.integrate_median));
  r["speedup_raycast"] = Rounded2(Ratio(o3d_raycast, row.raycast_median));
  r["speedup_mesh"] = Rounded2(Ratio(Min(legacy_mesh, vbg_mesh), row.mesh_ms));
  r["open3d_legacy"] = row.open3d_legacy;
  r["open3d_vbg"] = row.open3d_vbg;
  return r;
}

}  // namespace

const char* RaycastKernelName(const RaycastParams& params) {
  return params.simd && RaycastSimdAvailable() ? "avx2" : "scalar";
}

json BenchJson(const BenchOptions& o, const bench::FusionBenchParams& fp, const DatasetInfo& info,
               size_t frames_selected, const FusionBenchResult& result) {
  const std::vector<FusionBenchRow>& rows = result.rows;
  json rows_json = json::array();
  for (const FusionBenchRow& row : rows) rows_json.push_back(RowJson(row));
  json j;
  j["command"] = std::string("bench ") + bench::BenchModeName(fp.mode);
  j["dataset"] = o.in.dataset;
  j["format"] = DatasetFormatName(info.format);
  j["frames"] = result.frames.size();
  j["frames_selected"] = frames_selected;
  j["frames_skipped_no_pose"] = result.skipped_no_pose;
  j["frames_skipped_no_depth"] = result.skipped_no_depth;
  j["stride"] = o.in.stride;
  j["voxel_size_m"] = o.voxel_size_m;
  j["trunc_m"] = o.trunc_m;
  j["min_depth_m"] = o.in.min_depth_m;
  j["max_depth_m"] = o.in.max_depth_m;
  j["repeat"] = o.repeat;
  j["threads"] = fp.threads;
  j["kernel"] = KernelName(ResolveKernel(fp.integrate.kernel));
  j["raycast_kernel"] = RaycastKernelName(fp.raycast);
  j["raycast_views"] = result.raycast_poses.size();
  j["raycast_pose_indexes"] = result.raycast_poses;
  j["camera"] = CameraJson(info.camera);
  j["vs_open3d"] = o.vs_open3d;
  j["machine"] = {{"nproc", bench::Nproc()}, {"cpu_model", bench::CpuModel()}};
  // The top level repeats the largest thread count's row.
  const json& top = rows_json.back();
  for (const char* key : kTopLevelKeys) j[key] = top.at(key);
  auto scaling = [&](const std::optional<double> FusionBenchRow::*field) -> json {
    if (rows.size() < 2 || rows.front().threads != 1) return nullptr;
    return Rounded2(Ratio(rows.front().*field, rows.back().*field));
  };
  j["thread_scaling_integrate"] = scaling(&FusionBenchRow::integrate_median);
  j["thread_scaling_raycast"] = scaling(&FusionBenchRow::raycast_median);
  j["thread_scaling_mesh"] = scaling(&FusionBenchRow::mesh_ms);
  if (o.vs_open3d && !rows.empty()) {
    const json& any = rows.back().open3d_vbg;
    j["open3d_version"] = any.is_object() ? any.value("open3d_version", json()) : json(nullptr);
  }
  j["rows"] = rows_json;
  j["json"] = o.json_path.empty() ? json(nullptr) : json(o.json_path);
  return j;
}

std::string BenchTable(const json& j, bool vs_open3d) {
  std::ostringstream table;
  table << "\n"
        << std::setw(7) << "threads" << std::setw(11) << "integ med" << std::setw(9) << "p90"
        << std::setw(8) << "load" << std::setw(9) << "raycast" << std::setw(9) << "mesh"
        << std::setw(10) << "o3d leg" << std::setw(9) << "o3d vbg" << std::setw(9) << "o3d ray"
        << std::setw(9) << "o3d mesh" << std::setw(8) << "x integ" << std::setw(7) << "x ray"
        << std::setw(8) << "x mesh"
        << "   (ms; x = Open3D's faster path / voxplan)\n";
  for (const json& r : j.at("rows")) {
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
  table << "map: " << j.at("blocks") << " blocks, " << j.at("map_mb") << " MiB, "
        << j.at("bytes_per_voxel") << " bytes/voxel (payload " << TsdfVolume::BytesPerVoxel()
        << "), peak RSS " << j.at("peak_rss_mb") << " MiB";
  if (vs_open3d) table << "; Open3D peak RSS " << j.at("open3d_peak_rss_mb") << " MiB";
  return table.str();
}

}  // namespace voxplan::cli
