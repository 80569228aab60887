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

#include <algorithm>
#include <cmath>
#include <numbers>
#include <span>

namespace mebake::solve {

struct TexelSource {
    Vec3f pos, nrm;  // centre and unit normal (the emitting side)
    float area = 0;  // real area, world units
};

// A point-texel pair's geometry, which TexelTransfer and FacetsAgree both read: the gather
// computes it once per pair (as separate calls the two recomputed it, and FacetsAgree,
// TexelTransfer and FacetedTransfer were 18 % of lucy's solve).
struct PairGeometry {
    Vec3d d;          // t.pos - x
    double r2 = 0;    // |d|^2
    double ce = 0;    // -d . t.nrm: > 0 where x lies in front of the texel
};
inline PairGeometry GeometryOf(const Vec3f& x, const TexelSource& t) {
    const Vec3d d = Vec3d(t.pos) - Vec3d(x);
    return {d, Dot(d, d), -Dot(d, Vec3d(t.nrm))};
}

// The near form (below): the texel as a square clipped to x's upper half-space.
bool NearTransfer(const Vec3f& x, const Vec3f& n, const TexelSource& t, Vec3d* e);

// Adds nothing and returns false when the texel cannot light x: it lies below x's tangent
// plane, faces away from x, coincides with x, or (near form) is wholly below the horizon.
// `texel_side` is the side of the texel's level, which picks the form. g = GeometryOf(x, t).
inline bool TexelTransfer(const Vec3f& x, const Vec3f& n, const TexelSource& t,
                          const PairGeometry& g, double texel_side, Vec3d* e) {
    if (g.r2 < 1e-20)
        return false;
    if (Dot(g.d, Vec3d(n)) <= 0)
        return false;  // below the receiver's horizon
    if (g.ce <= 0)
        return false;  // the emitter faces away
    if (g.r2 < 4 * texel_side * texel_side)
        return NearTransfer(x, n, t, e);
    *e = g.d * (double(t.area) * g.ce / (std::numbers::pi * g.r2 * g.r2));
    return true;
}
inline bool TexelTransfer(const Vec3f& x, const Vec3f& n, const TexelSource& t,
                          double texel_side, Vec3d* e) {
    return TexelTransfer(x, n, t, GeometryOf(x, t), texel_side, e);
}

// The same for a sample `t` that stands for finer facets (its normal their area-weighted
// mean, the same unit radiosity; `facets` may be empty). Where the facets do not all face
// the same way from x, their own transfers are summed (each facet of side texel_side / 2):
// the mean normal's (cos)+ is below the facets' summed (cos)+ (max(0, .) is convex), so
// with the mean alone a sample across a crease or fold lost the light of its facets facing
// x, or all of it when the mean faced away (bench/RESULTS.md, "Issue 14 (session 10)").
// *carrier: the facet that carries the most of it, or -1 for the sample as a whole (the
// caller's visibility ray ends there).
// g = GeometryOf(x, t), as in TexelTransfer. Inline for the gather's inner loop; the
// facets' own sum is MixedFacetsTransfer (*carrier as here, which it leaves at -1 when
// no facet carries light).
bool MixedFacetsTransfer(const Vec3f& x, const Vec3f& n, std::span<const TexelSource> facets,
                         double texel_side, Vec3d* e, int* carrier);
inline bool FacetedTransfer(const Vec3f& x, const Vec3f& n, const TexelSource& t,
                            const PairGeometry& g, std::span<const TexelSource> facets,
                            double texel_side, Vec3d* e, int* carrier) {
    *carrier = -1;
    int toward = 0, real = 0;
    for (const TexelSource& f : facets) {
        if (f.area <= 0)
            continue;
        ++real;
        toward += Dot(Vec3d(x) - Vec3d(f.pos), Vec3d(f.nrm)) > 0 ? 1 : 0;
    }
    if (toward == 0 || toward == real)
        return TexelTransfer(x, n, t, g, texel_side, e);  // all one way: the mean decides
    return MixedFacetsTransfer(x, n, facets, texel_side, e, carrier);
}
inline bool FacetedTransfer(const Vec3f& x, const Vec3f& n, const TexelSource& t,
                            std::span<const TexelSource> facets, double texel_side, Vec3d* e,
                            int* carrier) {
    return FacetedTransfer(x, n, t, GeometryOf(x, t), facets, texel_side, e, carrier);
}

// How far a sample's facets can disagree with the sample as a whole about the side of them
// a point x lies on: with D = |x - t.pos|, every facet's (x - f.pos) . f.nrm lies within
// offset + D x tilt of (x - t.pos) . t.nrm, since their difference is
// (x - f.pos) . (f.nrm - t.nrm) + (t.pos - f.pos) . t.nrm (rounding included).
// `reach`: no facet's centre lies further than that from the sample's (plus the margin).
struct FacetSpread {
    float offset = 0, tilt = 0, reach = 0;
};
FacetSpread SpreadOf(const TexelSource& t, std::span<const TexelSource> facets);

// True when that bound proves every facet (of area > 0) faces x the way the sample does:
// FacetedTransfer then gives TexelTransfer's bits, so the caller may skip the facets (most
// pairs: the facet test was 16 % of lucy's solve). False: not known, ask FacetedTransfer.
// g = GeometryOf(x, t): |g.ce| is |(x - t.pos) . t.nrm| to the bit (IEEE subtraction is
// antisymmetric).
inline bool FacetsAgree(const PairGeometry& g, const FacetSpread& spread) {
    const double side = std::abs(g.ce);
    if (!(side > spread.offset))
        return false;
    // side - offset > sqrt(r2) x tilt, squared (no root: it was a tenth of the gather's
    // pair loop); the subtraction errs by 1 ulp of its result, the products by a few, all
    // far inside the 1e-9 widening, so this still proves it.
    const double s = side - spread.offset, tilt = spread.tilt;
    return s * s > g.r2 * (tilt * tilt) * (1 + 1e-9);
}
inline bool FacetsAgree(const Vec3f& x, const TexelSource& t, const FacetSpread& spread) {
    return FacetsAgree(GeometryOf(x, t), spread);
}

// True when the sample's centre and every facet's lie below the tangent plane of x (normal
// n, unit): FacetedTransfer then returns false, whatever the facets (each part's transfer
// first tests its centre against x's horizon), so the caller need not read them. The
// facets' centres lie within spread.reach of the sample's; the margin covers the rounding
// of both sides' dot products (relative ~1e-16 of |d|_1 + reach) and of |n| (1e-7).
inline bool BelowHorizon(const PairGeometry& g, const Vec3f& n, const FacetSpread& spread) {
    const double h = Dot(g.d, Vec3d(n));
    const double d1 = std::abs(g.d.x) + std::abs(g.d.y) + std::abs(g.d.z);
    return h < 0 && -h > spread.reach + 1e-9 * d1;
}

// A link's emitter region (several samples) as one receiver point sees it, to test once
// per point instead of once per pair in the gather (CollectPairs): most of a link's
// candidate pairs on a scan's folds cannot carry light, half of lucy's in links that carry
// none. A sphere around the samples' centres and their facets' (within spread.reach of
// the sample's centre) and a cone around their normals (the facets' within spread.tilt of
// the sample's, as a chord); reach and tilt are 0 where the facets are not read. `centre`
// and `axis` (unit) are any point and direction near them; Add() grows the bounds to hold a
// sample, with margins for rounding.
struct RegionBound {
    Vec3f centre, axis;
    double radius = 0, min_cos = 1;  // |p - centre| <= radius, Dot(axis, m) >= min_cos
    void Add(const Vec3f& pos, const Vec3f& nrm, float reach, float tilt) {
        radius = std::max(radius, (Length(Vec3d(pos) - Vec3d(centre)) + double(reach)) *
                                      (1 + 1e-6));
        min_cos = std::min(min_cos, Dot(Vec3d(axis), Vec3d(nrm)) - double(tilt) * (1 + 1e-6));
    }
};

// True when every centre the region holds lies below the tangent plane of x (normal n,
// unit within 1e-6): each pair's transfer (TexelTransfer, FacetedTransfer, either path)
// then fails its horizon test, Dot(p - x, n) <= 0 for its part's centre p, so the caller
// may skip the region's pairs for x. Margins: |n| <= 1 + 1e-6, and the dot products'
// rounding (~1e-16 of |p - x|_1 <= |c - x|_1 + 2 radius) on both sides.
inline bool RegionBelowHorizon(const Vec3f& x, const Vec3f& n, const RegionBound& r) {
    const Vec3d d = Vec3d(r.centre) - Vec3d(x);
    const double h = Dot(d, Vec3d(n));
    const double d1 = std::abs(d.x) + std::abs(d.y) + std::abs(d.z);
    return h < 0 && -h > r.radius * (1 + 1e-5) + 1e-9 * (d1 + r.radius);
}

// True when x lies behind the plane of every part the region holds (Dot(x - p, m) < 0 for
// each centre p and normal m): each pair's transfer then fails its facing test (the
// sample's, or in a mixed sample each facet's), so the caller may skip the region for x.
// With v = x - centre at angle phi from the axis and the normals within theta = acos(min_cos)
// of it, Dot(v, m) <= |v| cos(phi - theta) once phi >= theta, and Dot(c - p, m) <= radius.
// cos(phi - theta) grows with cos phi there, so cos phi is taken from above (the axis
// and normals are unit within 1e-6), |v| |m| from below, and min_cos lowered by 1e-5.
inline bool RegionFacesAway(const Vec3f& x, const RegionBound& r) {
    const double k = r.min_cos - 1e-5;
    if (k <= 0)
        return false;  // a cone of 90 degrees or more: some normal may face x
    const Vec3d v = Vec3d(x) - Vec3d(r.centre);
    const double len = Length(v);
    if (!(len > 0))
        return false;
    const double c = std::max(-1.0, Dot(v, Vec3d(r.axis)) / len + 1e-5);
    if (c >= 0)
        return false;  // phi <= 90 degrees
    const double cos_gap = c * k + std::sqrt(1 - c * c) * std::sqrt(1 - k * k);
    return cos_gap < 0 &&
           len * (1 - 1e-5) * -cos_gap > r.radius * (1 + 1e-5) + 1e-9 * (len + r.radius);
}

}  // namespace mebake::solve
