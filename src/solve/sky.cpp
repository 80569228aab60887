// Uniform and CIE overcast sky: closed-form vector irradiance and tilted irradiance, and a
// Fibonacci direction set for visibility-weighted sky transfer. See sky.h.
#include "solve/sky.h"

#include "core/check.h"

#include <algorithm>
#include <cmath>

namespace mebake::solve {

SkyModel SkyModel::Uniform(double radiance, const Vec3d& up) {
    return {radiance, 0, Normalize(up)};
}

SkyModel SkyModel::CieOvercast(double zenith_radiance, const Vec3d& up) {
    return {zenith_radiance / 3, 2 * zenith_radiance / 3, Normalize(up)};
}

double SkyModel::Radiance(const Vec3d& w) const {
    const double c = Dot(up, w);
    return c > 0 ? a + b * c : 0;
}

Vec3d SkyVectorIrradiance(const SkyModel& sky) {
    return sky.up * (M_PI * sky.a + 2 * M_PI * sky.b / 3);
}

double SkyIrradiance(const SkyModel& sky, const Vec3d& n) {
    const double c = std::clamp(Dot(n, sky.up) / std::max(Length(n), 1e-300), -1.0, 1.0);
    const double alpha = std::acos(c);
    const double i0 = 0.5 * M_PI * (1 + c);
    const double i1 = (2.0 / 3.0) * ((M_PI - alpha) * c + std::sqrt(std::max(0.0, 1 - c * c)));
    return sky.a * i0 + sky.b * i1;
}

SkySamples MakeSkySamples(const SkyModel& sky, int n) {
    CHECK_GT(n, 0);
    SkySamples s;
    s.dir.resize(size_t(n));
    s.weight.resize(size_t(n));
    // Orthonormal frame around up.
    const Vec3d w = sky.up;
    const Vec3d t = std::abs(w.x) < 0.9 ? Vec3d{1, 0, 0} : Vec3d{0, 1, 0};
    const Vec3d u = Normalize(Cross(t, w));
    const Vec3d v = Cross(w, u);
    const double golden = M_PI * (3 - std::sqrt(5.0));
    const double solid_angle = 2 * M_PI / n;
    for (int k = 0; k < n; ++k) {
        // z uniform in (0,1) gives equal solid angle per sample on the hemisphere.
        const double z = 1 - (k + 0.5) / n;
        const double r = std::sqrt(std::max(0.0, 1 - z * z));
        const double phi = golden * k;
        const Vec3d d = u * (r * std::cos(phi)) + v * (r * std::sin(phi)) + w * z;
        s.dir[size_t(k)] = Vec3f(d);
        s.weight[size_t(k)] = float((sky.a + sky.b * z) * solid_angle);
    }
    return s;
}

Vec3d SkyTransfer(const SkySamples& samples, std::span<const uint8_t> visible) {
    CHECK(visible.empty() || visible.size() == samples.dir.size());
    Vec3d e;
    for (size_t k = 0; k < samples.dir.size(); ++k) {
        if (!visible.empty() && !visible[k])
            continue;
        e += Vec3d(samples.dir[k]) * double(samples.weight[k]);
    }
    return e;
}

SkyVisibility SkyOpenness(const SkySamples& samples, std::span<const uint8_t> visible) {
    CHECK(visible.empty() || visible.size() == samples.dir.size());
    double total = 0, open = 0;
    for (size_t k = 0; k < samples.dir.size(); ++k) {
        total += samples.weight[k];
        if (visible.empty() || visible[k])
            open += samples.weight[k];
    }
    SkyVisibility r;
    r.open_fraction = total > 0 ? open / total : 0;
    r.bent = Normalize(SkyTransfer(samples, visible));
    return r;
}

}  // namespace mebake::solve
