// Turning the solved field into what people see: albedo from materials and vertex
// colours, radiosity B = pi Le + rho (n . E)+ at full geometric detail (n from the mesh),
// and the seed's view-dependent glossy approximation L ~ Le + |E| fr(x, x + E, z).
// Shared by export, render and the probe of `mebake compare`, so all agree to the bit.
#pragma once

#include <cstdint>

#include "core/vec.h"
#include "solve/field.h"
#include "solve/scene.h"

namespace mebake::solve {

// Linear albedo of a surface point: the material's, or its vertex colour (sRGB-encoded
// [0,1], x < 0 = none) decoded and scaled when the material uses vertex colours.
Vec3f SurfaceAlbedo(const Material& m, const Vec3f& color);

// `val` is the field's value at the point (ChartField::EvalValue, or the continuous
// reconstruction of output/continuous_field.h): E per colour (9 floats) or, for a
// radiosity solution, B (3 floats).

// Radiosity at a point with unit normal n (W/m^2 per channel).
Vec3f ShadeRadiosity(const float* val, bool radiosity_unknown, const Vec3f& n,
                     const Vec3f& albedo, const Material& m);

// The vector irradiance E (colour c, x y z); zero for a radiosity solution.
void VectorIrradianceAt(const float* val, bool radiosity_unknown, Vec3f e[3]);

// Outgoing radiance towards `view` (unit, from the surface to the eye) with the glossy
// approximation: the diffuse part B/pi plus |E| times a normalized Phong lobe around the
// mirror direction of E's direction (seed 000, "Display").
Vec3f ShadeGlossy(const float* val, bool radiosity_unknown, const Vec3f& n, const Vec3f& view,
                  const Vec3f& albedo, const Material& m);

}  // namespace mebake::solve
