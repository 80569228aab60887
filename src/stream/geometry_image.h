// The sampled geometry pyramid of a chart: its unit square as images of the surface.
//
// The finest level has `resolution` x `resolution` texels (a power of two set by the
// texel size); texel (i, j) covers [i/R, (i+1)/R] x [j/R, (j+1)/R] of the square. Each
// coarser level halves the resolution by area-weighted averaging, down to 1 x 1. The
// solver evaluates receivers, emitters and bounds from these images instead of the
// triangles, which is what makes its cost follow the lighting, not the polygon count.
#pragma once

#include <cstdint>
#include <vector>

#include "core/vec.h"

namespace mebake::stream {

struct GeometryTexel {
    Vec3f position;    // surface point at the texel centre (extrapolated if virtual)
    Vec3f normal;      // unit normal there
    Vec3f vis_point;   // nearest real surface point: where visibility is evaluated
    Vec3f color;       // vertex colour (linear RGB), or (-1, -1, -1) when none
    float area;        // real 3D surface area inside the texel
    float coverage;    // real fraction of the texel's square, 0..1
    float radius;      // bound on |p - position| for real points p in the texel
    uint32_t material; // packed scene material id (input << 16 | local)
};
static_assert(sizeof(GeometryTexel) == 64);

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

}  // namespace mebake::stream
