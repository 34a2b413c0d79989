#pragma once
// Internal to io: the structural checks a binary glTF (.glb) must pass before assimp sees it,
// so that assimp's glTF2 importer never reads past a buffer, allocates from an absurd count or
// recurses through a cycle of nodes.
#include <string_view>

#include "core/status.h"

namespace voxplan::internal {

// The 12-byte header (magic "glTF", version 2, length = the file's size), the chunks (a JSON
// chunk first, each inside the file), then in the JSON: every buffer view inside its buffer (the
// BIN chunk for buffer 0 without a uri), every accessor (sparse ones too) inside its buffer view,
// every reference to a buffer, view, accessor, mesh or node in range, and the node graph a forest.
// Errors are reasons without the file name.
Status CheckGlb(std::string_view bytes);

}  // namespace voxplan::internal
