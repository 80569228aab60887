// From linear radiance to 8-bit display values: exposure in stops (EV), a tone curve, and
// the sRGB transfer function (IEC 61966-2-1). Used for every PNG mebake writes (light maps,
// the light map embedded in a .glb, rendered views, per-vertex colours), so they agree.
//
// Curves, applied per channel to x = radiance * 2^EV:
//   Filmic   the ACES filmic fit of Narkowicz (2015), "ACES Filmic Tone Mapping Curve":
//            (x (2.51 x + 0.03)) / (x (2.43 x + 0.59) + 0.14), clamped to [0, 1];
//   Reinhard x / (1 + x) (Reinhard et al. 2002, simple operator);
//   Clamp    min(x, 1): linear, for exact values in tests and for already display-ready data.
#pragma once

#include "core/vec.h"

#include <cstdint>
#include <optional>
#include <string>

namespace mebake::output {

enum class ToneCurve { Filmic, Reinhard, Clamp };

struct ToneMap {
    float exposure = 0;  // EV: radiance is scaled by 2^exposure
    ToneCurve curve = ToneCurve::Filmic;
};

// "filmic", "reinhard", "clamp" -> curve; nullopt otherwise.
std::optional<ToneCurve> ParseToneCurve(const std::string& name);

// Display-linear value in [0, 1] of a linear radiance value (NaN and negatives give 0).
float ApplyToneCurve(float radiance, const ToneMap& tm);

// sRGB encoding of a display-linear value in [0, 1], and its 8-bit code.
float EncodeSrgb(float linear);
uint8_t ToSrgb8(float display_linear);

// Radiance (linear RGB) -> 8-bit sRGB.
void ToneMapPixel(const Vec3f& radiance, const ToneMap& tm, uint8_t out[3]);

}  // namespace mebake::output
