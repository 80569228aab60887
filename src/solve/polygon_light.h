// Exact vector irradiance of a uniform planar polygonal emitter: Lambert's formula
// (J. H. Lambert 1760; in graphics J. Arvo, "The Irradiance Jacobian for Partially Occluded
// Polyhedral Sources", SIGGRAPH 1994), used for the fully visible direct term (docs/method.md, Direct light).
//
// Convention. E points from the receiver towards the light:
//   E(x) = integral over the emitter of L cos(theta_y) w / r^2 dA(y),  w = (y-x)/r, r = |y-x|,
// so the irradiance of a surface at x with normal n (when all of the emitter is above its
// tangent plane) is n . E(x). This is the transport of docs/method.md
//   dE(x) = B(y) max(0, (x-y).n(y)) (y-x) / (pi |y-x|^4) dA(y)   with B = pi L.
// Closed form: E(x) = (L/2) sum_k theta_k g_k, theta_k the angle the edge (v_k, v_k+1)
// subtends at x and g_k the unit normal of the plane through x and that edge, oriented
// towards the emitter's front side for a polygon wound counter-clockwise as seen from its
// front (the side it emits to; front normal = right-hand rule).
//
// The polygon must be planar and simple (convex or not), with at most kMaxPolygonVertices
// vertices (scene loaders reject larger ones). Points on the emitter's plane get 0; so do
// points behind a one-sided emitter. Nothing here returns NaN for finite input.
#pragma once

#include "core/vec.h"

#include <span>

namespace mebake::solve {

inline constexpr int kMaxPolygonVertices = 64;

enum class Emission {
    kFront,  // emits to the half-space its front normal points to
    kBoth,   // emits to both sides (a double-sided light panel)
};

// atan2(y, x) for y > 0 (an angle in (0, pi)), within one unit in the last place of
// std::atan2 (polygon_light_test sweeps it): Cephes' rational atan on [0, 0.66] and one
// reduction step, at about half glibc's cost. LambertSum takes one per edge, and the
// penumbra's cells made glibc's atan2 ~6 % of a solve's CPU (bench/RESULTS.md, "Issue 13
// (session 18)").
double EdgeAngle(double y, double x);

// Lambert's boundary sum over the closed polygon v[0..nv) seen from x:
// sum_k theta_k * unit(a_k x e_k), a_k = v_k - x, e_k = v_k+1 - v_k (a x e equals
// (v_k - x) x (v_k+1 - x) but loses less to cancellation when x is far from the edge).
// For a polygon wound counter-clockwise seen from x it points away from the polygon;
// the vector irradiance of a uniform polygon is -L/2 times it.
Vec3d LambertSum(const Vec3d* v, int nv, const Vec3d& x);

// One edge's term of LambertSum: theta * unit(a x e) for the edge p -> q, zero when x is on
// the edge's line (it subtends no solid angle). Sums over edges are additive: the
// penumbra's cells share edges, which it evaluates once (penumbra.cpp).
Vec3d LambertEdge(const Vec3d& p, const Vec3d& q, const Vec3d& x);

// Sutherland-Hodgman: the part of polygon v[0..nv) in {y : (y - x).n >= 0}, written to
// out (room for 2 nv vertices: each edge emits at most two); returns its vertex count. A
// non-convex polygon may come out with zero-area bridges, which boundary integrals (as
// Lambert's formula) cancel exactly.
int ClipToHalfSpace(const Vec3d* v, int nv, const Vec3d& x, const Vec3d& n, Vec3d* out);

// Unit front normal (Newell's method, robust for non-convex polygons); zero if degenerate.
Vec3d PolygonNormal(std::span<const Vec3d> polygon);
double PolygonArea(std::span<const Vec3d> polygon);

// E(x) as defined above, not clipped by any receiver tangent plane (E is a field; the
// receiver's normal enters only at display/shooting time through max(0, n.E)).
Vec3d VectorIrradiance(std::span<const Vec3d> polygon, double radiance, const Vec3d& x,
                       Emission emission = Emission::kFront);

// Irradiance of a receiver at x with unit normal n: the emitter is clipped to the receiver's
// upper half-space {y : (y-x).n >= 0} first, so parts below the horizon do not subtract.
// Equals the integral of L max(0, cos theta_x) cos theta_y / r^2 over the emitter.
double IrradianceClipped(std::span<const Vec3d> polygon, double radiance, const Vec3d& x,
                         const Vec3d& n, Emission emission = Emission::kFront);

}  // namespace mebake::solve
