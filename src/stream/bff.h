// Boundary First Flattening (Sawhney and Crane, "Boundary First Flattening", ACM TOG 2017):
// a conformal flattening with a free ("natural") boundary computed from two solves with
// the interior cotangent Laplacian, far cheaper than LSCM's coupled system. Used as the
// starting map of the local/global refinement (arap.h).
#pragma once

#include "core/vec.h"
#include "stream/cotan_laplacian.h"

#include <array>
#include <cstdint>
#include <span>
#include <vector>

namespace mebake::stream {

// Flattens a disc whose boundary loop is `boundary` (in the triangles' winding order),
// keeping boundary edge lengths (scale factor u = 0 on the boundary) and choosing the
// boundary curvature so the map is conformal. The interior is the harmonic extension of
// the boundary curve. Returns false if a solve fails or the boundary curve cannot be
// closed with positive edge lengths; *uv is then unspecified.
bool FlattenBff(std::span<const Vec3f> position, std::span<const FlatTriangle> flat,
                std::span<const std::array<uint32_t, 3>> triangles,
                std::span<const uint32_t> boundary, std::vector<Vec2d>* uv);

}  // namespace mebake::stream
