// Triangulation of one hole by the greedy shortcut rule of the Master-Element paper
// (section 3.1, step 1). Pure geometry on the loop's positions; the caller decides which
// holes to fill and adds the triangles to its mesh (repair.cpp).
#pragma once

#include "core/vec.h"

#include <array>
#include <cstdint>
#include <functional>
#include <vector>

namespace mebake::stream {

// loop: the hole's border, vertex positions in the order the border is walked (the
// resulting triangles use this order, so they are oriented like the loop).
// chord_allowed(i, j): false when the mesh already has an edge between loop vertices i and
// j (inserting it again would make an edge non-manifold).
// min_area_ratio: a triangle whose twice-area is <= min_area_ratio * (longest edge)^2 is
// degenerate and never produced.
// On success returns true and appends loop.size() - 2 triangles (indices into loop) to
// *triangles, ordered so that each triangle after the first shares an edge with an
// earlier one. On failure (no valid triangulation found) returns false and leaves
// *triangles unchanged.
bool TriangulateHole(const std::vector<Vec3d>& loop,
                     const std::function<bool(uint32_t, uint32_t)>& chord_allowed,
                     double min_area_ratio, std::vector<std::array<uint32_t, 3>>* triangles);

}  // namespace mebake::stream
