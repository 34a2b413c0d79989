#pragma once
// Internal to io: voxplan's own PLY reader, used for every .ply instead of assimp (whose PLY
// importer crashes, loops or allocates without bound on malformed files). ascii,
// binary_little_endian and binary_big_endian; every standard scalar type.
//
// Read: vertex x y z, optional nx ny nz and red green blue (or r g b; integers are scaled by
// their type's maximum, floats are 0..1), the face list vertex_indices (or vertex_index) with
// any integer count and index types; every other element and property is skipped by its size.
// Polygons with more than three corners are fan-triangulated.
//
// Everything is checked before anything is allocated or trusted: the header is complete within
// ply::kMaxHeaderBytes, each element's count times its smallest record fits in the bytes left,
// lists of indices have 3..kMaxPolygonVertices entries, every index names a vertex, every
// coordinate is a finite float. Refusals read "<path>: <reason>" (ascii: "<path>: line N: ...").
#include <cstdint>
#include <string>

#include "core/mesh.h"
#include "core/status.h"

namespace voxplan::internal {

constexpr uint32_t kMaxPolygonVertices = 1024;

// The file's mesh in its own coordinates. As assimp's JoinIdenticalVertices did before, vertices
// no face uses are dropped and vertices equal in every attribute are merged (first one kept, in
// file order), so valid files read exactly as they did through assimp.
Result<Mesh> ReadPly(const std::string& path);

}  // namespace voxplan::internal
