#pragma once
// The floor height of a scene mesh: the lowest large upward-facing horizontal surface. The
// simulator, floor plans and planning maps put the floor at z = 0; a scanned scene (Replica's
// office at z = -1.17) has it elsewhere, and LoadWorld (SceneLoadOptions::detect_floor) moves
// such a world down by the height found here.
//
// Method: every triangle whose normal points up within acos(min_normal_z) of +z (winding
// counter-clockwise seen from outside, as core/mesh.h has it) adds its area to a histogram of
// its centroid's z in bins of bin_m, from the lowest such centroid up. The floor is the lowest pair
// of adjacent bins holding at least min_share of all upward-facing area; its height is the
// area-weighted median centroid z of the triangles in that pair, so within one bin of the surface.
// Tables, seats, shelves and worktops hold less than that share in an indoor scene; a small step or
// a plinth below the floor holds less too. A flat floor is found at exactly its height (a floor at
// z = 0 as 0, rugs and thresholds on it or not). Measured (tests/sim/test_floor_detect.cpp):
// Replica office0 -1.130 m (a scan: its floor triangles lie between -1.17 and -1.10), the AWS small
// house 0, the Cornell box (Y-up) 0, habitat's simple_room 0.15 m, the generated apartments 0.
#include "core/mesh.h"
#include "core/status.h"

namespace voxplan {

struct FloorDetectParams {
  float bin_m = 0.02f;         // histogram bin height
  float min_normal_z = 0.9f;   // n_z / |n| of an upward-facing horizontal triangle (about 26°)
  float min_share = 0.2f;      // share of all upward-facing area the floor's two bins hold
  float max_range_m = 200.0f;  // refused when the upward-facing triangles span more in z
};

struct FloorDetection {
  float z_m = 0.0f;          // the floor's height
  double floor_area_m2 = 0;  // upward-facing area in the floor's two bins
  double up_area_m2 = 0;     // all upward-facing area
};

// NotFound when the mesh has no upward-facing triangle or no bin pair reaches min_share;
// InvalidArgument for parameters out of range.
Result<FloorDetection> DetectFloor(const Mesh& mesh, const FloorDetectParams& params = {});

}  // namespace voxplan
