// voxplan eval objects: per-object quality of a reconstruction against a world with instances
// (Guo 2022 O-Comp, O-RMS).
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>

#include "apps/voxplan/cli_common.h"
#include "core/parallel.h"
#include "eval/eval_objects.h"
#include "io/mesh_io.h"

namespace voxplan::cli {

namespace {

namespace fs = std::filesystem;

std::vector<std::string> SplitList(const std::string& text) {
  std::vector<std::string> items;
  std::stringstream stream(text);
  std::string item;
  while (std::getline(stream, item, ',')) {
    if (!item.empty()) items.push_back(item);
  }
  return items;
}

struct EvalObjectsOptions {
  std::string reconstruction;
  SceneOptions scene;
  double threshold_m = 0.05;
  double samples_per_m2 = 10000.0;
  size_t min_samples = 200;
  uint64_t seed = 1;
  double max_attribution_m = 0.0;  // 0: no limit
  std::string exclude = "wall,floor,ceiling,door,window,structure";
  int threads = 0;
  bool any_world = false;
};

int RunEvalObjects(const EvalObjectsOptions& o) {
  std::error_code ec;
  if (!fs::is_regular_file(o.reconstruction, ec))
    return Fail("mesh file not found: " + o.reconstruction);
  ThreadLimit thread_limit(o.threads);
  Result<Mesh> reconstruction = ReadMesh(o.reconstruction);
  if (!reconstruction.ok()) return Fail(MessageNaming(reconstruction.status(), o.reconstruction));
  Result<World> world = LoadScene(o.scene);
  if (!world.ok()) return Fail(world.status().message());
  if (int code = CheckSceneIsRunWorld(o.reconstruction, *world, o.any_world); code != kExitOk)
    return code;
  if (world->instances.empty())
    return Fail(o.scene.scene + ": the world has no instances (no instance table beside it?)");

  ObjectEvalParams params;
  params.threshold_m = float(o.threshold_m);
  params.samples_per_m2 = float(o.samples_per_m2);
  params.min_samples_per_object = o.min_samples;
  params.seed = o.seed;
  if (o.max_attribution_m > 0.0) params.max_attribution_distance_m = float(o.max_attribution_m);
  params.excluded_classes = SplitList(o.exclude);
  const Stopwatch clock;
  std::optional<Progress> bar;
  params.progress = [&bar](size_t done, size_t total) {
    if (!bar) bar.emplace("eval objects", total, "steps");
    bar->Update(done);
  };
  Result<ObjectsEvalResult> result = EvaluateObjects(*reconstruction, *world, params);
  if (bar) bar->Finish();
  if (!result.ok()) return Fail("evaluation failed: " + result.status().message());
  const ObjectsEvalResult& r = *result;

  nlohmann::json objects = nlohmann::json::array();
  for (const ObjectEvalResult& object : r.objects) {
    std::cerr << "  " << object.id << " " << object.class_name << " (" << object.model
              << "): completeness " << RoundTo(100.0 * object.completeness, 1) << " %";
    if (object.reconstruction_samples > 0)
      std::cerr << ", accuracy " << RoundTo(object.accuracy_mean_m * 1000, 2) << " mm";
    std::cerr << "\n";
    nlohmann::json j;
    j["id"] = object.id;
    j["class"] = object.class_name;
    j["model"] = object.model;
    j["ground_truth_area_m2"] = object.ground_truth_area_m2;
    j["ground_truth_samples"] = object.ground_truth_samples;
    j["completeness"] = object.completeness;
    j["reconstruction_samples"] = object.reconstruction_samples;
    // No reconstruction, no accuracy: null rather than a misleading 0.
    j["accuracy_mean_m"] =
        object.reconstruction_samples > 0 ? nlohmann::json(object.accuracy_mean_m) : nullptr;
    j["accuracy_rms_m"] =
        object.reconstruction_samples > 0 ? nlohmann::json(object.accuracy_rms_m) : nullptr;
    objects.push_back(j);
  }
  std::cerr << r.objects.size() << " objects (" << r.objects_reconstructed
            << " reconstructed): O-Comp " << RoundTo(100.0 * r.o_comp, 2) << " % within "
            << o.threshold_m << " m, O-RMS " << RoundTo(r.o_rms_m * 1000, 2) << " mm\n";
  if (!r.skipped.empty())
    Warn(std::to_string(r.skipped.size()) + " instances have no surface and were skipped");

  nlohmann::json j;
  j["command"] = "eval objects";
  j["reconstruction"] = o.reconstruction;
  j["scene"] = o.scene.scene;
  j["objects_evaluated"] = r.objects.size();
  j["objects_reconstructed"] = r.objects_reconstructed;
  j["o_comp"] = r.o_comp;
  j["o_comp_percent"] = RoundTo(100.0 * r.o_comp, 3);
  j["o_rms_m"] = r.o_rms_m;
  j["mean_object_rms_m"] = r.mean_object_rms_m;
  j["completeness_all_objects"] = r.completeness_all_objects;
  j["reconstruction_samples"] = r.reconstruction_samples;
  j["reconstruction_samples_unattributed"] = r.reconstruction_samples_unattributed;
  j["skipped_instances"] = r.skipped;
  j["excluded_classes"] = params.excluded_classes;
  j["threshold_m"] = o.threshold_m;
  j["samples_per_m2"] = o.samples_per_m2;
  j["seed"] = o.seed;
  j["objects"] = objects;
  j["eval_ms"] = RoundTo(clock.ElapsedMs(), 3);
  PrintJsonLine(j);
  return kExitOk;
}

}  // namespace

Command AddEvalObjectsCommand(CLI::App& eval) {
  auto o = std::make_shared<EvalObjectsOptions>();
  CLI::App* objects = eval.add_subcommand(
      "objects", "Per-object completeness and accuracy against a world with instances");
  objects->add_option("reconstruction", o->reconstruction, "Reconstructed mesh")->required();
  AddSceneOptions(objects, &o->scene, /*required=*/true);
  objects->add_flag("--any-world", o->any_world,
                    "Score against --scene even when it is not the world the run's metrics.json "
                    "names");
  objects->add_option("--threshold", o->threshold_m, "Completeness distance threshold (m)")
      ->check(InRange(1e-4, 10.0, "m"))
      ->capture_default_str();
  objects->add_option("--samples-per-m2", o->samples_per_m2, "Surface samples per square metre")
      ->check(InRange(1.0, 1e6))
      ->capture_default_str();
  objects->add_option("--min-samples", o->min_samples, "Fewest ground-truth samples per object")
      ->check(IntInRange(1, int64_t(1) << 30))
      ->capture_default_str();
  objects->add_option("--seed", o->seed, "Sampling seed")->capture_default_str();
  objects
      ->add_option("--max-attribution", o->max_attribution_m,
                   "Reconstruction farther than this (m) from all ground truth belongs to no "
                   "object (0: no limit)")
      ->check(InRange(0.0, 1e4, "m"))
      ->capture_default_str();
  objects
      ->add_option("--exclude-classes", o->exclude,
                   "Comma-separated instance classes that are not objects (empty: none)")
      ->capture_default_str();
  objects->add_option("--threads", o->threads, "Worker threads (0: all hardware threads)")
      ->check(ThreadCount())
      ->capture_default_str();
  return {objects, [o] { return RunEvalObjects(*o); }};
}

}  // namespace voxplan::cli
