// The sampled geometry pyramid of a chart: its unit square as images of the surface.
//
// The finest level has `resolution` x `resolution` texels (a power of two set by the
// texel size); texel (i, j) covers [i/R, (i+1)/R] x [j/R, (j+1)/R] of the square. Each
// coarser level halves the resolution by area-weighted averaging, down to 1 x 1. The
// solver evaluates receivers, emitters and bounds from these images instead of the
// triangles, which is what makes its cost follow the lighting, not the polygon count.
#pragma once

#include "core/vec.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace mebake::stream {

struct GeometryTexel {
    Vec3f position;     // surface point at the texel centre (extrapolated if virtual)
    Vec3f normal;       // unit normal there
    Vec3f vis_point;    // nearest real surface point: where visibility is evaluated
    Vec3f color;        // vertex colour (linear RGB), or (-1, -1, -1) when none
    float area;         // real 3D surface area inside the texel
    float coverage;     // real fraction of the texel's square, 0..1
    float radius;       // bound on |p - position| for real points p in the texel
    uint32_t material;  // packed scene material id (input << 16 | local)
};
static_assert(sizeof(GeometryTexel) == 64);

// Cells of a world size for chart merging's turn bound (chart_merge.h,
// merge_horizon_cells): a chart of 2^T light-map texels a side (every chart has the same
// texel size) is measured on level HorizonLevel(T) of its geometry pyramid, cells of
// 2^kHorizonCellLevels texels, never coarser than 8 x 8. The solver's horizon
// (Solver::HorizonNormal) is the finest level, which no cell of this size is coarser than.
inline constexpr int kHorizonCellLevels = 3;
inline int HorizonLevel(int texel_level) {
    return std::max(3, texel_level - kHorizonCellLevels);
}

// The light-map resolution of a chart whose unit square is `scale` long in 3D: the power of
// two (within [min_resolution, max_resolution]) that gives texels at most sqrt(2) x
// texel_size.
inline uint32_t ChartResolution(double scale, double texel_size, uint32_t min_resolution,
                                uint32_t max_resolution) {
    const double want = scale / texel_size;
    uint32_t r = min_resolution;
    while (r < max_resolution && double(r) * std::sqrt(2.0) < want)
        r *= 2;
    return r;
}

inline int LevelOf(uint32_t resolution) {
    int level = 0;
    while ((1u << level) < resolution)
        ++level;
    return level;
}

struct GeometryImage {
    uint32_t resolution = 0;  // finest level, power of two
    // levels[l] has (2^l)^2 texels, row-major (index = j * 2^l + i); levels.back() is finest.
    std::vector<std::vector<GeometryTexel>> levels;

    int finest_level() const { return int(levels.size()) - 1; }
    const GeometryTexel& At(int level, uint32_t i, uint32_t j) const {
        return levels[size_t(level)][size_t(j) * (size_t(1) << level) + i];
    }
    // Rebuilds levels[0 .. finest-1] from the finest level by area-weighted averaging.
    void BuildPyramid();
};

// A surface sample interpolated bilinearly from one level at chart coordinates (u, v).
struct SurfaceSample {
    Vec3f position, normal, vis_point, color;
    uint32_t material;
    float coverage;
};
SurfaceSample SampleBilinear(const GeometryImage& img, int level, float u, float v);

// The same on any pyramid with At(level, i, j) and finest_level() (the solver's memory-
// mapped view, solve/geometry_cache.h): one definition, so both give the same bits.
template <typename Pyramid>
SurfaceSample SampleBilinearOf(const Pyramid& img, int level, float u, float v) {
    // Texel centres are the samples; outside the outermost centres the image is
    // extrapolated linearly (clamping would move border points by half a texel).
    level = std::min(std::max(level, 1), img.finest_level());
    const int nn = 1 << level;
    const float x = u * float(nn) - 0.5f, y = v * float(nn) - 0.5f;
    const int i0 = nn > 1 ? std::clamp(int(std::floor(x)), 0, nn - 2) : 0;
    const int j0 = nn > 1 ? std::clamp(int(std::floor(y)), 0, nn - 2) : 0;
    const int i1 = std::min(i0 + 1, nn - 1), j1 = std::min(j0 + 1, nn - 1);
    const float fx = nn > 1 ? x - float(i0) : 0.f, fy = nn > 1 ? y - float(j0) : 0.f;
    const GeometryTexel* t[4] = {
        &img.At(level, uint32_t(i0), uint32_t(j0)), &img.At(level, uint32_t(i1), uint32_t(j0)),
        &img.At(level, uint32_t(i0), uint32_t(j1)), &img.At(level, uint32_t(i1), uint32_t(j1))};
    const float w[4] = {(1 - fx) * (1 - fy), fx * (1 - fy), (1 - fx) * fy, fx * fy};
    SurfaceSample s{};
    Vec3f nrm{};
    float col_w = 0;
    int best = 0;
    // The nearest texel decides discrete attributes and the visibility point.
    const float dx = std::clamp(x, 0.f, float(nn - 1)) - float(i0);
    const float dy = std::clamp(y, 0.f, float(nn - 1)) - float(j0);
    best = (dx >= 0.5f ? 1 : 0) + (dy >= 0.5f ? 2 : 0);
    for (int k = 0; k < 4; ++k) {
        s.position += t[k]->position * w[k];
        nrm += t[k]->normal * w[k];
        s.coverage += t[k]->coverage * w[k];
        if (t[k]->color.x >= 0) {
            s.color += t[k]->color * w[k];
            col_w += w[k];
        }
    }
    s.coverage = std::clamp(s.coverage, 0.f, 1.f);
    s.normal = Length(nrm) > 0 ? Normalize(nrm) : t[best]->normal;
    s.color = col_w > 0 ? Vec3f(std::clamp(s.color.x / col_w, 0.f, 1.f),
                                std::clamp(s.color.y / col_w, 0.f, 1.f),
                                std::clamp(s.color.z / col_w, 0.f, 1.f))
                        : Vec3f(-1, -1, -1);
    s.material = t[best]->material;
    // Visibility is taken at the sample itself where the surface is real, else at the
    // nearest texel's real point (the seed's x' rule).
    s.vis_point = t[best]->coverage >= 0.999f ? s.position : t[best]->vis_point;
    return s;
}

}  // namespace mebake::stream
