// The discrete Dirichlet energy of a triangle mesh: per-triangle flattening (an isometric
// 2D frame and the gradients of the hat functions) and the cotangent Laplacian
// L = sum_T A_T G_T G_T^T (Pinkall and Polthier 1993), factorized once by sparse LDL^T
// with AMD ordering. Shared by the parameterization stages (bff, lscm, arap).
#pragma once

#include "core/vec.h"

#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

namespace mebake::stream {

// A 3D triangle laid flat by an isometry into its own plane, counter-clockwise.
// grad[j] is the gradient of vertex j's hat function in that frame, so for any per-vertex
// function f the triangle's gradient is sum_j f_j grad[j]. area is the 3D area; 0 marks a
// degenerate triangle (angles under ~1e-12 rad; its gradients are left at zero).
struct FlatTriangle {
    std::array<Vec2d, 3> grad;
    double area = 0;
};

FlatTriangle FlattenTriangle(const Vec3d& p0, const Vec3d& p1, const Vec3d& p2);

// Flattens every triangle; positions are promoted to double first.
std::vector<FlatTriangle> FlattenTriangles(std::span<const Vec3f> position,
                                           std::span<const std::array<uint32_t, 3>> triangles);

// Entry (i, j) of triangle T's contribution to L: A_T grad_i . grad_j.
inline double CotanWeight(const FlatTriangle& t, int i, int j) {
    return t.area * Dot(t.grad[i], t.grad[j]);
}

// L restricted to the free vertices (referenced and not marked fixed), factorized.
class CotanLaplacian {
public:
    CotanLaplacian();
    ~CotanLaplacian();
    CotanLaplacian(const CotanLaplacian&) = delete;
    CotanLaplacian& operator=(const CotanLaplacian&) = delete;

    // fixed[v] != 0 removes vertex v (Dirichlet). False if the factorization fails (e.g. a
    // free part of the mesh that no fixed vertex anchors).
    bool Factorize(std::span<const FlatTriangle> flat,
                   std::span<const std::array<uint32_t, 3>> triangles, std::span<const char> fixed);

    static constexpr uint32_t kFixed = ~uint32_t(0);
    uint32_t size() const { return size_; }
    // Row of each vertex, kFixed for fixed and unreferenced vertices.
    const std::vector<uint32_t>& row() const { return row_; }
    // Solves L x = b in place for `columns` right-hand sides stored column-major
    // (b[c * size() + r]). False if the result is not finite. It uses scratch kept in the
    // Laplacian: one thread at a time.
    bool Solve(std::vector<double>* b, int columns) const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
    uint32_t size_ = 0;
    std::vector<uint32_t> row_;
};

}  // namespace mebake::stream
