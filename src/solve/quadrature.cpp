// Point-to-patch vector irradiance transfer by quadrature, and the node-to-node transfer
// bound. See quadrature.h.
#include "solve/quadrature.h"

#include "core/check.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace mebake::solve {
namespace {

constexpr int kLanes = 8;
constexpr float kPi = 3.14159265358979f;
// Smallest denominator: keeps x == y_k finite (the numerator is then 0) in float.
constexpr float kTinyDenominator = 1e-30f;

// Transfer factor s_k such that dE_c = B_c s_k (y_k - x).
template <Kernel kKernel>
inline float Factor(const EmitterSamples& s, size_t k, float dx, float dy, float dz) {
    const float r2 = dx * dx + dy * dy + dz * dz;
    // (x - y).n = -(d.n)
    const float cos_num = -(dx * s.nx[k] + dy * s.ny[k] + dz * s.nz[k]);
    const float w = s.weight[k];
    float den;
    if constexpr (kKernel == Kernel::kDisk) {
        den = r2 * (kPi * r2 + w);
    } else {
        den = kPi * r2 * r2;
    }
    den = std::max(den, kTinyDenominator);
    return std::max(cos_num, 0.0f) * w / den;
}

template <Kernel kKernel>
void Accumulate(const EmitterSamples& s, std::span<const uint8_t> visible, const Vec3f& x,
                RgbVector* out) {
    const size_t n = s.size();
    const bool all_visible = visible.empty();
    // Fixed lanes: sample k always lands in lane k % kLanes, and lanes are summed in order at
    // the end, so the result does not depend on the compiler's vectorization.
    float acc[9][kLanes] = {};
    size_t k0 = 0;
    for (; k0 + kLanes <= n; k0 += kLanes) {
        for (int l = 0; l < kLanes; ++l) {
            const size_t k = k0 + l;
            const float dx = s.px[k] - x.x, dy = s.py[k] - x.y, dz = s.pz[k] - x.z;
            float f = Factor<kKernel>(s, k, dx, dy, dz);
            if (!all_visible)
                f = visible[k] ? f : 0.0f;
            const float fr = f * s.r[k], fg = f * s.g[k], fb = f * s.b[k];
            acc[0][l] += fr * dx;
            acc[1][l] += fr * dy;
            acc[2][l] += fr * dz;
            acc[3][l] += fg * dx;
            acc[4][l] += fg * dy;
            acc[5][l] += fg * dz;
            acc[6][l] += fb * dx;
            acc[7][l] += fb * dy;
            acc[8][l] += fb * dz;
        }
    }
    for (size_t k = k0; k < n; ++k) {
        const int l = int(k - k0);
        const float dx = s.px[k] - x.x, dy = s.py[k] - x.y, dz = s.pz[k] - x.z;
        float f = Factor<kKernel>(s, k, dx, dy, dz);
        if (!all_visible)
            f = visible[k] ? f : 0.0f;
        const float fr = f * s.r[k], fg = f * s.g[k], fb = f * s.b[k];
        acc[0][l] += fr * dx;
        acc[1][l] += fr * dy;
        acc[2][l] += fr * dz;
        acc[3][l] += fg * dx;
        acc[4][l] += fg * dy;
        acc[5][l] += fg * dz;
        acc[6][l] += fb * dx;
        acc[7][l] += fb * dy;
        acc[8][l] += fb * dz;
    }
    for (int i = 0; i < 9; ++i) {
        double sum = 0;
        for (int l = 0; l < kLanes; ++l)
            sum += acc[i][l];
        out->e[i] += sum;
    }
}

}  // namespace

void AccumulateTransfer(const EmitterSamples& samples, std::span<const uint8_t> visible,
                        const Vec3f& x, RgbVector* out, Kernel kernel) {
    const size_t n = samples.size();
    CHECK(samples.py.size() == n && samples.pz.size() == n && samples.nx.size() == n &&
          samples.ny.size() == n && samples.nz.size() == n && samples.weight.size() == n &&
          samples.r.size() == n && samples.g.size() == n && samples.b.size() == n);
    CHECK(visible.empty() || visible.size() == n);
    if (kernel == Kernel::kDisk) {
        Accumulate<Kernel::kDisk>(samples, visible, x, out);
    } else {
        Accumulate<Kernel::kPoint>(samples, visible, x, out);
    }
}

BoundingSphere ComputeBoundingSphere(std::span<const float> px, std::span<const float> py,
                                     std::span<const float> pz) {
    CHECK(py.size() == px.size() && pz.size() == px.size());
    BoundingSphere s;
    if (px.empty())
        return s;
    Vec3f lo{px[0], py[0], pz[0]}, hi = lo;
    for (size_t i = 1; i < px.size(); ++i) {
        const Vec3f p{px[i], py[i], pz[i]};
        lo = Min(lo, p);
        hi = Max(hi, p);
    }
    s.center = (lo + hi) * 0.5f;
    float r2 = 0;
    for (size_t i = 0; i < px.size(); ++i) {
        const Vec3f d = Vec3f{px[i], py[i], pz[i]} - s.center;
        r2 = std::max(r2, Dot(d, d));
    }
    // Round up so that float rounding of the centre never leaves a point outside.
    s.radius = std::sqrt(r2) * (1 + 1e-6f) + 1e-30f;
    return s;
}

TransferBound BoundTransfer(const BoundingSphere& emitter, double emitter_area, double b_max,
                            const BoundingSphere& receiver) {
    TransferBound t;
    const Vec3d d = Vec3d(emitter.center) - Vec3d(receiver.center);
    const double centre_dist = Length(d);
    const double radii = double(emitter.radius) + double(receiver.radius);
    t.gap = centre_dist - radii;
    t.spread = centre_dist > 0 ? radii / centre_dist : std::numeric_limits<double>::infinity();
    t.form_factor =
        t.gap > 0 ? emitter_area / (M_PI * t.gap * t.gap) : std::numeric_limits<double>::infinity();
    t.e_max = b_max * std::min(t.form_factor, 4.0);
    return t;
}

}  // namespace mebake::solve
