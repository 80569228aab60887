// Lambert's closed form for the vector irradiance of a uniform polygon, with one/two-sided
// emission and clipping to a receiver's upper half-space. See polygon_light.h.
#include "solve/polygon_light.h"

#include "core/check.h"

#include <algorithm>
#include <cmath>

namespace mebake::solve {

namespace {

// atan(x) for 0 <= |x| <= 0.66: x + x^3 P(x^2) / Q(x^2), Cephes' atan.c (S. L. Moshier),
// relative error ~1e-16.
double AtanSmall(double x) {
    constexpr double P[] = {-8.750608600031904122785E-1, -1.615753718733365076637E1,
                            -7.500855792314704667340E1, -1.228866684490136173410E2,
                            -6.485021904942025371773E1};
    constexpr double Q[] = {2.485846490142306297962E1, 1.650270098316988542046E2,
                            4.328810604912902668951E2, 4.853903996359136964868E2,
                            1.945506571482613964425E2};
    const double z = x * x;
    const double p = (((P[0] * z + P[1]) * z + P[2]) * z + P[3]) * z + P[4];
    const double q = ((((z + Q[0]) * z + Q[1]) * z + Q[2]) * z + Q[3]) * z + Q[4];
    return x + x * (z * p / q);
}

// EdgeAngle's body, inlined into LambertEdge (a call per edge showed as ~2 % of the
// bunny's solve once the penumbra's edges were summed one by one).
inline double Angle(double y, double x) {
    // pi/4, pi/2 and pi as two doubles each (value + the rest), as Cephes adds them.
    constexpr double kPio4 = 0.78539816339744830962, kPio4Lo = 3.061616997868382943065E-17;
    constexpr double kPio2 = 1.57079632679489661923, kPio2Lo = 6.123233995736765886130E-17;
    constexpr double kPi = 3.14159265358979323846, kPiLo = 1.2246467991473531772E-16;
    const double ax = std::abs(x);
    const double lo = std::min(y, ax), hi = std::max(y, ax);
    // The angle of (hi, lo) in [0, pi/4]: above tan = 0.66 by atan(t) = pi/4 + atan((t-1)/(t+1)).
    double t = lo <= 0.66 * hi ? AtanSmall(lo / hi)
                               : kPio4 + (AtanSmall((lo - hi) / (lo + hi)) + kPio4Lo);
    if (y > ax)
        t = (kPio2 - t) + kPio2Lo;
    if (x < 0)
        t = (kPi - t) + kPiLo;
    return t;
}

}  // namespace

double EdgeAngle(double y, double x) { return Angle(y, x); }

Vec3d LambertEdge(const Vec3d& p, const Vec3d& q, const Vec3d& x) {
    const Vec3d a = p - x, b = q - x;
    const Vec3d c = Cross(a, q - p);
    const double len = Length(c);
    // len == 0: x is on the edge's line, the edge subtends no solid angle (theta = 0) or x
    // is on the edge itself (on the emitter's plane, handled by the caller).
    if (!(len > 0))
        return Vec3d{};
    return c * (Angle(len, Dot(a, b)) / len);
}

Vec3d LambertSum(const Vec3d* v, int nv, const Vec3d& x) {
    Vec3d sum;
    for (int k = 0; k < nv; ++k)
        sum += LambertEdge(v[k], v[k + 1 == nv ? 0 : k + 1], x);
    return sum;
}

int ClipToHalfSpace(const Vec3d* v, int nv, const Vec3d& x, const Vec3d& n, Vec3d* out) {
    if (nv <= 0)
        return 0;
    int nc = 0;
    // Each vertex's side once: an edge's dq is the next edge's dp (the same product).
    const double d0 = Dot(v[0] - x, n);
    double dp = d0;
    for (int k = 0; k < nv; ++k) {
        const Vec3d& p = v[k];
        const bool last = k + 1 == nv;
        const Vec3d& q = v[last ? 0 : k + 1];
        const double dq = last ? d0 : Dot(q - x, n);
        if (dp >= 0)
            out[nc++] = p;
        if ((dp >= 0) != (dq >= 0))
            out[nc++] = p + (q - p) * (dp / (dp - dq));
        dp = dq;
    }
    return nc;
}

namespace {

// Signed side of x: +1 in front, -1 behind, 0 on the plane (relative tolerance) or degenerate.
int Side(std::span<const Vec3d> polygon, const Vec3d& normal, const Vec3d& x) {
    Vec3d centroid;
    for (const Vec3d& v : polygon)
        centroid += v;
    centroid = centroid / double(polygon.size());
    // The largest distance from the centroid, with one square root: sqrt is correctly
    // rounded, hence monotonic, so this is the largest of the lengths to the bit.
    double scale2 = 0;
    for (const Vec3d& v : polygon)
        scale2 = std::max(scale2, Dot(v - centroid, v - centroid));
    const double d = Dot(normal, x - centroid);
    scale2 = std::max(scale2, Dot(x - centroid, x - centroid));
    if (!(std::abs(d) > 1e-14 * std::sqrt(scale2)))
        return 0;
    return d > 0 ? 1 : -1;
}

// Sign that turns the Lambert sum into E for a receiver on side `side`; 0 if no light.
double Orientation(int side, Emission emission) {
    if (side == 0)
        return 0;
    if (side < 0 && emission == Emission::kFront)
        return 0;
    // In front the polygon is counter-clockwise seen from x, so E = -(L/2) sum; behind it is
    // clockwise and the sign flips.
    return side > 0 ? -1.0 : 1.0;
}

}  // namespace

Vec3d PolygonNormal(std::span<const Vec3d> polygon) {
    Vec3d n;
    const size_t nv = polygon.size();
    for (size_t k = 0; k < nv; ++k) {
        const Vec3d& p = polygon[k];
        const Vec3d& q = polygon[(k + 1) % nv];
        n.x += (p.y - q.y) * (p.z + q.z);
        n.y += (p.z - q.z) * (p.x + q.x);
        n.z += (p.x - q.x) * (p.y + q.y);
    }
    return Normalize(n);
}

double PolygonArea(std::span<const Vec3d> polygon) {
    Vec3d sum;
    const size_t nv = polygon.size();
    if (nv < 3)
        return 0;
    for (size_t k = 1; k + 1 < nv; ++k)
        sum += Cross(polygon[k] - polygon[0], polygon[k + 1] - polygon[0]);
    return 0.5 * Length(sum);
}

Vec3d VectorIrradiance(std::span<const Vec3d> polygon, double radiance, const Vec3d& x,
                       Emission emission) {
    CHECK_LE(polygon.size(), size_t(kMaxPolygonVertices));
    if (polygon.size() < 3)
        return {};
    const Vec3d normal = PolygonNormal(polygon);
    const double sign = Orientation(Side(polygon, normal, x), emission);
    if (sign == 0)
        return {};
    return LambertSum(polygon.data(), int(polygon.size()), x) * (sign * 0.5 * radiance);
}

double IrradianceClipped(std::span<const Vec3d> polygon, double radiance, const Vec3d& x,
                         const Vec3d& n, Emission emission) {
    CHECK_LE(polygon.size(), size_t(kMaxPolygonVertices));
    if (polygon.size() < 3)
        return 0;
    const Vec3d normal = PolygonNormal(polygon);
    const double sign = Orientation(Side(polygon, normal, x), emission);
    if (sign == 0)
        return 0;
    Vec3d clipped[2 * kMaxPolygonVertices];
    const int nc = ClipToHalfSpace(polygon.data(), int(polygon.size()), x, n, clipped);
    if (nc < 3)
        return 0;
    const double e = Dot(n, LambertSum(clipped, nc, x)) * (sign * 0.5 * radiance);
    // The clipped part lies in the upper half-space, so the exact value is >= 0; rounding
    // for grazing configurations can leave a tiny negative number.
    return std::max(e, 0.0);
}

}  // namespace mebake::solve
