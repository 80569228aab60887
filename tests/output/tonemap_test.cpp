// ToSrgb8 looks the code up among the values where it steps (tonemap.cpp): it must give the
// formula's code everywhere, checked here around every step and on a sweep of [0, 1].
#include "output/tonemap.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>

namespace mebake::output {
namespace {

uint8_t Formula(float v) {
    return uint8_t(std::lround(std::clamp(EncodeSrgb(v), 0.f, 1.f) * 255.f));
}

TEST(ToneMap, Srgb8IsTheFormulasCodeAroundEveryStepAndOnASweep) {
    const uint32_t one = std::bit_cast<uint32_t>(1.f);
    uint32_t steps = 0, checked = 0;
    // Every 4093rd float of [0, 1], and 300 floats either side of each step found on the way.
    uint8_t last = Formula(0.f);
    for (uint64_t b = 0; b <= one; b += 4093) {
        const uint8_t code = Formula(std::bit_cast<float>(uint32_t(b)));
        if (code != last) {  // a step between b - 4093 and b: find it, check around it
            uint32_t lo = uint32_t(b - 4093), hi = uint32_t(b);
            while (lo + 1 < hi) {
                const uint32_t mid = lo + (hi - lo) / 2;
                (Formula(std::bit_cast<float>(mid)) == code ? hi : lo) = mid;
            }
            for (uint32_t x = hi - std::min(hi, 300u); x <= std::min(hi + 300, one); ++x, ++checked)
                ASSERT_EQ(ToSrgb8(std::bit_cast<float>(x)), Formula(std::bit_cast<float>(x)))
                    << std::bit_cast<float>(x);
            ++steps;
            last = code;
        }
        ASSERT_EQ(ToSrgb8(std::bit_cast<float>(uint32_t(b))), code) << std::bit_cast<float>(uint32_t(b));
    }
    EXPECT_EQ(steps, 255u);  // every code from 0 to 255 is reached
    EXPECT_GT(checked, 255u * 500);
    // Outside (0, 1]: as the formula.
    for (float v : {0.f, -0.f, -1.f, 1.f, 1.5f, std::numeric_limits<float>::infinity(),
                    std::numeric_limits<float>::denorm_min()})
        EXPECT_EQ(ToSrgb8(v), Formula(v)) << v;
    EXPECT_EQ(ToSrgb8(std::numeric_limits<float>::quiet_NaN()),
              Formula(std::numeric_limits<float>::quiet_NaN()));
}

}  // namespace
}  // namespace mebake::output

namespace mebake::output {
namespace {

// ToneMapPixel scales by 2^exposure once for its three channels: each channel's code is
// still ToSrgb8(ApplyToneCurve(channel)), for every curve and exposure.
TEST(ToneMap, PixelIsEachChannelsCurveAndCode) {
    for (const ToneCurve curve : {ToneCurve::Filmic, ToneCurve::Reinhard, ToneCurve::Clamp})
        for (const float exposure : {-3.3f, 0.f, 0.7f, 2.f}) {
            const ToneMap tm{exposure, curve};
            for (int i = 0; i < 20000; ++i) {
                const Vec3f r(float(i) * 1.3e-4f, std::exp(float(i % 97) * 0.2f - 12.f),
                              i % 5 == 0 ? -1.f : float(i) * 7e-3f);
                uint8_t px[3];
                ToneMapPixel(r, tm, px);
                for (int c = 0; c < 3; ++c)
                    ASSERT_EQ(px[c], ToSrgb8(ApplyToneCurve(r[c], tm)))
                        << "curve " << int(curve) << " exposure " << exposure << " value " << r[c];
            }
        }
}

}  // namespace
}  // namespace mebake::output
