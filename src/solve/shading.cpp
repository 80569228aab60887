#include "solve/shading.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace mebake::solve {

namespace {
float SrgbToLinear(float c) {
    return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
}
constexpr float kPi = float(std::numbers::pi);
}  // namespace

Vec3f SurfaceAlbedo(const Material& m, const Vec3f& color) {
    Vec3f a = m.albedo;
    if (m.use_vertex_colors && color.x >= 0)
        for (int c = 0; c < 3; ++c)
            a[c] = std::min(0.99f, SrgbToLinear(color[c]) * m.color_factor);
    return a;
}

Vec3f ShadeRadiosity(const float* val, bool radiosity_unknown, const Vec3f& n, const Vec3f& albedo,
                     const Material& m) {
    Vec3f b = m.emission * kPi;
    for (int c = 0; c < 3; ++c) {
        if (radiosity_unknown) {
            b[c] += std::max(0.f, val[c]);
        } else {
            float irr = n.x * val[3 * c] + n.y * val[3 * c + 1] + n.z * val[3 * c + 2];
            b[c] += albedo[c] * std::max(0.f, irr);
        }
    }
    return b;
}

void VectorIrradianceAt(const float* val, bool radiosity_unknown, Vec3f e[3]) {
    if (radiosity_unknown) {
        e[0] = e[1] = e[2] = Vec3f{};
        return;
    }
    for (int c = 0; c < 3; ++c)
        e[c] = Vec3f(val[3 * c], val[3 * c + 1], val[3 * c + 2]);
}

Vec3f ShadeGlossy(const float* val, bool radiosity_unknown, const Vec3f& n, const Vec3f& view,
                  const Vec3f& albedo, const Material& m) {
    Vec3f diffuse = ShadeRadiosity(val, radiosity_unknown, n, albedo, m) / kPi;
    if (m.glossy_exponent <= 0 || m.glossy_weight <= 0 || radiosity_unknown)
        return diffuse;
    Vec3f e[3];
    VectorIrradianceAt(val, radiosity_unknown, e);
    Vec3f out = diffuse * (1 - m.glossy_weight);
    for (int c = 0; c < 3; ++c) {
        float mag = Length(e[c]);
        if (mag <= 0)
            continue;
        Vec3f wi = e[c] / mag;                // where the light comes from, on average
        Vec3f r = n * (2 * Dot(n, wi)) - wi;  // its mirror direction
        float cos_r = std::max(0.f, Dot(r, view));
        float lobe = (m.glossy_exponent + 2) / (2 * kPi) * std::pow(cos_r, m.glossy_exponent);
        out[c] += m.glossy_weight * albedo[c] * mag * lobe * std::max(0.f, Dot(n, wi));
    }
    return out;
}

}  // namespace mebake::solve
