#include "sim/floor_detect.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

namespace voxplan {

namespace {

std::string FormatNumber(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

}  // namespace

Result<FloorDetection> DetectFloor(const Mesh& mesh, const FloorDetectParams& params) {
  if (!(params.bin_m >= 1e-4f && params.bin_m <= 1.0f))
    return InvalidArgument("floor detection: bin must be in [0.0001, 1] m, got " +
                           FormatNumber(params.bin_m));
  if (!(params.min_normal_z > 0.0f && params.min_normal_z <= 1.0f))
    return InvalidArgument("floor detection: min_normal_z must be in (0, 1], got " +
                           FormatNumber(params.min_normal_z));
  if (!(params.min_share > 0.0f && params.min_share <= 1.0f))
    return InvalidArgument("floor detection: min_share must be in (0, 1], got " +
                           FormatNumber(params.min_share));
  if (!(params.max_range_m > 0.0f && params.max_range_m <= 1e4f))
    return InvalidArgument("floor detection: max_range_m must be in (0, 10000] m, got " +
                           FormatNumber(params.max_range_m));

  struct Up {
    double z, area;
  };
  std::vector<Up> up;
  double z_lo = std::numeric_limits<double>::infinity(), z_hi = -z_lo, total = 0.0;
  const size_t nv = mesh.positions.size();
  for (const auto& t : mesh.triangles) {
    if (t[0] >= nv || t[1] >= nv || t[2] >= nv) continue;
    const Eigen::Vector3d a = mesh.positions[t[0]].cast<double>();
    const Eigen::Vector3d b = mesh.positions[t[1]].cast<double>();
    const Eigen::Vector3d c = mesh.positions[t[2]].cast<double>();
    const Eigen::Vector3d ab = b - a, ac = c - a;
    const Eigen::Vector3d n = ab.cross(ac);
    const double len = n.norm();
    if (!(len > 0.0) || !std::isfinite(len) || n.z() < double(params.min_normal_z) * len) continue;
    const double z = (a.z() + b.z() + c.z()) / 3.0, area = 0.5 * len;
    up.push_back({z, area});
    z_lo = std::min(z_lo, z);
    z_hi = std::max(z_hi, z);
    total += area;
  }
  if (up.empty()) return NotFound("floor detection: the mesh has no upward-facing triangle");
  if (z_hi - z_lo > double(params.max_range_m))
    return InvalidArgument("floor detection: upward-facing triangles span " +
                           FormatNumber(z_hi - z_lo) + " m in z, more than " +
                           FormatNumber(params.max_range_m) + " m");

  // Bins from the lowest upward-facing triangle up: a mesh moved in z keeps its bins, so its
  // floor moves with it (and a moved world's floor is found at 0 again).
  const double bin = double(params.bin_m);
  auto bin_of = [&](double z) { return size_t(std::max(0.0, std::floor((z - z_lo) / bin))); };
  const size_t bins = bin_of(z_hi) + 2;
  std::vector<double> area(bins, 0.0);
  for (const Up& u : up) area[bin_of(u.z)] += u.area;
  const double needed = double(params.min_share) * total;
  for (size_t i = 0; i + 1 < bins; ++i) {
    const double pair = area[i] + area[i + 1];
    if (pair < needed || pair <= 0.0) continue;
    // The area-weighted median height of the pair's triangles: a flat floor's own height, with
    // rugs, thresholds and scan noise on it.
    std::vector<Up> pair_up;
    double sum = 0.0;
    for (const Up& u : up) {
      const size_t k = bin_of(u.z);
      if (k != i && k != i + 1) continue;
      pair_up.push_back(u);
      sum += u.area;
    }
    std::sort(pair_up.begin(), pair_up.end(), [](const Up& l, const Up& r) { return l.z < r.z; });
    double below = 0.0, median = pair_up.back().z;
    for (const Up& u : pair_up) {
      below += u.area;
      if (below >= 0.5 * sum) {
        median = u.z;
        break;
      }
    }
    FloorDetection out;
    out.z_m = float(median);
    out.floor_area_m2 = sum;
    out.up_area_m2 = total;
    return out;
  }
  return NotFound("floor detection: no " + FormatNumber(2.0 * bin) + " m height band holds " +
                  FormatNumber(100.0 * params.min_share) +
                  "% of the upward-facing area (no large horizontal floor)");
}

}  // namespace voxplan
