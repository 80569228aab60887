// Uniform and CIE overcast sky: closed-form vector irradiance and tilted irradiance, and a
// Fibonacci direction set for visibility-weighted sky transfer. See sky.h.
#include "solve/sky.h"

#include "core/check.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

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

Vec3d HalfSpacesVector(std::span<const Vec3d> planes) {
    // Distinct unit normals (a plane twice would count its arc twice), at most three; fixed
    // arrays, no heap: the sky calls this once per receiver point.
    std::array<Vec3d, 3> unit;
    size_t n = 0;
    for (const Vec3d& p : planes) {
        const double len = Length(p);
        if (len == 0)
            continue;
        const Vec3d q = p / len;
        if (std::none_of(unit.begin(), unit.begin() + std::ptrdiff_t(n),
                         [&](const Vec3d& r) { return Dot(q, r) > 1 - 1e-12; })) {
            CHECK_LT(n, unit.size());
            unit[n++] = q;
        }
    }
    Vec3d sum{};
    for (size_t i = 0; i < n; ++i) {
        // The great circle of plane i, c(phi) = cos phi u + sin phi v; each other plane keeps
        // the half of it centred on the plane's projection: a semicircle.
        const Vec3d& a = unit[i];
        const Vec3d t = std::abs(a.x) < 0.9 ? Vec3d{1, 0, 0} : Vec3d{0, 1, 0};
        const Vec3d u = Normalize(Cross(a, t)), v = Cross(a, u);
        std::array<double, 2> centres;
        size_t nc = 0;
        for (size_t j = 0; j < n; ++j) {
            const double x = Dot(u, unit[j]), y = Dot(v, unit[j]);
            if (j != i && x * x + y * y > 1e-24)  // else the circles coincide (opposite planes)
                centres[nc++] = std::atan2(y, x);
        }
        // Two semicircles whose centres are d apart overlap over pi - d.
        const double arc =
            nc == 0   ? 2 * M_PI
            : nc == 1 ? M_PI
                      : std::max(0.0, M_PI - std::abs(std::remainder(centres[0] - centres[1],
                                                                     2 * M_PI)));
        sum += a * (0.5 * arc);
    }
    return sum;
}

std::vector<Vec3f> SkyDirections(int requested) {
    std::vector<Vec3f> dirs;
    const int k = std::max(2, int(std::lround(std::sqrt(double(requested)))));
    for (int i = 0; i < k; ++i) {
        const double z = (i + 0.5) / k, radius = std::sqrt(1 - z * z);
        for (int j = 0; j < k; ++j) {
            const double phi = 2 * std::numbers::pi * (j + 0.5 + 0.618034 * i) / k;
            dirs.push_back(
                Vec3f(float(radius * std::cos(phi)), float(radius * std::sin(phi)), float(z)));
        }
    }
    return dirs;
}

}  // namespace mebake::solve
