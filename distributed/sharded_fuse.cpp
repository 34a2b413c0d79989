#include "distributed/sharded_fuse.h"

#include <algorithm>
#include <array>
#include <map>

#include "core/stopwatch.h"
#include "core/summary.h"
#include "distributed/wire.h"
#include "fusion/mesh_block.h"

namespace voxplan {

namespace {

// ---- What travels: statuses, frames, blocks, mesh pieces -------------------------------------

void PutStatus(wire::Writer& w, const Status& s) {
  w.Put(uint8_t(s.code()));
  w.PutString(s.message());
}
Status GetStatus(wire::Reader& r) {
  uint8_t code = 0;
  std::string message;
  r.Get(code);
  r.GetString(message);
  if (!r.ok() || code == 0 || code > uint8_t(StatusCode::kCancelled))
    return CorruptData("malformed status from rank 0");
  return Status(StatusCode(code), message);
}

template <typename T>
void PutImage(wire::Writer& w, const Image<T>& image) {
  w.Put(int32_t(image.width));
  w.Put(int32_t(image.height));
  w.PutVector(image.data);
}
template <typename T>
bool GetImage(wire::Reader& r, Image<T>& image) {
  int32_t width = 0, height = 0;
  if (!r.Get(width) || !r.Get(height) || !r.GetVector(image.data)) return false;
  image.width = width;
  image.height = height;
  return size_t(std::max(width, 0)) * size_t(std::max(height, 0)) == image.data.size();
}

Bytes EncodeFrame(const Result<Frame>& result) {
  wire::Writer w;
  w.Put(uint8_t(result.ok()));
  if (!result.ok()) {
    PutStatus(w, result.status());
    return w.Take();
  }
  const Frame& f = *result;
  w.Put(uint64_t(f.index));
  w.Put(f.timestamp);
  PutImage(w, f.depth);
  PutImage(w, f.color);
  w.Put(uint8_t(f.T_W_C.has_value()));
  if (f.T_W_C) {
    std::array<double, 16> m;
    std::copy(f.T_W_C->matrix().data(), f.T_W_C->matrix().data() + 16, m.begin());
    w.Put(m);
  }
  w.Put(uint8_t(f.pose_rejected));
  w.PutString(f.pose_rejected_why);
  w.PutString(f.depth_path);
  w.PutString(f.color_path);
  return w.Take();
}

Result<Frame> DecodeFrame(const Bytes& bytes) {
  wire::Reader r(bytes);
  uint8_t ok = 0;
  r.Get(ok);
  if (!ok) return GetStatus(r);
  Frame f;
  uint64_t index = 0;
  uint8_t has_pose = 0, rejected = 0;
  r.Get(index);
  r.Get(f.timestamp);
  if (!GetImage(r, f.depth) || !GetImage(r, f.color))
    return CorruptData("malformed frame from rank 0");
  r.Get(has_pose);
  if (has_pose) {
    std::array<double, 16> m{};
    r.Get(m);
    f.T_W_C = Pose3d(Eigen::Map<const Eigen::Matrix4d>(m.data()));
  }
  r.Get(rejected);
  r.GetString(f.pose_rejected_why);
  r.GetString(f.depth_path);
  r.GetString(f.color_path);
  VOXPLAN_RETURN_IF_ERROR(r.Finish("frame from rank 0"));
  if (rejected > uint8_t(PoseRejection::kGroundTruthGap))
    return CorruptData("malformed frame from rank 0");
  f.index = size_t(index);
  f.pose_rejected = PoseRejection(rejected);
  return f;
}

// Frames come from rank 0; the dataset is never read on the other ranks.
class RelayedDataset final : public Dataset {
 public:
  explicit RelayedDataset(const DatasetInfo& info) : info_(info) {}
  const DatasetInfo& info() const override { return info_; }
  Result<Frame> Load(size_t) const override {
    return Unsupported("frames of a sharded run are read on rank 0");
  }

