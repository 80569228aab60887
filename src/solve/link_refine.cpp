#include "solve/link_refine.h"

#include "solve/basis.h"
#include "solve/field.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace mebake::solve {

namespace {

constexpr double kHalfPi = std::numbers::pi / 2;

double AngleBetween(const Vec3f& a, const Vec3f& b) {
    return std::acos(std::clamp(double(Dot(a, b)), -1.0, 1.0));
}

// An angle as its cosine and sine: ConeLinkBound's angles are summed and compared by
// the sum formulas instead of acos, add, cos (those calls were ~2.5 % of a solve).
struct CosSin {
    double c, s;
};
CosSin Of(double angle) { return {std::cos(angle), std::sin(angle)}; }
CosSin Sum(const CosSin& a, const CosSin& b) {
    return {a.c * b.c - a.s * b.s, a.s * b.c + a.c * b.s};
}
// The angle between unit vectors a and b, in [0, pi].
CosSin Between(const Vec3f& a, const Vec3f& b) {
    const double c = std::clamp(double(Dot(a, b)), -1.0, 1.0);
    return {c, std::sqrt(1 - c * c)};
}

// The largest cosine between a direction within `spread` of `dir` and a normal of a cone
// about `axis` whose angle (below pi/2) is `cone`: cos of the gap theta - phi, phi = the
// cone's angle + spread; 1 where the gap closes, 0 past pi/2. With spread <= pi/2, phi is
// below pi, where the cosine decreases: theta <= phi is cos theta >= cos phi.
double MaxCosine(const Vec3f& dir, const CosSin& spread, const Vec3f& axis, const CosSin& cone) {
    const CosSin theta = Between(dir, axis), phi = Sum(cone, spread);
    if (theta.c >= phi.c)
        return 1;
    return std::max(0.0, theta.c * phi.c + theta.s * phi.s);  // cos(theta - phi)
}

}  // namespace

NormalCone ConeAround(const Vec3f& axis, const Vec3f* normals, size_t count) {
    // The widest normal is the one of the smallest cosine: one acos per cone, not one per
    // normal (acos decreases, so it is the largest of the angles to the bit).
    double lowest = 1;
    for (size_t k = 0; k < count; ++k)
        if (Dot(normals[k], normals[k]) > 0)
            lowest = std::min(lowest, std::clamp(double(Dot(axis, Normalize(normals[k]))), -1.0, 1.0));
    NormalCone c{axis, float(std::acos(lowest))};
    if (c.angle >= kHalfPi)
        c.angle = float(std::numbers::pi);
    return c;
}

NormalCone Enclose(const Vec3f& axis, const NormalCone& a, const NormalCone& b) {
    const double wa = a.angle + AngleBetween(axis, a.axis);
    const double wb = b.angle + AngleBetween(axis, b.axis);
    const double w = std::max(wa, wb);
    // Rounding in acos: widen by a hair so a child's normal never falls outside.
    return {axis, w >= kHalfPi ? float(std::numbers::pi) : float(w) + 1e-6f};
}

void SphereBuilder::Get(const Vec3f& fallback_c, float fallback_r, Vec3f* c, float* r) const {
    *c = fallback_c;
    *r = fallback_r;
    if (parts_.empty())
        return;
    Vec3f lo = parts_[0].c, hi = parts_[0].c;
    for (const Part& p : parts_) {
        const Vec3f e(p.r, p.r, p.r);
        lo = Min(lo, p.c - e);
        hi = Max(hi, p.c + e);
    }
    const Vec3f mid = (lo + hi) * 0.5f;
    float rad = 0;
    for (const Part& p : parts_)
        rad = std::max(rad, Length(p.c - mid) + p.r);
    rad *= 1 + 1e-6f;  // rounding
    if (rad < fallback_r) {
        *c = mid;
        *r = rad;
    }
}

double ConeLinkBound(double db_max, double power, const LinkSide& r, const LinkSide& e) {
    const bool r_cone = r.cone.angle < kHalfPi, e_cone = e.cone.angle < kHalfPi;
    const CosSin rc = r_cone ? Of(r.cone.angle) : CosSin{};
    const CosSin ec = e_cone ? Of(e.cone.angle) : CosSin{};
    // Touching or not: the band of directions both sides allow.
    // psi >= the cones' angles, and where those reach 1.1 (past pi / 3, with the cosine's
    // rounding far below the gap) 2 (1 - cos psi) > 1: band is 1 without the axes' angle.
    // Past pi, cos psi <= -cos 1.1 < 1/2: band is 1 as at pi.
    double band = 1;
    if (r_cone && e_cone && r.cone.angle + e.cone.angle < 1.1f) {
        const double cos_psi = Sum(Sum(rc, ec), Between(r.cone.axis, e.cone.axis)).c;
        band = std::min(1.0, 2 * (1 - cos_psi));
    }
    const Vec3f d = e.center - r.center;
    const double dist = Length(d), gap = dist - r.radius - e.radius;
    if (gap <= 0)
        return db_max * band;
    const Vec3f u = d / float(dist);
    // The spread alpha = asin((r_r + r_e) / D), below pi/2 as the gap is positive.
    const double sin_alpha = std::min(1.0, (double(r.radius) + e.radius) / dist);
    const CosSin alpha{std::sqrt(1 - sin_alpha * sin_alpha), sin_alpha};
    const double far = power / (std::numbers::pi * gap * gap) *
                       (r_cone ? MaxCosine(u, alpha, r.cone.axis, rc) : 1) *
                       (e_cone ? MaxCosine(-u, alpha, e.cone.axis, ec) : 1);
    return std::min(db_max * band, far);
}

double NodeIrradiance(const ChartField& field, size_t node) {
    // c_00 of each block is the block's mean over the node (basis.h).
    const int n = NumCoeffs(field.order());
    const float* v = field.value(node);
    double sum = 0;
    if (field.blocks() == 9) {
        for (int c = 0; c < 3; ++c) {
            const double x = v[(3 * c) * n], y = v[(3 * c + 1) * n], z = v[(3 * c + 2) * n];
            sum += std::sqrt(x * x + y * y + z * z);
        }
    } else {
        for (int c = 0; c < field.blocks(); ++c)
            sum += std::max(0.f, v[c * n]);
    }
    return sum / 3;
}

LinkTolerance::LinkTolerance(const ChartField& field, double scale, double floor_irradiance) {
    if (scale <= 0)
        return;
    allowed_.resize(field.node_count());
    for (size_t n = 0; n < allowed_.size(); ++n)
        allowed_[n] = float(scale * std::max(NodeIrradiance(field, n), floor_irradiance));
}

}  // namespace mebake::solve
