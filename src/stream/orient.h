// Ingest pass 2b: outward orientation. A closed (or nearly closed) surface wound inwards
// (its faces' normals point into the solid) is lit on the inside by the bake and renders
// black from outside. Repair (repair.h) makes every component consistent but keeps the
// input's majority winding, so this pass decides, per connected component of the whole
// mesh, whether that winding is inside out, and reverses the component's faces in the
// brick files before pass 3 reads them.
//
// The rule, per component (vertices joined by faces, exact-position welds as in repair,
// across bricks through the vertices they share):
//   A = area, N = vector area (sum of the faces' area vectors), c = area centroid,
//   V = sum over faces of det(v0 - c, v1 - c, v2 - c) / 6: the signed volume seen from c;
//       the exact enclosed volume when the component is closed (then N = 0 and c does not
//       matter), the normal-weighted flux of (x - c) / 3 otherwise.
//   openness  w = |N| / A: 0 when closed; the holes' projected area over the surface.
//   q = V / (volume of the sphere of area A): +1 for a sphere wound outwards, -1 inwards.
// Flipped when all hold:
//   1 nearly closed: w <= kMaxOpenness (an open patch - a dome or the inside of a bowl,
//     a wall - has no inside that geometry alone can name);
//   2 clearly inside out: q <= -kMinVolumeRatio (a closed sheet with both sides has q ~ 0);
//   3 not nested: its bounding box neither contains nor lies in the box of another
//     component with at least kNestedArea of its area (a room around objects and the wall
//     of a cavity inside a solid are wound inwards on purpose).
// Memory: per brick in flight, its faces; across bricks, one record per component piece
// that touches a shared vertex, is large (>= kKeptArea of the surface) or is a candidate.
#pragma once

#include "core/progress.h"
#include "stream/bricks.h"

#include <cstdint>
#include <string>

namespace mebake::stream {

inline constexpr double kMaxOpenness = 0.1;
inline constexpr double kMinVolumeRatio = 0.05;
inline constexpr double kNestedArea = 0.01;
inline constexpr double kKeptArea = 1e-4;

struct OrientReport {
    uint64_t components = 0;  // connected components of the whole mesh
    uint64_t flipped_components = 0;
    uint64_t flipped_triangles = 0;
    uint64_t nested_kept = 0;  // inside out but nested: left as they are
};

// Decides and applies (rewrites the bricks of flipped components). Deterministic: the same
// bricks give the same decisions for any thread count. progress counts each face once.
OrientReport OrientOutwards(const std::string& dir, const BrickPlan& plan, const Vec3d& bbox_min,
                            const Vec3d& bbox_max, ProgressStage* progress);

}  // namespace mebake::stream
