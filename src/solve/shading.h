// Turning the solved field into what people see: albedo from materials and vertex
// colours, radiosity B = pi Le + rho (n . E)+ at full geometric detail (n from the mesh),
// and the seed's view-dependent glossy approximation L ~ Le + |E| fr(x, x + E, z).
// Shared by the solver, export and render, so all three agree to the bit.
#pragma once

#include <cstdint>

#include "core/vec.h"
#include "solve/field.h"
#include "solve/scene.h"

namespace mebake::solve {

// Linear albedo of a surface point: the material's, or its vertex colour (sRGB-encoded
// [0,1], x < 0 = none) decoded and scaled when the material uses vertex colours.
Vec3f SurfaceAlbedo(const Material& m, const Vec3f& color);

// Radiosity at chart point (u, v) with unit normal n (W/m^2 per channel).
Vec3f ShadeRadiosity(const ChartField& field, bool radiosity_unknown, double u, double v,
                     const Vec3f& n, const Vec3f& albedo, const Material& m);

// The vector irradiance E (colour c, x y z) at (u, v); zero for a radiosity solution.
void VectorIrradianceAt(const ChartField& field, bool radiosity_unknown, double u, double v,
                        Vec3f e[3]);

// Outgoing radiance towards `view` (unit, from the surface to the eye) with the glossy
// approximation: the diffuse part B/pi plus |E| times a normalized Phong lobe around the
// mirror direction of E's direction (seed 000, "Display").
Vec3f ShadeGlossy(const ChartField& field, bool radiosity_unknown, double u, double v,
                  const Vec3f& n, const Vec3f& view, const Vec3f& albedo, const Material& m);

}  // namespace mebake::solve
