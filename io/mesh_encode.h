#pragma once
// voxplan's own mesh encoders (internal to mesh_io.cpp's WriteMesh): each writes every vertex
// and triangle as given, in order, with no vertex joining or other processing, so a clean mesh
// stays clean. Colours are written as c / 255; the mesh has been checked (CheckMesh).
#include <string>

#include "core/mesh.h"
#include "core/status.h"

namespace voxplan::internal {

// Wavefront OBJ text: "v x y z [r g b]", "vn", "f a//a ..." (1-based); every float in the
// shortest form that reads back to the same float.
std::string EncodeObj(const Mesh& mesh);

// Binary glTF 2.0 (.glb): one mesh, one triangle primitive with POSITION, NORMAL, COLOR_0
// (float RGB) and 32-bit indices, coordinates as they are (voxplan's Z-up world). Refuses a
// mesh too large for the format's 32-bit lengths.
Result<std::string> EncodeGlb(const Mesh& mesh);

}  // namespace voxplan::internal
