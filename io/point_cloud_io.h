#pragma once
// Point clouds as binary little-endian PLY: one vertex element (x y z, with nx ny nz and
// uchar red green blue when the points have them), no faces, as Open3D, PCL and MeshLab read
// them. Written through a temporary file and renamed (io/file_util.h).
#include <string>

#include "core/mesh.h"
#include "core/status.h"

namespace voxplan {

// The vertices of `points` (its triangles, if any, are not written). The error names the file.
Status WritePointCloudPly(const Mesh& points, const std::string& path);

}  // namespace voxplan
