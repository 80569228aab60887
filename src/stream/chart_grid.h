// Point location over a chart's master element: the unit square [0,1]^2 holding the chart
// in uv (its real part) and the rest (its virtual part). A regular G x G grid lists, per
// cell, the triangles overlapping it; cells not certainly inside the chart also list the
// candidate nearest triangles, a set proven to contain the exact uv-nearest triangle of
// every point of the cell. The seed paper stores "in each [virtual] triangle ... a
// reference to the nearest real triangle"; this is the same query without a virtual mesh.
//
// Evaluation extends the surface into the virtual part by the nearest triangle's affine
// map: p(u) = p(u') + J (u - u'), u' the nearest point of the chart, J the 3x2 Jacobian.
// Positions are continuous across the chart's boundary, and p(u') is the real point that
// stands in for u in visibility queries (x' in the seed paper).
#pragma once

#include "core/vec.h"

#include <array>
#include <cstdint>
#include <span>
#include <vector>

namespace mebake::stream {

constexpr uint32_t kNoTriangle = ~uint32_t(0);

struct GridLocation {
    uint32_t triangle = kNoTriangle;     // kNoTriangle: a grid without triangles (or
                                         // LocateReal's virtual point)
    std::array<float, 3> barycentric{};  // of u (real) or of nearest_uv (virtual); sum 1
    bool real = false;                   // u lies in a triangle of the chart
    Vec2f nearest_uv;                    // u itself when real
    float distance = 0;                  // uv distance from u to the chart, 0 when real
};

struct ChartGrid {
    int resolution = 0;                              // G
    std::vector<Vec2f> uv;                           // copy of the chart's uv
    std::vector<std::array<uint32_t, 3>> triangles;  // copy of the chart's triangles
    // Triangles overlapping cell c = (ix, iy), c = iy * G + ix:
    // cell_tris[cell_start[c] .. cell_start[c + 1]), ascending.
    std::vector<uint32_t> cell_start, cell_tris;
    // Candidate nearest triangles of cell c (empty when the cell lies inside the chart):
    // near_tris[near_start[c] .. near_start[c + 1]), ascending.
    std::vector<uint32_t> near_start, near_tris;
    // Triangles on the uv outline: with a boundary edge, or flipped / zero uv area.
    std::vector<uint32_t> outline_tris;

    // Exact point location. u is clamped to [0,1]^2 first. A point within 2^-22 (a few
    // float ulps) of a triangle counts as inside it. Among overlapping triangles (a
    // non-injective map) and among equally near ones, the lowest index wins.
    GridLocation Locate(Vec2f u) const;
    // Locate(u).triangle when Locate(u).real, else kNoTriangle, without the nearest-triangle
    // search of the virtual part.
    uint32_t InsideTriangle(Vec2f u) const;
    // Locate(u) when Locate(u).real, else a location with triangle kNoTriangle (and real
    // false), without the nearest-triangle search of the virtual part.
    GridLocation LocateReal(Vec2f u) const;

    size_t MemoryBytes() const;
};

// A grid resolution with about one cell per triangle: ceil(sqrt(n)), in [1, 2048].
int DefaultGridResolution(size_t triangle_count);

// Builds the grid. Works for any triangle soup in uv (flipped, overlapping, degenerate
// triangles are located correctly); resolution must be in [1, 16384].
ChartGrid BuildChartGrid(const std::vector<Vec2f>& uv,
                         const std::vector<std::array<uint32_t, 3>>& triangles, int resolution);

struct SurfacePoint {
    Vec3f position;          // on the chart (real) or extrapolated (virtual)
    Vec3f normal;            // unit; interpolated vertex normal (real), triangle normal (virtual)
    Vec3f visible_position;  // the real point used for visibility: position itself when real
    bool real = false;
    uint32_t triangle = kNoTriangle;
};

// Evaluates the master element at u. position and vertex_normal are per chart vertex (the
// uv the grid was built from). Zero-area uv triangles extrapolate with J = 0.
SurfacePoint Evaluate(const ChartGrid& grid, std::span<const Vec3f> position,
                      std::span<const Vec3f> vertex_normal, Vec2f u);

// Angle-weighted vertex normals (Thürmer and Wüthrich 1998), unit length; zero for
// vertices with only degenerate triangles.
std::vector<Vec3f> VertexNormals(std::span<const Vec3f> position,
                                 std::span<const std::array<uint32_t, 3>> triangles);

}  // namespace mebake::stream
