#include "output/tonemap.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

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

namespace {

// The curve of a radiance already scaled by 2^exposure.
float Curve(float x, ToneCurve curve) {
    if (!(x > 0))
        return 0;  // also NaN
    float y;
    switch (curve) {
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

}  // namespace

float ApplyToneCurve(float radiance, const ToneMap& tm) {
    return Curve(radiance * std::exp2(tm.exposure), tm.curve);
}

float EncodeSrgb(float c) {
    c = std::clamp(c, 0.f, 1.f);
    return c <= 0.0031308f ? 12.92f * c : 1.055f * std::pow(c, 1 / 2.4f) - 0.055f;
}

namespace {

uint8_t ToSrgb8Direct(float display_linear) {
    return uint8_t(std::lround(std::clamp(EncodeSrgb(display_linear), 0.f, 1.f) * 255.f));
}

// ToSrgb8 without a pow per channel, the same codes: the code rises with the value, so it
// is known from the values where it steps. `first[k]` is the smallest float whose code is k
// or more (bisection over the float bits of [0, 1] with the formula itself). Above
// first[1], `base` holds the code at the start of each bucket of floats sharing their top
// 16 bits (exponent and 7 mantissa bits); a bucket is under 1/2 code wide (the steepest,
// just below 1: 2^-8 x 255 / 2.4 x 1.055 = 0.44), so a value is its bucket's code or one
// more.
struct Srgb8Table {
    static constexpr int kShift = 16;
    std::array<float, 257> first{};  // first[256] = infinity: no code above 255
    uint32_t bucket0 = 0;            // the bucket of first[1]
    std::vector<uint8_t> base;

    Srgb8Table() {
        const uint32_t one = std::bit_cast<uint32_t>(1.f);  // code(1) = 255
        for (int k = 1; k < 256; ++k) {
            uint32_t lo = 0, hi = one;
            while (lo < hi) {
                const uint32_t mid = lo + (hi - lo) / 2;
                if (ToSrgb8Direct(std::bit_cast<float>(mid)) >= k)
                    hi = mid;
                else
                    lo = mid + 1;
            }
            first[size_t(k)] = std::bit_cast<float>(lo);
        }
        first[256] = std::numeric_limits<float>::infinity();
        bucket0 = std::bit_cast<uint32_t>(first[1]) >> kShift;
        for (uint32_t b = bucket0; b <= one >> kShift; ++b)
            base.push_back(ToSrgb8Direct(std::max(std::bit_cast<float>(b << kShift), first[1])));
    }
};

}  // namespace

uint8_t ToSrgb8(float display_linear) {
    static const Srgb8Table t;
    if (!(display_linear >= t.first[1]))  // code 0, and negatives and NaN as the formula says
        return ToSrgb8Direct(display_linear);
    if (display_linear >= 1.f)
        return 255;
    const uint8_t code = t.base[(std::bit_cast<uint32_t>(display_linear) >> Srgb8Table::kShift) -
                                t.bucket0];
    return uint8_t(code + (display_linear >= t.first[size_t(code) + 1]));
}

void ToneMapPixel(const Vec3f& radiance, const ToneMap& tm, uint8_t out[3]) {
    const float scale = std::exp2(tm.exposure);  // ApplyToneCurve's, once for the three
    for (int c = 0; c < 3; ++c)
        out[c] = ToSrgb8(Curve(radiance[c] * scale, tm.curve));
}

}  // namespace mebake::output
