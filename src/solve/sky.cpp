// Uniform and CIE overcast sky: closed-form vector irradiance and tilted irradiance, and a
// Fibonacci direction set for visibility-weighted sky transfer. See sky.h.
#include "solve/sky.h"

#include "core/check.h"

#include <algorithm>
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
