// In-core repair of one brick (Master-Element paper, section 3.1 step 1): weld, drop
// degenerate and duplicate triangles, split non-manifold vertices and edges, orient each
// component consistently, and fill small holes. The result is an oriented 2-manifold with
// boundary that segmentation (segment.h) can cut into discs.
#pragma once

#include "stream/trimesh.h"

#include <cstddef>
#include <cstdint>
#include <vector>

namespace mebake::stream {

struct RepairOptions {
    // Vertices closer than this (Euclidean, same units as positions) are welded; 0 welds
    // only exactly equal positions. Clusters are transitive (single linkage), so keep it well
    // below the edge length.
    double weld_epsilon = 0.0;
    // A triangle whose twice-area is <= min_area_ratio * (longest edge)^2 has zero area.
    double min_area_ratio = 1e-10;
    bool fill_holes = true;
    // A hole is filled only if its border has at most max_hole_edges edges (<= 1024) and
    // the diagonal of the border's bounding box is at most max_hole_relative_diameter times
    // the diagonal of its connected component's bounding box (so a lone patch of scan is
    // never closed into a pillow).
    int max_hole_edges = 128;
    double max_hole_relative_diameter = 0.25;
};

// Counts of everything Repair did, in the order it does it.
struct RepairReport {
    size_t input_vertices = 0;
    size_t input_triangles = 0;
    size_t invalid_triangles = 0;      // index out of range or non-finite position: dropped
    size_t welded_vertices = 0;        // vertices merged into another one
    size_t degenerate_triangles = 0;   // repeated vertex after welding: dropped
    size_t zero_area_triangles = 0;    // dropped
    size_t duplicate_triangles = 0;    // same vertex set as an earlier one: dropped
    size_t nonmanifold_edges = 0;      // edges found with more than two faces
    size_t orientation_flips = 0;      // triangles reversed
    size_t orientation_cuts = 0;       // edges cut to make a non-orientable part orientable
    size_t split_vertices = 0;         // vertex copies made to separate fans
    size_t detached_corners = 0;       // copies made to undo folds around an edge
    size_t isolated_triangles = 0;     // last resort: triangle given its own vertices
    size_t unreferenced_vertices = 0;  // dropped
    size_t boundary_loops = 0;         // before hole filling
    size_t holes_filled = 0;
    size_t hole_triangles = 0;  // triangles added (face_id = kNoId)
    size_t holes_on_cut = 0;    // loops touching a cut vertex: the brick border
    size_t holes_too_large = 0;
    size_t seams = 0;             // loops through two copies of one vertex: not holes
    size_t holes_unfillable = 0;  // no valid triangulation
    size_t output_vertices = 0;
    size_t output_triangles = 0;
    size_t output_boundary_loops = 0;

    // Per output vertex: 1 if any input vertex merged into it was on the cut.
    std::vector<uint8_t> vertex_on_cut;
};

// Repairs mesh in place. vertex_on_cut[v] (one per input vertex, may be empty = none)
// marks vertices also used by faces of another brick: a boundary loop through any of them
// is part of the brick's cut, not a hole. Output: vertices in input order (welded ones and
// unused ones dropped) followed by copies made by non-manifold splits (same vertex_id as
// their original); triangles in input order, flipped where orientation demanded, followed
// by hole-filling triangles (face_id = kNoId, material of a neighbouring triangle).
// Deterministic; throws a usage Error (core/error.h) on invalid options.
RepairReport Repair(TriMesh& mesh, const std::vector<uint8_t>& vertex_on_cut,
                    const RepairOptions& options);

}  // namespace mebake::stream
