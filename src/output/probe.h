// The solved bake at given surface points, and its error against reference values there:
// how `mebake compare` scores a solution against `mebake reference` (docs/accuracy.md).
// Evaluation goes through ChartShader::AtTriangle, the same path as the light maps,
// vertex colours and renders (bake_view.h), so what is scored is what is exported.
#pragma once

#include "core/vec.h"
#include "output/bake_view.h"

#include <cstdint>
#include <span>
#include <vector>

namespace mebake::output {

// A point of a chart's tile: triangle index within the tile and barycentrics.
struct ProbeSite {
    uint32_t chart = 0, local_triangle = 0;
    Vec3f barycentric{};
};

struct ProbeValue {
    Vec3f b{};        // radiosity B
    Vec3f e[3] = {};  // vector irradiance per colour (zero for a radiosity solution)
    Vec2f uv{};
    Vec3f normal{};       // the shading normal the display uses
    Vec3f face_normal{};  // the tile triangle's own (geometric) normal, unit
    Vec3f albedo{};
    Vec3f emission{};  // emitted radiance Le
};

// Reads only the tiles that hold sites. Throws Error(Input) naming the site when a chart or
// triangle does not exist or the barycentrics are not finite.
std::vector<ProbeValue> ProbeSolution(const BakeView& view, std::span<const ProbeSite> sites);

// The light map's display rule (solve/shading.h: B = pi Le + rho (n . E)+ with the point's
// shading normal, albedo and emission) applied to another vector irradiance e at the point:
// with the reference's own E, what a bake whose field were exact would show there.
Vec3d DisplayRule(const ProbeValue& v, const Vec3d e[3]);

// Error of baked B against reference B over a set of points (all colours):
//   relative RMS  = sqrt(mean |B_bake - B_ref|^2) / sqrt(mean |B_ref|^2),
//   relative max  = max |B_bake - B_ref| / sqrt(mean |B_ref|^2),
//   noise RMS     = sqrt(mean |se_ref|^2) / sqrt(mean |B_ref|^2): the reference's own error,
//   corrected RMS = sqrt(max(0, rms^2 - noise^2)): the expected bake error with the
//                   reference noise (independent of the bake's) removed.
// Also the median of the per-point relative error |dB| / max(|B_ref|, 1e-3 RMS).
struct ProbeError {
    uint64_t points = 0;
    double relative_rms = 0, relative_max = 0, noise_rms = 0, corrected_rms = 0;
    double median_relative = 0;
    double mean_bake = 0, mean_reference = 0;  // mean |B|, to see a bias at a glance
};
ProbeError CompareRadiosity(std::span<const Vec3d> reference, std::span<const Vec3d> reference_se,
                            std::span<const Vec3d> bake);

}  // namespace mebake::output
