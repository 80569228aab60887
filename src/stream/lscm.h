// Least Squares Conformal Maps (Lévy, Petitjean, Ray, Maillot, SIGGRAPH 2002) with natural
// boundaries: two pinned vertices, everything else free. Also the per-triangle flattening
// (isometric 2D frame, gradients of the hat functions) that LSCM, ARAP and the distortion
// metrics share.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "core/vec.h"

namespace mebake::stream {

// A 3D triangle laid flat by an isometry into its own plane, counter-clockwise.
// grad[j] is the gradient of vertex j's hat function in that frame, so for any per-vertex
// function f the triangle's gradient is sum_j f_j grad[j]. area is the 3D area; 0 marks a
// degenerate triangle (its gradients are left at zero).
struct FlatTriangle {
    std::array<Vec2d, 3> grad;
    double area = 0;
};

FlatTriangle FlattenTriangle(const Vec3d& p0, const Vec3d& p1, const Vec3d& p2);

// Flattens every triangle; positions are promoted to double first.
std::vector<FlatTriangle> FlattenTriangles(std::span<const Vec3f> position,
                                           std::span<const std::array<uint32_t, 3>> triangles);

// Minimizes the conformal energy sum_T area_T |grad u - rot90(grad v)|^2 with vertex pin0
// at (0,0) and pin1 at (pin_distance, 0). Orientation preserving: a counter-clockwise
// (seen from the normal side) 3D triangle stays counter-clockwise in uv.
// Vertices not referenced by any triangle get (0,0). Returns false if the sparse
// factorization fails (e.g. the mesh is disconnected or all triangles are degenerate).
bool SolveLscm(std::span<const FlatTriangle> flat,
               std::span<const std::array<uint32_t, 3>> triangles, uint32_t vertex_count,
               uint32_t pin0, uint32_t pin1, double pin_distance, std::vector<Vec2d>* uv);

}  // namespace mebake::stream
