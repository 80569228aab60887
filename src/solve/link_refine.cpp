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

// The largest cosine between a direction within `spread` of `dir` and a normal of `cone`.
double MaxCosine(const Vec3f& dir, double spread, const NormalCone& cone) {
    if (cone.angle >= kHalfPi)
        return 1;
    const double gap = AngleBetween(dir, cone.axis) - cone.angle - spread;
    return gap <= 0 ? 1 : gap >= kHalfPi ? 0 : std::cos(gap);
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
    // Touching or not: the band of directions both sides allow.
    // psi >= the cones' angles, and where those reach 1.1 (past pi / 3, with the cosine's
    // rounding far below the gap) 2 (1 - cos psi) > 1: band is 1 without the axes' angle.
    double band = 1;
    const float cones = r.cone.angle + e.cone.angle;
    if (r.cone.angle < kHalfPi && e.cone.angle < kHalfPi && cones < 1.1f) {
        const double psi = cones + AngleBetween(r.cone.axis, e.cone.axis);
        band = std::min(1.0, 2 * (1 - std::cos(std::min(psi, std::numbers::pi))));
    }
    const Vec3f d = e.center - r.center;
    const double dist = Length(d), gap = dist - r.radius - e.radius;
    if (gap <= 0)
        return db_max * band;
    const Vec3f u = d / float(dist);
    const double alpha = std::asin(std::min(1.0, (double(r.radius) + e.radius) / dist));
    const double far = power / (std::numbers::pi * gap * gap) * MaxCosine(u, alpha, r.cone) *
                       MaxCosine(-u, alpha, e.cone);
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
