// Seed 002, section 5.4: the penumbral radiance estimate. At a point P in the penumbra of
// one convex occluder (extremal_boundary_exact.h), take the minimal-boundary edge whose two
// endpoints are closest to P; along the line from its midpoint M through P to the maximal
// boundary B the irradiance runs from 0 (umbra) to the unoccluded value, and a local
// backprojection just inside each end gives its derivative there; the Hermite cubic of
// those values and derivatives gives the value at P. The backprojection of one convex
// occluder is exact (the light minus the occluder's projection onto the light's plane),
// which also gives the exact value the estimate is measured against. Where it holds and
// where it does not: docs/method.md, "Several sources".
#pragma once

#include "solve/extremal_boundary_exact.h"

#include <span>

namespace mebake::solve {

// Irradiance (normal n, radiance 1, clipped to the receiver's horizon) at x from the part
// of the light that the convex occluder does not hide, by backprojection: exact for one
// convex occluder between light and receiver.
double BackprojectedIrradiance(std::span<const Vec3d> light, const ConvexOccluder& occluder,
                               const Vec3d& x, const Vec3d& n);

struct PenumbraEstimate {
    bool ok = false;                 // false: no minimal boundary (no umbra) to start from
    double hermite = 0, linear = 0;  // the cubic's value and the straight line's (0 -> unoccluded)
};

// The estimate at st for occluder k of eb (the point should lie in its penumbra).
PenumbraEstimate EstimatePenumbra(const ExactExtremalBoundary& eb, size_t k,
                                  std::span<const Vec3d> light, const ConvexOccluder& occluder,
                                  const ReceiverPlane& plane, const Vec2d& st);

}  // namespace mebake::solve
