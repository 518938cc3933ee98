#pragma once
// The vertex order a streamed file codes (order.cpp): each chunk's splits by their substitutes.
#include <cstdint>
#include <vector>

#include "tom/format.h"

namespace tom {

/// The image of `file` (whose bytes are `bytes`) with every mesh i's vertices renumbered within
/// each of its chunks, `ends[i]` (the resolutions its chunks end at, none inside a group of
/// copies): a chunk's groups of copies and single vertices ordered by the largest substitute
/// of a member outside them, then as before; substitutes, corners, groups and every per-vertex
/// stream follow, each part's triangles sorted again by the resolution they become live at, and
/// `COAR` left out. The level at every chunk boundary is the same mesh, renumbered.
std::vector<uint8_t> stream_ordered_image(const File& file, const uint8_t* bytes, const std::vector<std::vector<uint32_t>>& ends);

}  // namespace tom
