// voxplan info: what a dataset folder or a map file holds, as the readers see it.
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>

#include "apps/voxplan/cli_common.h"
#include "core/block.h"
#include "io/dataset.h"
#include "io/map_io.h"
#include "io/sharded_map.h"

namespace voxplan::cli {

namespace {

namespace fs = std::filesystem;

struct InfoOptions {
  std::string path;
  std::string format = "auto";
  std::string topics;
};

int DatasetInfoCommand(const InfoOptions& o) {
  DatasetOptions options;
  Result<DatasetFormat> format = ParseDatasetFormat(o.format);
  if (!format.ok()) return Fail(format.status().message(), kExitUsage);
  options.format = *format;
  if (!o.topics.empty()) {
    Result<RosBagTopics> topics = ParseRosBagTopics(o.topics);
    if (!topics.ok()) return Fail(topics.status().message(), kExitUsage);
    options.topics = *topics;
  }
  Result<std::unique_ptr<Dataset>> dataset = OpenDataset(o.path, options);
  if (!dataset.ok()) return Fail(MessageNaming(dataset.status(), o.path));
  const DatasetInfo& info = (*dataset)->info();
  const PinholeCamera& c = info.camera;

  std::fprintf(stderr, "dataset     %s\n", info.root.c_str());
  std::fprintf(stderr, "format      %s\n", DatasetFormatName(info.format));
  std::fprintf(stderr, "frames      %zu\n", info.num_frames);
  std::fprintf(stderr, "image       %d x %d\n", c.width, c.height);
  std::fprintf(stderr, "intrinsics  fx %g  fy %g  cx %g  cy %g  (%s)\n", c.fx, c.fy, c.cx, c.cy,
               info.intrinsics_source.c_str());
  if (info.depth_metres)
    std::fprintf(stderr, "depth       %s, metres (the depth scale does not apply)\n",
                 info.depth_encoding.c_str());
  else if (info.depth_encoding.empty())
    std::fprintf(stderr, "depth scale %g units per metre\n", info.depth_scale);
  else
    std::fprintf(stderr, "depth scale %g units per metre (%s)\n", info.depth_scale,
                 info.depth_encoding.c_str());
  std::fprintf(stderr, "poses       %s\n", info.pose_source.c_str());
  std::fprintf(stderr, "up axis     %s (%s)\n", WorldUpName(info.up), info.up_source.c_str());
  if (info.frames_bad_pose > 0)
    std::fprintf(stderr,
                 "bad poses   %zu of %zu frames (not rigid, e.g. ScanNet's -inf: no pose)\n",
                 info.frames_bad_pose, info.num_frames);
  std::fprintf(stderr, "colour      %s\n", info.has_color ? "yes" : "no");
  if (!info.streams.empty()) std::fprintf(stderr, "topics      %s\n", info.streams.c_str());
  std::fprintf(stderr, "warnings    %zu\n", info.warnings.size());
  for (const std::string& w : info.warnings) std::fprintf(stderr, "  %s\n", w.c_str());
  std::fflush(stdout);

  nlohmann::json j;
  j["command"] = "info";
  j["kind"] = "dataset";
  j["path"] = o.path;
  j["root"] = info.root;
  j["format"] = DatasetFormatName(info.format);
  j["frames"] = info.num_frames;
  j["camera"] = CameraJson(c);
  j["intrinsics_source"] = info.intrinsics_source;
  j["depth_scale"] = info.depth_scale;
  j["depth_encoding"] =
      info.depth_encoding.empty() ? nlohmann::json(nullptr) : nlohmann::json(info.depth_encoding);
  j["depth_scale_applies"] = !info.depth_metres;
  j["pose_source"] = info.pose_source;
  j["up"] = WorldUpName(info.up);
  j["up_source"] = info.up_source;
  j["frames_bad_pose"] = info.frames_bad_pose;
  j["has_color"] = info.has_color;
  if (!info.streams.empty()) j["topics"] = info.streams;
  j["warnings"] = info.warnings;
  PrintJsonLine(j);
  return kExitOk;
}

// A sharded map (io/sharded_map.h): its manifest, then the shards loaded as one map.
int ShardedMapInfoCommand(const InfoOptions& o) {
  Result<ShardManifest> manifest = ReadShardManifest(o.path);
  if (!manifest.ok()) return Fail(MessageNaming(manifest.status(), o.path));
  Result<TsdfVolume> volume = LoadShardedMap(o.path);
  if (!volume.ok()) return Fail(MessageNaming(volume.status(), o.path));
  uint64_t file_bytes = 0;
  nlohmann::json shards = nlohmann::json::array();
  for (const ShardManifest::Shard& s : manifest->shards) {
    std::error_code ec;
    const auto bytes = fs::file_size(ShardFilePath(o.path, s.file), ec);
    file_bytes += ec ? 0 : uint64_t(bytes);
    shards.push_back({{"file", s.file}, {"blocks", s.blocks}});
  }
  std::fprintf(stderr, "map         %s (sharded: manifest)\n", o.path.c_str());
  std::fprintf(stderr, "shards      %u (owner %s)%s\n", manifest->ranks,
               manifest->owner_function.c_str(),
               manifest->complete ? "" : ", a checkpoint of an unfinished run");
  std::fprintf(stderr, "voxel size  %g m\n", manifest->params.voxel_size_m);
  std::fprintf(stderr, "truncation  %g m\n", manifest->params.trunc_m);
  std::fprintf(stderr, "up axis     %s\n", WorldUpName(manifest->up));
  std::fprintf(stderr, "blocks      %zu (%zu voxels)\n", volume->num_blocks(),
               volume->num_voxels());
  std::fprintf(stderr, "files       %.3f MiB in all\n", Mib(size_t(file_bytes)));
  nlohmann::json j;
  j["command"] = "info";
  j["kind"] = "sharded_map";
  j["path"] = o.path;
  j["ranks"] = manifest->ranks;
  j["complete"] = manifest->complete;
  j["generation"] = manifest->generation;
  j["owner_function"] = manifest->owner_function;
  j["voxel_size_m"] = ShortestDouble(manifest->params.voxel_size_m);
  j["trunc_m"] = ShortestDouble(manifest->params.trunc_m);
  j["up"] = WorldUpName(manifest->up);
  AddMapStats(j, *volume);
  j["checksum"] = std::to_string(VolumeChecksum(*volume));
  j["shards"] = shards;
  j["file_bytes"] = file_bytes;
  PrintJsonLine(j);
  return kExitOk;
}

int MapInfoCommand(const InfoOptions& o) {
  if (IsShardedMapFile(o.path)) return ShardedMapInfoCommand(o);
  Result<MapHeader> header = ReadMapHeader(o.path);
  if (!header.ok()) return Fail(MessageNaming(header.status(), o.path));
  Result<TsdfVolume> volume = LoadMap(o.path);
  if (!volume.ok()) return Fail(MessageNaming(volume.status(), o.path));

  size_t observed = 0;
  volume->ForEachBlock([&](BlockIndex, const TsdfBlock& block) {
    for (int v = 0; v < kBlockVoxels; ++v) observed += block.weight[v] > 0 ? 1 : 0;
  });
  std::error_code ec;
  const auto file_bytes = fs::file_size(o.path, ec);
  const double observed_percent =
      volume->num_voxels() > 0 ? 100.0 * double(observed) / double(volume->num_voxels()) : 0.0;

  std::fprintf(stderr, "map         %s\n", o.path.c_str());
  std::fprintf(stderr, "version     %u\n", header->version);
  std::fprintf(stderr, "voxel size  %g m\n", header->params.voxel_size_m);
  std::fprintf(stderr, "truncation  %g m\n", header->params.trunc_m);
  std::fprintf(stderr, "up axis     %s%s\n", WorldUpName(header->up),
               header->up == WorldUp::kUnknown ? " (render takes +z)" : "");
  std::fprintf(stderr, "blocks      %llu (%zu voxels, %zu observed, %.1f%%)\n",
               (unsigned long long)header->num_blocks, volume->num_voxels(), observed,
               observed_percent);
  std::fprintf(stderr, "memory      %.3f MiB (%.1f bytes per voxel)\n", Mib(volume->MemoryBytes()),
               TsdfVolume::BytesPerVoxel());
  std::fprintf(stderr, "file        %.3f MiB\n", Mib(ec ? 0 : size_t(file_bytes)));
  std::fflush(stdout);

  nlohmann::json j;
  j["command"] = "info";
  j["kind"] = "map";
  j["path"] = o.path;
  j["version"] = header->version;
  j["voxel_size_m"] = ShortestDouble(header->params.voxel_size_m);
  j["trunc_m"] = ShortestDouble(header->params.trunc_m);
  j["up"] = WorldUpName(header->up);
  AddMapStats(j, *volume);
  j["observed_voxels"] = observed;
  // Of the blocks alone (io/sharded_map.h): equal for equal maps, plain or sharded.
  j["checksum"] = std::to_string(VolumeChecksum(*volume));
  j["memory_bytes"] = volume->MemoryBytes();
  j["file_bytes"] = ec ? 0 : size_t(file_bytes);
  PrintJsonLine(j);
  return kExitOk;
}

int RunInfo(const InfoOptions& o) {
  std::error_code ec;
  if (fs::is_directory(o.path, ec)) return DatasetInfoCommand(o);
  if (fs::is_regular_file(o.path, ec) && IsDatasetFile(o.path)) return DatasetInfoCommand(o);
  if (fs::is_regular_file(o.path, ec)) return MapInfoCommand(o);
  return Fail("not found (want a dataset folder or file, or a .vpmap file): " + o.path);
}

}  // namespace

Command AddInfoCommand(CLI::App& app) {
  auto o = std::make_shared<InfoOptions>();
  CLI::App* sub = app.add_subcommand("info", "Describe a dataset folder or a map file");
  sub->add_option("path", o->path, "Dataset folder or file (.sens, .bag), or .vpmap file")
      ->required();
  sub->add_option("--format", o->format, "Dataset format (datasets only)")
      ->check(CLI::IsMember(
          {"auto", "tum", "icl", "redwood", "7scenes", "3dmatch", "replica", "scannet", "rosbag"}))
      ->capture_default_str();
  AddTopicsOption(sub, o->topics);
  return {sub, [o] { return RunInfo(*o); }};
}

}  // namespace voxplan::cli
