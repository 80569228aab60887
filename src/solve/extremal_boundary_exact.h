// Exact extremal boundaries of convex polygonal occluders on a planar receiver (seed 002,
// section 4.1), the reference the sampled pass (extremal_boundary.h) is checked against and
// the "extremal boundary vs complete discontinuity structure" of the paper's Table 1.
//
// Maximal boundary (penumbra / light): formed by EV events only. Every wedge of a light
// vertex with an occluder edge, and of an occluder vertex with a light edge, whose plane
// separates the light from the occluder bounds the shadow; the shadow of one convex
// occluder is the intersection of those half-spaces, a convex polygon on the receiver whose
// corners are occluder vertices projected from light vertices, so it is built as the hull
// of those projections (SeparatingWedgeShadow builds it from the wedges, as a check). Minimal
// boundary (umbra / penumbra) of one convex occluder: the intersection of the occluder's shadows
// from each light vertex (its edges are EV events too). Where two occluders together hide the light
// (EEE events) the umbra is not found: such points are classified penumbra. Valid when every
// occluder lies strictly between the light's plane and the receiver (touching the receiver is
// fine).
#pragma once

#include "core/vec.h"
#include "solve/extremal_boundary.h"

#include <array>
#include <span>
#include <vector>

namespace mebake::solve {

// A convex polyhedron (or a convex polygon: one face) by its faces, each a vertex index
// loop.
struct ConvexOccluder {
    std::vector<Vec3d> vertices;
    std::vector<std::vector<int>> faces;
    std::vector<std::array<int, 2>> Edges() const;  // each once
};

// Receiver points origin + s u + t v; the lit side is u x v.
struct ReceiverPlane {
    Vec3d origin, u, v;
    Vec3d At(const Vec2d& st) const { return origin + u * st.x + v * st.y; }
};

class ExactExtremalBoundary {
public:
    ExactExtremalBoundary(std::span<const Vec3d> light, std::span<const ConvexOccluder> occluders,
                          const ReceiverPlane& plane);

    // kLit outside every maximal polygon, kUmbra inside some minimal one, else kPenumbra.
    ExtremalBoundaries::Class Classify(const Vec2d& st) const;
    // Per occluder, counter-clockwise in (s, t); minimal may be empty.
    const std::vector<Vec2d>& maximal(size_t occluder) const { return maximal_[occluder]; }
    const std::vector<Vec2d>& minimal(size_t occluder) const { return minimal_[occluder]; }
    size_t occluder_count() const { return maximal_.size(); }

private:
    std::vector<std::vector<Vec2d>> maximal_, minimal_;
};

// The maximal polygon of one occluder built from the EV events themselves: the receiver
// clipped by every EV wedge (light vertex with occluder edge, occluder vertex with light
// edge) whose plane separates light and occluder; *wedges counts those. The same polygon
// as ExactExtremalBoundary::maximal, by another construction (the test compares them).
std::vector<Vec2d> SeparatingWedgeShadow(std::span<const Vec3d> light, const ConvexOccluder& occ,
                                         const ReceiverPlane& plane, size_t* wedges);

// The complete EV structure of one light and the occluders on the plane, as the
// discontinuity meshing of [Dret94] would trace it: every wedge of a light vertex with an
// occluder's silhouette edge, and of a silhouette vertex with a light edge, traced to the
// receiver as a segment, and the points where those segments cross (the mesh's vertices).
// Not included: EEE events and events between occluders (non-emitter events), and the
// clipping of traces by other occluders.
struct DiscontinuityStructure {
    size_t wedges = 0, crossings = 0;
    std::vector<std::array<Vec2d, 2>> segments;
};
DiscontinuityStructure CompleteDiscontinuities(std::span<const Vec3d> light,
                                               std::span<const ConvexOccluder> occluders,
                                               const ReceiverPlane& plane);

// Whether p lies in (or on) the counter-clockwise convex polygon.
bool InsideConvex(std::span<const Vec2d> poly, const Vec2d& p);

}  // namespace mebake::solve