 private:
  const DatasetInfo& info_;
};

void PutBlock(wire::Writer& w, BlockIndex b, const TsdfBlock& block) {
  w.Put(b);
  w.Put(block);
}

void PutPiece(wire::Writer& w, BlockIndex b, const internal::BlockMesh& piece) {
  w.Put(b);
  w.PutVector(piece.keys);
  w.PutVector(piece.shared);
  std::vector<std::array<float, 3>> positions(piece.positions.size());
  for (size_t i = 0; i < positions.size(); ++i)
    positions[i] = {piece.positions[i].x(), piece.positions[i].y(), piece.positions[i].z()};
  w.PutVector(positions);
  w.PutVector(piece.colors);
  w.PutVector(piece.triangles);
}
bool GetPiece(wire::Reader& r, BlockIndex& b, internal::BlockMesh& piece) {
  std::vector<std::array<float, 3>> positions;
  if (!(r.Get(b) && r.GetVector(piece.keys) && r.GetVector(piece.shared) &&
        r.GetVector(positions) && r.GetVector(piece.colors) && r.GetVector(piece.triangles) &&
        piece.shared.size() == piece.keys.size() && positions.size() == piece.keys.size()))
    return false;
  piece.positions.resize(positions.size());
  for (size_t i = 0; i < positions.size(); ++i)
    piece.positions[i] = {positions[i][0], positions[i][1], positions[i][2]};
  // Triangles index this piece's vertices only.
  for (const auto& t : piece.triangles)
    for (uint32_t v : t)
      if (v >= piece.keys.size()) return false;
  return true;
}

// Every rank's share of the band walk to the blocks' owners: each sends the blocks it found to
// their owners and merges what it receives (each list sorted, so the union is too, deduplicated).
class CommBandExchange final : public BandExchange {
 public:
  explicit CommBandExchange(Communicator& comm) : comm_(comm) {}
  Result<std::vector<BlockIndex>> Exchange(const std::vector<BlockIndex>& found) override {
    const uint32_t ranks = uint32_t(comm_.size());
    std::vector<std::vector<BlockIndex>> to(ranks);
    for (const BlockIndex& b : found) to[BlockOwner(b, ranks)].push_back(b);
    std::vector<Bytes> out(ranks);
    for (uint32_t r = 0; r < ranks; ++r) {
      wire::Writer w;
      w.PutVector(to[r]);
      out[r] = w.Take();
    }
    Result<std::vector<Bytes>> in = comm_.AllToAll(out);
    if (!in.ok()) return in.status();
    std::vector<BlockIndex> owned;
    for (const Bytes& bytes : *in) {
      wire::Reader r(bytes);
      std::vector<BlockIndex> part;
      r.GetVector(part);
      VOXPLAN_RETURN_IF_ERROR(r.Finish("band blocks from another rank"));
      owned.insert(owned.end(), part.begin(), part.end());
    }
    std::sort(owned.begin(), owned.end());
    owned.erase(std::unique(owned.begin(), owned.end()), owned.end());
    return owned;
  }

