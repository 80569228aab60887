// Sky light: vector irradiance of a uniform and of the CIE standard overcast sky
// (Moon & Spencer 1942, CIE S 011/E:2003 type 1: L(theta) = Lz (1 + 2 cos theta) / 3) in
// closed form, the references the tests hold the solver and the path tracer to; and the
// solver's stratified sky directions.
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

// Integral of w dw over the directions above every plane (unit normals; zero ones are
// skipped): a region bounded by great-circle arcs, whose integral is half the sum over its
// arcs of the arc's angle times its plane's normal (Stokes; Arvo 1995, the polygon light's
// formula). With the sky's up and a receiver's planes, a uniform sky's vector irradiance
// over what is above them, in closed form (DirectLight's control variate).
Vec3d HalfSpacesVector(std::span<const Vec3d> planes);

// The directions the solver traces the sky along (DirectLight), about +z (the caller
// turns them to the sky's up axis): uniform over the upper hemisphere (each stands for
// 2 pi / n of solid angle), stratified in z (k rings of equal area, at their midpoints) and
// in azimuth (k per ring, each ring turned by the golden angle); k = round(sqrt(requested)),
// at least 2. Not cosine-weighted about up: n . E for a tilted n weighs near-horizon
// directions by tan(zenith) against that density, and an 11 x 11 cosine grid missed 24 % of
// a vertical face's sky. At the default 128 directions the irradiance n . E of an open
// receiver is exact facing up under a uniform sky (the rings' mean height is 1/2), within
// 0.2 % under an overcast one, 0.6 % for tilts up to 120 degrees, 1.5 % to 165 and 3 % at
// 170, where only a sliver of sky is above the horizon (sky_test.cpp).
std::vector<Vec3f> SkyDirections(int requested);

}  // namespace mebake::solve
