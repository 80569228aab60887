#include "solve/transfer.h"

#include "solve/polygon_light.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace mebake::solve {

// The texel as a square of its area in its tangent plane, clipped to x's upper half-space.
bool NearTransfer(const Vec3f& x, const Vec3f& n, const TexelSource& t, Vec3d* e) {
    const Vec3f nz = t.nrm;
    const Vec3f ref = std::abs(nz.x) < 0.9f ? Vec3f(1, 0, 0) : Vec3f(0, 1, 0);
    const Vec3f tu = Normalize(Cross(ref, nz)), tv = Cross(nz, tu);
    const double h = 0.5 * std::sqrt(double(t.area));
    const Vec3d c(t.pos), au(tu), av(tv);
    const Vec3d quad[4] = {c - au * h - av * h, c + au * h - av * h, c + au * h + av * h,
                           c - au * h + av * h};
    Vec3d clipped[8];
    const int nc = ClipToHalfSpace(quad, 4, Vec3d(x), Vec3d(n), clipped);
    if (nc < 3)
        return false;
    *e = VectorIrradiance({clipped, size_t(nc)}, 1.0 / std::numbers::pi, Vec3d(x));
    return true;
}

bool MixedFacetsTransfer(const Vec3f& x, const Vec3f& n, std::span<const TexelSource> facets,
                         double texel_side, Vec3d* e, int* carrier) {
    *e = Vec3d(0, 0, 0);
    double most = 0;
    bool any = false;
    for (size_t k = 0; k < facets.size(); ++k) {
        Vec3d part;
        if (facets[k].area <= 0 || !TexelTransfer(x, n, facets[k], 0.5 * texel_side, &part))
            continue;
        *e += part;
        any = true;
        if (Dot(part, Vec3d(n)) > most) {
            most = Dot(part, Vec3d(n));
            *carrier = int(k);
        }
    }
    return any;
}

FacetSpread SpreadOf(const TexelSource& t, std::span<const TexelSource> facets) {
    double offset = 0, tilt = 0, reach = 0;
    for (const TexelSource& f : facets) {
        if (f.area <= 0)
            continue;  // FacetedTransfer does not count it
        const Vec3d to = Vec3d(t.pos) - Vec3d(f.pos);
        const double rho = Length(to), delta = Length(Vec3d(f.nrm) - Vec3d(t.nrm));
        offset = std::max(offset, rho * delta + std::abs(Dot(to, Vec3d(t.nrm))));
        tilt = std::max(tilt, delta);
        reach = std::max(reach, rho);
    }
    // Margins for rounding: both sides' dot products are evaluated in double from floats
    // (relative error ~1e-15 of D + rho), and the bound is stored as floats.
    return {float((offset + 1e-6 * reach) * (1 + 1e-5)), float(tilt + 1e-6),
            float(reach * (1 + 1e-5))};
}

}  // namespace mebake::solve
