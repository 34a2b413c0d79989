#pragma once
// The harmonic-function baseline of Xu 2017's X T3 (Shade & Newman 2011, "choosing where to go
// next"): Laplace's equation over the known free floor, frontier cells held at 0 and obstacle and
// unknown cells at 1, solved by successive over-relaxation; the robot follows -∇φ, which has no
// local minimum in free space, so every descent ends at a frontier. Plain data over a window of
// the floor (frames.h's codes).
#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include "plugins/omt/algorithms/types.h"

namespace voxplan::tensorfield {

struct HarmonicParams {
  int max_sweeps = 600;         // SOR sweeps at most (a 12 m window converges in a few hundred)
  double omega = 1.9;           // over-relaxation
  double tolerance = 1e-12;     // stop once no cell changes by more
  double step_m = 0.05;         // descent step
  double min_gradient = 1e-12;  // flatter than this (per metre): no way down
};

// φ per window cell (row-major); frontier cells 0, obstacle and unknown cells 1.
std::vector<double> SolveHarmonic(const omt::RasterGeometry& geometry,
                                  std::span<const std::uint8_t> codes,
                                  const HarmonicParams& params = {});

// Steepest descent of φ from start, at most length_m: stops on a frontier cell, where φ is flat
// or where `ok` refuses the next point (blocked). Points from the start on, every step_m.
std::vector<Eigen::Vector2d> DescendPotential(const omt::RasterGeometry& geometry,
                                              std::span<const double> phi,
                                              std::span<const std::uint8_t> codes,
                                              const Eigen::Vector2d& start, double length_m,
                                              const std::function<bool(const Eigen::Vector2d&)>& ok,
                                              const HarmonicParams& params = {});

}  // namespace voxplan::tensorfield
