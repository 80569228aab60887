// Penumbral radiance estimate (penumbra_estimate.h; seed 002, section 5.4).
#include "solve/penumbra_estimate.h"

#include "core/check.h"
#include "solve/polygon_light.h"
#include "stream/square_fit.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace mebake::solve {

double BackprojectedIrradiance(std::span<const Vec3d> light, const ConvexOccluder& occluder,
                               const Vec3d& x, const Vec3d& n) {
    // The light's plane coordinates: e1 along its first edge, e2 = normal x e1, so a light
    // wound counter-clockwise from its front is counter-clockwise in (e1, e2).
    const Vec3d ln = PolygonNormal(light);
    const Vec3d e1 = Normalize(light[1] - light[0]), e2 = Cross(ln, e1);
    auto to2 = [&](const Vec3d& p) {
        return Vec2d{Dot(p - light[0], e1), Dot(p - light[0], e2)};
    };
    std::vector<Vec2d> lp, shadow;
    for (const auto& v : light)
        lp.push_back(to2(v));
    const double hx = Dot(ln, x - light[0]);
    for (const auto& o : occluder.vertices) {
        // The ray from x through o to the light's plane (the occluder lies between them; a
        // vertex level with x, as a block's foot on the receiver, projects very far out).
        const double ho = Dot(ln, o - light[0]);
        shadow.push_back(to2(x + (o - x) * (hx / std::max(hx - ho, 1e-7 * hx))));
    }
    // Hidden part of the light: the light intersected with the occluder's projection.
    std::vector<Vec2d> hidden = stream::ConvexHull(shadow);
    for (size_t k = 0; k < lp.size() && hidden.size() >= 3; ++k) {
        const Vec2d a = lp[k], b = lp[(k + 1) % lp.size()];
        std::vector<Vec2d> out;
        for (size_t i = 0; i < hidden.size(); ++i) {
            const Vec2d p = hidden[i], q = hidden[(i + 1) % hidden.size()];
            const double fp = Cross(b - a, p - a), fq = Cross(b - a, q - a);
            if (fp >= 0)
                out.push_back(p);
            if ((fp >= 0) != (fq >= 0))
                out.push_back(p + (q - p) * (fp / (fp - fq)));
        }
        hidden.swap(out);
    }
    double e = IrradianceClipped(light, 1.0, x, n);
    if (hidden.size() >= 3) {
        std::vector<Vec3d> h3;
        for (const auto& p : hidden)
            h3.push_back(light[0] + e1 * p.x + e2 * p.y);
        e -= IrradianceClipped(h3, 1.0, x, n);
    }
    return std::max(0.0, e);
}

PenumbraEstimate EstimatePenumbra(const ExactExtremalBoundary& eb, size_t k,
                                  std::span<const Vec3d> light, const ConvexOccluder& occluder,
                                  const ReceiverPlane& plane, const Vec2d& st) {
    PenumbraEstimate est;
    const auto& mn = eb.minimal(k);
    const auto& mx = eb.maximal(k);
    if (mn.size() < 3 || mx.size() < 3)
        return est;
    // The minimal edge whose endpoints are closest to P.
    size_t best = 0;
    double best_d = std::numeric_limits<double>::max();
    for (size_t i = 0; i < mn.size(); ++i) {
        const double d = Length(mn[i] - st) + Length(mn[(i + 1) % mn.size()] - st);
        if (d < best_d)
            best_d = d, best = i;
    }
    const Vec2d m = (mn[best] + mn[(best + 1) % mn.size()]) * 0.5;
    const double sp = Length(st - m);
    const Vec3d n = Normalize(Cross(plane.u, plane.v));
    const Vec3d xp = plane.At(st);
    est.ok = true;
    if (sp < 1e-12)
        return est;
    const Vec2d d = (st - m) / sp;
    // Where the line leaves the maximal polygon (convex, counter-clockwise).
    double sb = std::numeric_limits<double>::max();
    for (size_t i = 0; i < mx.size(); ++i) {
        const Vec2d a = mx[i], e = mx[(i + 1) % mx.size()] - mx[i];
        const Vec2d out_n{e.y, -e.x};  // outward normal
        const double rate = Dot(out_n, d);
        if (rate > 0)
            sb = std::min(sb, Dot(out_n, a - m) / rate);
    }
    if (!(sb > sp))
        sb = sp;  // P on (or numerically past) the maximal boundary
    const Vec3d xb = plane.At(m + d * sb);
    const double eb1 = IrradianceClipped(light, 1.0, xb, n);
    // Derivatives from local backprojections a small step inside each end.
    const double h = 1e-3 * sb;
    const double d0 = BackprojectedIrradiance(light, occluder, plane.At(m + d * h), n) / h;
    const double d1 =
        (eb1 - BackprojectedIrradiance(light, occluder, plane.At(m + d * (sb - h)), n)) / h;
    const double t = sp / sb, t2 = t * t, t3 = t2 * t;
    const double v = (-2 * t3 + 3 * t2) * eb1 + (t3 - 2 * t2 + t) * sb * d0 + (t3 - t2) * sb * d1;
    const double unocc = IrradianceClipped(light, 1.0, xp, n);
    est.hermite = std::clamp(v, 0.0, unocc);
    est.linear = std::clamp(t * eb1, 0.0, unocc);
    return est;
}

}  // namespace mebake::solve
