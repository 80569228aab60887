#include "output/tonemap.h"

#include <algorithm>
#include <cmath>

namespace mebake::output {

std::optional<ToneCurve> ParseToneCurve(const std::string& name) {
    if (name == "filmic")
        return ToneCurve::Filmic;
    if (name == "reinhard")
        return ToneCurve::Reinhard;
    if (name == "clamp")
        return ToneCurve::Clamp;
    return std::nullopt;
}

float ApplyToneCurve(float radiance, const ToneMap& tm) {
    const float x = radiance * std::exp2(tm.exposure);
    if (!(x > 0))
        return 0;  // also NaN
    float y;
    switch (tm.curve) {
    case ToneCurve::Filmic:
        y = (x * (2.51f * x + 0.03f)) / (x * (2.43f * x + 0.59f) + 0.14f);
        break;
    case ToneCurve::Reinhard:
        y = std::isinf(x) ? 1.f : x / (1 + x);
        break;
    case ToneCurve::Clamp:
    default:
        y = x;
        break;
    }
    return std::isnan(y) ? 1.f : std::clamp(y, 0.f, 1.f);
}

float EncodeSrgb(float c) {
    c = std::clamp(c, 0.f, 1.f);
    return c <= 0.0031308f ? 12.92f * c : 1.055f * std::pow(c, 1 / 2.4f) - 0.055f;
}

uint8_t ToSrgb8(float display_linear) {
    return uint8_t(std::lround(std::clamp(EncodeSrgb(display_linear), 0.f, 1.f) * 255.f));
}

void ToneMapPixel(const Vec3f& radiance, const ToneMap& tm, uint8_t out[3]) {
    for (int c = 0; c < 3; ++c)
        out[c] = ToSrgb8(ApplyToneCurve(radiance[c], tm));
}

}  // namespace mebake::output
