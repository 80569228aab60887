// Sky light: vector irradiance of a uniform and of the CIE standard overcast sky
// (Moon & Spencer 1942, CIE S 011/E:2003 type 1: L(theta) = Lz (1 + 2 cos theta) / 3), and a
// deterministic stratified direction set for visibility-weighted sky transfer.
//
// Both skies are linear in cos theta = up.w over the upper hemisphere: L(w) = a + b (up.w),
// zero below the horizon (no ground light). Closed forms (derived in the lune coordinates of
// the two hemispheres; alpha = angle between n and up):
//   E        = integral of L(w) w dw = (pi a + 2 pi b / 3) up
//   I(n)     = integral over {up.w > 0, n.w > 0} of L(w) (n.w) dw
//            = a (pi/2)(1 + cos alpha) + b (2/3)((pi - alpha) cos alpha + sin alpha)
// I(n) is the irradiance of an unoccluded receiver; n.E is not (the sky below the receiver's
// horizon would subtract). Uniform sky: E = pi L up; CIE overcast: E = (7 pi / 9) Lz up.
#pragma once

#include "core/vec.h"

#include <cstdint>
#include <span>
#include <vector>

namespace mebake::solve {

struct SkyModel {
    double a = 0, b = 0;  // L(w) = a + b (up.w) for up.w > 0
    Vec3d up{0, 0, 1};    // unit zenith direction

    static SkyModel Uniform(double radiance, const Vec3d& up);
    static SkyModel CieOvercast(double zenith_radiance, const Vec3d& up);
    double Radiance(const Vec3d& w) const;  // w unit
};

// Unoccluded vector irradiance (the same at every point).
Vec3d SkyVectorIrradiance(const SkyModel& sky);

// Irradiance of an unoccluded receiver with unit normal n (clipped to its hemisphere).
double SkyIrradiance(const SkyModel& sky, const Vec3d& n);

// n directions over the sky's upper hemisphere (Fibonacci spiral: equal solid angle 2 pi / n,
// stratified in up.w), each with weight L(w) * 2 pi / n. Deterministic for a given n.
struct SkySamples {
    std::vector<Vec3f> dir;
    std::vector<float> weight;
};
SkySamples MakeSkySamples(const SkyModel& sky, int n);

// sum_k V_k weight_k dir_k: the sky's vector irradiance at a point whose visibility of
// direction k is V_k (visible empty = all visible). Fixed summation order.
Vec3d SkyTransfer(const SkySamples& samples, std::span<const uint8_t> visible);

// Unoccluded fraction (visible weight / total weight) and the bent normal (unit direction of
// the visible vector irradiance; zero if nothing is visible).
struct SkyVisibility {
    double open_fraction = 0;
    Vec3d bent;
};
SkyVisibility SkyOpenness(const SkySamples& samples, std::span<const uint8_t> visible);

}  // namespace mebake::solve
