#pragma once
// The potential-field baseline of Xu 2017's X T3 in the style of Vallvé & Andrade-Cetto 2015
// ("potential information fields"): the information of each floor cell (unknown and frontier
// cells carry one unit, known cells none) blurred by a Gaussian of half the camera's range
// attracts, the known walls repel within a band, and the robot descends the sum (DescendPotential,
// harmonic.h). Unlike the harmonic function this potential has local minima (a wall corner
// between two unknown regions); the planner's frontier fallback takes over there. Plain data over
// a window of the floor (frames.h's codes); deterministic.
#include <cstdint>
#include <span>
#include <vector>

#include "plugins/omt/algorithms/types.h"

namespace voxplan::tensorfield {

struct PotentialInfoParams {
  double sigma_m = 2.0;            // the attraction's reach: half the camera range (4 m)
  double truncation_sigmas = 3.0;  // the blur is cut here
  // Repulsion η (1/c − 1/c0)² for clearance c < c0 (X T3 gives no constants; ours): strong
  // enough that a wall outweighs the whole attraction at the robot's radius.
  double repulse_within_m = 0.5;
  double repulse_gain = 0.05;
};

// φ per window cell (row-major): −(information blurred, scaled to a maximum of 1) + repulsion.
// clearance_m: the host's, per window cell.
std::vector<double> SolvePotentialInfo(const omt::RasterGeometry& geometry,
                                       std::span<const std::uint8_t> codes,
                                       std::span<const float> clearance_m,
                                       const PotentialInfoParams& params = {});

}  // namespace voxplan::tensorfield