 private:
  Communicator& comm_;
};

// ---- Checkpoints ------------------------------------------------------------------------------

// `resumed` then `more`, as one run's report.
FuseReport Concatenate(const FuseReport& resumed, const FuseReport& more) {
  FuseReport r = resumed;
  r.frames.insert(r.frames.end(), more.frames.begin(), more.frames.end());
  r.frames_selected += more.frames_selected;
  r.skipped_no_pose += more.skipped_no_pose;
  r.skipped_no_depth += more.skipped_no_depth;
  r.skipped_bad_pose += more.skipped_bad_pose;
  r.skipped_pose_gap += more.skipped_pose_gap;
  if (resumed.frames.empty()) {
    r.first_frames_median_depth_m = more.first_frames_median_depth_m;
    r.suggested_depth_scale = more.suggested_depth_scale;
  }
  r.frames_lost += more.frames_lost;
  r.blocks_refused += more.blocks_refused;
  r.frames_over_budget += more.frames_over_budget;
  const auto append = [](std::vector<double>& a, const std::vector<double>& b) {
    a.insert(a.end(), b.begin(), b.end());
  };
  append(r.load_ms, more.load_ms);
  append(r.integrate_ms, more.integrate_ms);
  append(r.frame_ms, more.frame_ms);
  append(r.track_ms, more.track_ms);
  append(r.collect_ms, more.collect_ms);
  append(r.exchange_ms, more.exchange_ms);
  append(r.update_ms, more.update_ms);
  r.loop_s += more.loop_s;
  return r;
}

}  // namespace

nlohmann::json CheckpointRun(const ShardedFuseParams& params, size_t done,
                             const FuseReport& report) {
  return {{"fingerprint", params.fingerprint},
          {"frames_done", done},
          {"report", FuseReportToJson(report)}};
}

nlohmann::json FuseReportToJson(const FuseReport& report) {
  nlohmann::json frames = nlohmann::json::array();
  for (const FusedFrame& f : report.frames) {
    std::vector<float> m(f.T_W_C.matrix().data(), f.T_W_C.matrix().data() + 16);
    frames.push_back({{"index", f.index},
                      {"timestamp_s", f.timestamp_s},
                      {"T_W_C", m},
                      {"depth", f.depth_path},
                      {"color", f.color_path}});
  }
  return {{"frames", frames},
          {"frames_selected", report.frames_selected},
          {"skipped_no_pose", report.skipped_no_pose},
          {"skipped_no_depth", report.skipped_no_depth},
          {"skipped_bad_pose", report.skipped_bad_pose},
          {"skipped_pose_gap", report.skipped_pose_gap},
          {"first_frames_median_depth_m", report.first_frames_median_depth_m},
          {"suggested_depth_scale", report.suggested_depth_scale},
          {"frames_lost", report.frames_lost},
          {"blocks_refused", report.blocks_refused},
          {"frames_over_budget", report.frames_over_budget},
          {"load_ms", report.load_ms},
          {"integrate_ms", report.integrate_ms},
          {"frame_ms", report.frame_ms},
          {"track_ms", report.track_ms},
          {"collect_ms", report.collect_ms},
          {"exchange_ms", report.exchange_ms},
          {"update_ms", report.update_ms},
          {"loop_s", report.loop_s}};
}

Result<FuseReport> FuseReportFromJson(const nlohmann::json& j) {
  try {
    FuseReport r;
    for (const nlohmann::json& f : j.at("frames")) {
      FusedFrame frame;
      frame.index = f.at("index").get<size_t>();
      frame.timestamp_s = f.at("timestamp_s").get<double>();
      const std::vector<float> m = f.at("T_W_C").get<std::vector<float>>();
      if (m.size() != 16) return CorruptData("a pose needs 16 values");
      frame.T_W_C.matrix() = Eigen::Map<const Eigen::Matrix4f>(m.data());
      frame.depth_path = f.at("depth").get<std::string>();
      frame.color_path = f.at("color").get<std::string>();
      r.frames.push_back(std::move(frame));
    }
    r.frames_selected = j.at("frames_selected").get<size_t>();
    r.skipped_no_pose = j.at("skipped_no_pose").get<size_t>();
    r.skipped_no_depth = j.at("skipped_no_depth").get<size_t>();
    r.skipped_bad_pose = j.at("skipped_bad_pose").get<size_t>();
    r.skipped_pose_gap = j.at("skipped_pose_gap").get<size_t>();
    r.first_frames_median_depth_m = j.at("first_frames_median_depth_m").get<double>();
    r.suggested_depth_scale = j.at("suggested_depth_scale").get<double>();
    r.frames_lost = j.at("frames_lost").get<size_t>();
    r.blocks_refused = j.at("blocks_refused").get<size_t>();
    r.frames_over_budget = j.at("frames_over_budget").get<size_t>();
    r.load_ms = j.at("load_ms").get<std::vector<double>>();
    r.integrate_ms = j.at("integrate_ms").get<std::vector<double>>();
    r.frame_ms = j.at("frame_ms").get<std::vector<double>>();
    r.track_ms = j.at("track_ms").get<std::vector<double>>();
    r.collect_ms = j.at("collect_ms").get<std::vector<double>>();
    r.exchange_ms = j.at("exchange_ms").get<std::vector<double>>();
    r.update_ms = j.at("update_ms").get<std::vector<double>>();
    r.loop_s = j.at("loop_s").get<double>();
    return r;
  } catch (const nlohmann::json::exception& e) {
    return CorruptData(std::string("checkpoint report: missing or mistyped field (") + e.what() +
                       ")");
  }
}

Status ShareDatasetInfo(Communicator& comm, DatasetInfo& info, std::vector<size_t>& indices) {
  wire::Writer w;
  if (comm.is_root()) {
    w.Put(info.format);
    w.PutString(info.root);
    w.Put(info.camera);
    w.Put(info.depth_scale);
    w.Put(uint64_t(info.num_frames));
    w.Put(uint8_t(info.has_color));
    w.PutString(info.intrinsics_source);
    w.PutString(info.pose_source);
    w.Put(info.up);
    w.PutString(info.up_source);
    w.PutString(info.depth_encoding);
    w.Put(uint8_t(info.depth_metres));
    w.Put(uint64_t(info.frames_bad_pose));
    w.PutString(info.streams);
    std::vector<uint64_t> selected(indices.begin(), indices.end());
    w.PutVector(selected);
  }
  Bytes bytes = w.Take();
  VOXPLAN_RETURN_IF_ERROR(comm.Broadcast(bytes, 0));
  if (comm.is_root()) return Status::Ok();
  wire::Reader r(bytes);
  uint64_t num_frames = 0;
  uint8_t has_color = 0;
  std::vector<uint64_t> selected;
  r.Get(info.format);
  r.GetString(info.root);
  r.Get(info.camera);
  r.Get(info.depth_scale);
  r.Get(num_frames);
  r.Get(has_color);
  r.GetString(info.intrinsics_source);
  r.GetString(info.pose_source);
  r.Get(info.up);
  r.GetString(info.up_source);
  uint8_t depth_metres = 0;
  uint64_t frames_bad_pose = 0;
  r.GetString(info.depth_encoding);
  r.Get(depth_metres);
  r.Get(frames_bad_pose);
  r.GetString(info.streams);
  r.GetVector(selected);
  VOXPLAN_RETURN_IF_ERROR(r.Finish("dataset description from rank 0"));
  info.num_frames = size_t(num_frames);
  info.has_color = has_color != 0;
  info.depth_metres = depth_metres != 0;
  info.frames_bad_pose = size_t(frames_bad_pose);
  indices.assign(selected.begin(), selected.end());
  return Status::Ok();
}

Result<ShardedFuseReport> FuseDatasetSharded(Communicator& comm, const Dataset* dataset,
                                             const DatasetInfo& info,
                                             const std::vector<size_t>& indices,
                                             const ShardedFuseParams& params, TsdfVolume& local,
                                             const FuseObserver& observer) {
  Status refused = Status::Ok();
  if (params.fuse.track && comm.size() > 1)
    refused = Unsupported(
        "--track under mpirun: tracking needs a ray cast of the whole model every frame, which "
        "a split map holds on every rank; fuse with tracking in one process, or with the "
        "dataset's poses under mpirun");
  else if (comm.is_root() && !dataset)
    refused = InvalidArgument("rank 0 needs the dataset");
  else if (params.resume && params.checkpoint_path.empty())
    refused = InvalidArgument("resume needs the checkpoint's path");
  VOXPLAN_RETURN_IF_ERROR(AgreeOnStatus(comm, refused));

  ShardedFuseReport out;
  FuseReport resumed;
  size_t start = 0;
  if (params.resume) {
    // Every rank reads the manifest and keeps the blocks it owns under this rank count.
    ShardManifest manifest;
    Result<TsdfVolume> loaded = LoadShardedMap(
        params.checkpoint_path, ShardSpec{uint32_t(comm.rank()), uint32_t(comm.size())}, &manifest);
    Status s = loaded.ok() ? Status::Ok() : loaded.status();
    if (s.ok() &&
        (loaded->voxel_size_m() != local.voxel_size_m() || loaded->trunc_m() != local.trunc_m()))
      s = InvalidArgument("checkpoint " + params.checkpoint_path +
                          " has another voxel size or truncation than this run");
    const nlohmann::json run = nlohmann::json::parse(manifest.run_json, nullptr, false);
    if (s.ok() &&
        (!run.is_object() || run.value("fingerprint", nlohmann::json()) != params.fingerprint))
      s = InvalidArgument("checkpoint " + params.checkpoint_path +
                          " is of another run (dataset, frames or parameters differ): start "
                          "again without --resume");
    if (s.ok()) {
      start = run.value("frames_done", size_t(0));
      if (start > indices.size())
        s = CorruptData("checkpoint " + params.checkpoint_path + " has done more frames (" +
                        std::to_string(start) + ") than this run selects");
    }
    if (s.ok()) {
      Result<FuseReport> report = FuseReportFromJson(run.value("report", nlohmann::json()));
      if (report.ok())
        resumed = std::move(*report);
      else
        s = report.status().WithContext(params.checkpoint_path);
    }
    VOXPLAN_RETURN_IF_ERROR(AgreeOnStatus(comm, s));
    // Copied into `local`, whose memory budget then applies to the blocks this run adds.
    loaded->ForEachBlock(
        [&](BlockIndex b, const TsdfBlock& block) { local.FindOrAllocate(b) = block; });
    out.frames_resumed = start;
  }
  FuseParams fuse = params.fuse;
  fuse.integrate.shard = {uint32_t(comm.rank()), uint32_t(comm.size())};
  CommBandExchange exchange(comm);
  if (params.split_band_walk && comm.size() > 1) fuse.integrate.band_exchange = &exchange;
  const std::vector<size_t> rest(indices.begin() + std::ptrdiff_t(start), indices.end());
  FuseObserver shifted = observer;
  if (observer.progress)
    shifted.progress = [&](size_t done, size_t) {
      observer.progress(start + done, indices.size());
    };

  FrameRelay relay;
  const bool split = comm.size() > 1;
  if (split && comm.is_root()) {
    relay.send = [&](const Result<Frame>& frame) {
      Bytes bytes = EncodeFrame(frame);
      const Stopwatch clock;
      Status s = comm.Broadcast(bytes, 0);
      out.broadcast_ms.push_back(clock.ElapsedMs());
      out.broadcast_bytes += bytes.size();
      return s;
    };
  } else if (split) {
    relay.receive = [&]() -> Result<Frame> {
      Bytes bytes;
      if (Status s = comm.Broadcast(bytes, 0); !s.ok()) return s;
      return DecodeFrame(bytes);
    };
  }
  if (split) relay.agree = [&](const Status& s) { return AgreeOnStatus(comm, s); };
  if (params.checkpoint_every > 0 && !params.checkpoint_path.empty()) {
    relay.frame_done = [&](size_t done, const FuseReport& so_far) -> Status {
      if (done % params.checkpoint_every != 0 || start + done == indices.size())
        return Status::Ok();
      const size_t total_done = start + done;
      FuseReport merged = Concatenate(resumed, so_far);
      merged.frames_selected = total_done;  // so far: the frames done, not the run's selection
      Result<ShardManifest> written =
          WriteShardedMap(comm, local, params.checkpoint_path, total_done, /*complete=*/false,
                          CheckpointRun(params, total_done, merged), info.up);
      return written.ok() ? Status::Ok() : written.status();
    };
  }
  const RelayedDataset relayed(info);
  const Dataset& source = comm.is_root() ? *dataset : relayed;
  Result<FuseReport> fused = FuseDataset(source, rest, fuse, local, shifted, &relay);
  // A failure before the first agreement (invalid parameters) is the same on every rank.
  if (!fused.ok()) return fused.status();
  out.report = Concatenate(resumed, *fused);
  return out;
}

Result<Mesh> ExtractMeshSharded(Communicator& comm, TsdfVolume& local, const MeshParams& params) {
  const uint32_t ranks = uint32_t(comm.size());
  const std::vector<BlockIndex> own = local.SortedBlockIndices();
  // The halo: neighbours of our blocks that other ranks own, asked of their owners.
  std::vector<std::vector<BlockIndex>> wanted(ranks);
  for (const BlockIndex& b : own)
    for (const BlockIndex& n : MeshStencilNeighbours(b))
      if (const uint32_t owner = BlockOwner(n, ranks); owner != uint32_t(comm.rank()))
        wanted[owner].push_back(n);
  std::vector<Bytes> asks(ranks);
  for (uint32_t r = 0; r < ranks; ++r) {
    std::sort(wanted[r].begin(), wanted[r].end());
    wanted[r].erase(std::unique(wanted[r].begin(), wanted[r].end()), wanted[r].end());
    wire::Writer w;
    w.PutVector(wanted[r]);
    asks[r] = w.Take();
  }
  Result<std::vector<Bytes>> asked = comm.AllToAll(asks);
  if (!asked.ok()) return asked.status();
  std::vector<Bytes> answers(ranks);
  Status malformed = Status::Ok();
  for (uint32_t r = 0; r < ranks; ++r) {
    wire::Reader reader((*asked)[r]);
    std::vector<BlockIndex> blocks;
    reader.GetVector(blocks);
    if (Status s = reader.Finish("halo request"); !s.ok()) malformed = s;
    wire::Writer w;
    for (const BlockIndex& b : blocks)
      if (const TsdfBlock* block = local.FindBlock(b)) PutBlock(w, b, *block);
    answers[r] = w.Take();
  }
  Result<std::vector<Bytes>> halo = comm.AllToAll(answers);
  if (!halo.ok()) return halo.status();
  std::vector<BlockIndex> halo_blocks;
  for (uint32_t r = 0; r < ranks && malformed.ok(); ++r) {
    if (r == uint32_t(comm.rank())) continue;
    wire::Reader reader((*halo)[r]);
    while (!reader.at_end()) {
      BlockIndex b;
      TsdfBlock block;
      if (!reader.Get(b) || !reader.Get(block)) {
        malformed = CorruptData("malformed halo from rank " + std::to_string(r));
        break;
      }
      local.FindOrAllocate(b) = block;
      halo_blocks.push_back(b);
    }
  }
  std::vector<internal::BlockMesh> pieces;
  if (malformed.ok()) pieces = MeshBlockPieces(local, own, params);
  for (const BlockIndex& b : halo_blocks) local.EraseBlock(b);
  VOXPLAN_RETURN_IF_ERROR(AgreeOnStatus(comm, malformed));

  wire::Writer w;
  for (size_t i = 0; i < own.size(); ++i)
    if (!pieces[i].triangles.empty()) PutPiece(w, own[i], pieces[i]);
  pieces.clear();
  Result<std::vector<Bytes>> gathered = comm.Gather(w.Take(), 0);
  if (!gathered.ok()) return gathered.status();
  if (!comm.is_root()) return Mesh{};
  // Each block has one owner, so sorting the pieces by block gives ExtractMesh's order.
  std::vector<std::pair<BlockIndex, internal::BlockMesh>> all;
  for (size_t r = 0; r < gathered->size(); ++r) {
    wire::Reader reader((*gathered)[r]);
    while (!reader.at_end()) {
      all.emplace_back();
      if (!GetPiece(reader, all.back().first, all.back().second))
        return CorruptData("malformed mesh pieces from rank " + std::to_string(r));
    }
    (*gathered)[r].clear();
  }
  std::sort(all.begin(), all.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<const internal::BlockMesh*> pointers;
  pointers.reserve(all.size());
  for (const auto& [b, piece] : all) pointers.push_back(&piece);
  return AssembleMeshPieces(pointers, params);
}

Result<std::vector<RankFigures>> GatherRankFigures(Communicator& comm, const TsdfVolume& local) {
  const RankFigures mine{uint64_t(local.num_blocks()), uint64_t(local.MemoryBytes()),
                         uint64_t(local.blocks_refused()), PeakRssMb()};
  wire::Writer w;
  w.Put(mine);
  Result<std::vector<Bytes>> all = comm.Gather(w.Take(), 0);
  if (!all.ok()) return all.status();
  std::vector<RankFigures> out;
  for (const Bytes& b : *all) {
    wire::Reader r(b);
    RankFigures f;
    r.Get(f);
    VOXPLAN_RETURN_IF_ERROR(r.Finish("rank figures"));
    out.push_back(f);
  }
  return out;
}

}  // namespace voxplan
