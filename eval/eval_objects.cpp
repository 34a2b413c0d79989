#include "eval/eval_objects.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <unordered_map>

#include "eval/eval_mesh.h"

namespace voxplan {

namespace {

// Each object's samples depend only on the seed and its id, not on the other objects, so an
// object's numbers stay put when the world gains or loses instances.
uint64_t ObjectSeed(uint64_t seed, uint32_t id) {
  std::seed_seq seq{seed, uint64_t(2), uint64_t(id)};
  std::mt19937_64 rng(seq);
  return rng();
}

uint64_t ReconstructionSeed(uint64_t seed) {
  std::seed_seq seq{seed, uint64_t(0)};
  std::mt19937_64 rng(seq);
  return rng();
}

}  // namespace

Result<ObjectsEvalResult> EvaluateObjects(const Mesh& reconstruction, const World& world,
                                          const ObjectEvalParams& params) {
  if (!(params.samples_per_m2 > 0.f) || !std::isfinite(params.samples_per_m2))
    return InvalidArgument("EvaluateObjects: samples_per_m2 must be positive");
  for (float t : params.extra_thresholds_m)
    if (!(t >= 0.f) || !std::isfinite(t))
      return InvalidArgument("EvaluateObjects: thresholds must be non-negative");
  if (!(params.threshold_m >= 0.f) || !std::isfinite(params.threshold_m))
    return InvalidArgument("EvaluateObjects: threshold_m must be non-negative");
  if (!(params.max_attribution_distance_m >= 0.f))
    return InvalidArgument("EvaluateObjects: max_attribution_distance_m must be non-negative");
  if (world.triangle_instance.size() != world.mesh.num_triangles())
    return InvalidArgument("EvaluateObjects: world '" + world.name + "' has " +
                           std::to_string(world.triangle_instance.size()) +
                           " triangle instance ids for " +
                           std::to_string(world.mesh.num_triangles()) + " triangles");

  // Instance id -> index in world.instances, and each instance's triangles.
  std::unordered_map<uint32_t, size_t> index_of;
  for (size_t i = 0; i < world.instances.size(); ++i) {
    if (!index_of.emplace(world.instances[i].id, i).second)
      return InvalidArgument("EvaluateObjects: instance id " +
                             std::to_string(world.instances[i].id) + " appears twice");
  }
  std::vector<std::vector<uint32_t>> triangles_of(world.instances.size());
  for (size_t t = 0; t < world.triangle_instance.size(); ++t) {
    const uint32_t id = world.triangle_instance[t];
    if (id == kNoInstance) continue;
    const auto it = index_of.find(id);
    if (it == index_of.end())
      return InvalidArgument("EvaluateObjects: triangle " + std::to_string(t) +
                             " has instance id " + std::to_string(id) +
                             ", which is not in the instance table");
    triangles_of[it->second].push_back(uint32_t(t));
  }

  // Ground-truth samples of every object, one after another.
  ObjectsEvalResult result;
  std::vector<Eigen::Vector3d> truth_points;
  std::vector<size_t> first_sample;                        // per evaluated object
  std::vector<int> object_of(world.instances.size(), -1);  // instance index -> object index
  const size_t steps = world.instances.size() + 3;
  const auto report = [&](size_t done) {
    if (params.progress) params.progress(done, steps);
  };
  for (size_t i = 0; i < world.instances.size(); ++i) {
    report(i);
    const Instance& instance = world.instances[i];
    const auto& excluded = params.excluded_classes;
    if (std::find(excluded.begin(), excluded.end(), instance.class_name) != excluded.end())
      continue;
    if (triangles_of[i].empty()) {
      result.skipped.push_back(instance.id);
      continue;
    }
    Result<SurfaceSamples> samples = SampleSurface(
        world.mesh, params.samples_per_m2, ObjectSeed(params.seed, instance.id), triangles_of[i],
        params.min_samples_per_object, "EvaluateObjects: instance " + std::to_string(instance.id));
    if (!samples.ok()) {
      // Triangles without area are no surface to reconstruct; anything else is bad data.
      if (samples.status().message().find("no triangle with area") == std::string::npos)
        return samples.status();
      result.skipped.push_back(instance.id);
      continue;
    }
    ObjectEvalResult object;
    object.id = instance.id;
    object.class_name = instance.class_name;
    object.model = instance.model;
    object.ground_truth_area_m2 = samples->area_m2;
    object.ground_truth_samples = samples->points.size();
    object_of[i] = int(result.objects.size());
    result.objects.push_back(std::move(object));
    first_sample.push_back(truth_points.size());
    truth_points.insert(truth_points.end(), samples->points.begin(), samples->points.end());
  }
  if (result.objects.empty())
    return InvalidArgument("EvaluateObjects: world '" + world.name +
                           "' has no object to evaluate after excluding structure classes");
  first_sample.push_back(truth_points.size());

  // O-Comp (eq. 6): ground-truth samples within the threshold of the reconstruction.
  std::vector<double> coverage;
  {  // one tree at a time, to bound peak memory on large meshes
    Result<SurfaceDistance> recon_surface =
        SurfaceDistance::Build(reconstruction, "EvaluateObjects: reconstruction");
    if (!recon_surface.ok()) return recon_surface.status();
    coverage = recon_surface->Distances(truth_points);
  }
  report(world.instances.size() + 1);
  const double threshold = double(params.threshold_m);
  size_t covered_all = 0;
  for (size_t k = 0; k < result.objects.size(); ++k) {
    const double n = double(first_sample[k + 1] - first_sample[k]);
    auto share_within = [&](double t) {
      size_t covered = 0;
      for (size_t s = first_sample[k]; s < first_sample[k + 1]; ++s) covered += coverage[s] <= t;
      return covered;
    };
    const size_t covered = share_within(threshold);
    result.objects[k].completeness = double(covered) / n;
    for (float t : params.extra_thresholds_m)
      result.objects[k].completeness_extra.push_back(double(share_within(double(t))) / n);
    covered_all += covered;
  }
  result.completeness_all_objects = double(covered_all) / double(truth_points.size());

  // O-RMS (eq. 7): reconstruction samples, each given to the instance of its closest
  // ground-truth triangle.
  Result<SurfaceSamples> recon_samples =
      SampleSurface(reconstruction, params.samples_per_m2, ReconstructionSeed(params.seed), {}, 1,
                    "EvaluateObjects: reconstruction");
  if (!recon_samples.ok()) return recon_samples.status();
  report(world.instances.size() + 2);
  Result<SurfaceDistance> world_surface =
      SurfaceDistance::Build(world.mesh, "EvaluateObjects: world mesh");
  if (!world_surface.ok()) return world_surface.status();
  std::vector<uint32_t> closest;
  const std::vector<double> accuracy = world_surface->Distances(recon_samples->points, &closest);
  report(steps);
  result.reconstruction_samples = accuracy.size();
  std::vector<double> sum(result.objects.size(), 0.0), sum_sq(result.objects.size(), 0.0);
  for (size_t s = 0; s < accuracy.size(); ++s) {
    if (!(accuracy[s] <= double(params.max_attribution_distance_m))) {
      ++result.reconstruction_samples_unattributed;
      continue;
    }
    const uint32_t id = world.triangle_instance[closest[s]];
    if (id == kNoInstance) continue;
    const int k = object_of[index_of.at(id)];
    if (k < 0) continue;  // structure
    ++result.objects[size_t(k)].reconstruction_samples;
    sum[size_t(k)] += accuracy[s];
    sum_sq[size_t(k)] += accuracy[s] * accuracy[s];
  }

  double comp_sum = 0.0, mean_sum = 0.0, rms_sum = 0.0;
  for (size_t k = 0; k < result.objects.size(); ++k) {
    ObjectEvalResult& object = result.objects[k];
    comp_sum += object.completeness;
    if (object.reconstruction_samples == 0) continue;
    const double n = double(object.reconstruction_samples);
    object.accuracy_mean_m = sum[k] / n;
    object.accuracy_rms_m = std::sqrt(sum_sq[k] / n);
    mean_sum += object.accuracy_mean_m;
    rms_sum += object.accuracy_rms_m;
    ++result.objects_reconstructed;
  }
  result.o_comp = comp_sum / double(result.objects.size());
  for (size_t e = 0; e < params.extra_thresholds_m.size(); ++e) {
    double sum_e = 0.0;
    for (const ObjectEvalResult& object : result.objects) sum_e += object.completeness_extra[e];
    result.o_comp_extra.push_back(sum_e / double(result.objects.size()));
  }
  if (result.objects_reconstructed > 0) {
    result.o_rms_m = mean_sum / double(result.objects_reconstructed);
    result.mean_object_rms_m = rms_sum / double(result.objects_reconstructed);
  }
  return result;
}

}  // namespace voxplan
