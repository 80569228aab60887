// Least Squares Conformal Maps (Lévy, Petitjean, Ray, Maillot, SIGGRAPH 2002) with natural
// boundaries: two pinned vertices, everything else free.
#pragma once

#include "core/vec.h"
#include "stream/cotan_laplacian.h"

#include <array>
#include <cstdint>
#include <span>
#include <vector>

namespace mebake::stream {

// Minimizes the conformal energy sum_T A_T |grad u - rot90(grad v)|^2 with vertex pin0 at
// (0,0) and pin1 at (pin_distance, 0). Orientation preserving: a counter-clockwise (seen
// from the normal side) 3D triangle stays counter-clockwise in uv. Unreferenced vertices
// get (0,0). Returns false if the sparse factorization fails (e.g. a disconnected mesh).
bool SolveLscm(std::span<const FlatTriangle> flat,
               std::span<const std::array<uint32_t, 3>> triangles, uint32_t vertex_count,
               uint32_t pin0, uint32_t pin1, double pin_distance, std::vector<Vec2d>* uv);

}  // namespace mebake::stream
