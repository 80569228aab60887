// The kernel of the indirect transfer: vector irradiance at a receiving point x (normal n)
// from one emitter texel of unit radiosity (docs/method.md, Indirect light):
//   far:  dE = (y - x) A cos_y / (pi r^4), the texel as a point of area A at y;
//   near: closer than two texel sides, the texel as a uniform square of area A in its
//         tangent plane, clipped to the receiver's upper half-space and integrated in
//         closed form (polygon_light.h), so nothing blows up as r -> 0.
// The solver's gather (solver.cpp) evaluates every link through it; transfer_test.cpp
// checks it against Lambert's formula and the far form.
#pragma once

#include "core/vec.h"

#include <span>

namespace mebake::solve {

struct TexelSource {
    Vec3f pos, nrm;  // centre and unit normal (the emitting side)
    float area = 0;  // real area, world units
};

// Adds nothing and returns false when the texel cannot light x: it lies below x's tangent
// plane, faces away from x, coincides with x, or (near form) is wholly below the horizon.
// `texel_side` is the side of the texel's level, which picks the form.
bool TexelTransfer(const Vec3f& x, const Vec3f& n, const TexelSource& t, double texel_side,
                   Vec3d* e);

// The same for a sample `t` that stands for finer facets (its normal their area-weighted
// mean, the same unit radiosity; `facets` may be empty). Where the facets do not all face
// the same way from x, their own transfers are summed (each facet of side texel_side / 2):
// the mean normal's (cos)+ is below the facets' summed (cos)+ (max(0, .) is convex), so
// with the mean alone a sample across a crease or fold lost the light of its facets facing
// x, or all of it when the mean faced away (bench/RESULTS.md, "Issue 14 (session 10)").
// *carrier: the facet that carries the most of it, or -1 for the sample as a whole (the
// caller's visibility ray ends there).
bool FacetedTransfer(const Vec3f& x, const Vec3f& n, const TexelSource& t,
                     std::span<const TexelSource> facets, double texel_side, Vec3d* e,
                     int* carrier);

// How far a sample's facets can disagree with the sample as a whole about the side of them
// a point x lies on: with D = |x - t.pos|, every facet's (x - f.pos) . f.nrm lies within
// offset + D x tilt of (x - t.pos) . t.nrm, since their difference is
// (x - f.pos) . (f.nrm - t.nrm) + (t.pos - f.pos) . t.nrm (rounding included).
struct FacetSpread {
    float offset = 0, tilt = 0;
};
FacetSpread SpreadOf(const TexelSource& t, std::span<const TexelSource> facets);

// True when that bound proves every facet (of area > 0) faces x the way the sample does:
// FacetedTransfer then gives TexelTransfer's bits, so the caller may skip the facets (most
// pairs: the facet test was 16 % of lucy's solve). False: not known, ask FacetedTransfer.
bool FacetsAgree(const Vec3f& x, const TexelSource& t, const FacetSpread& spread);

}  // namespace mebake::solve
