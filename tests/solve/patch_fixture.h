// Test helper: a parametric surface patch f(u, v), (u, v) in [0,1]^2, as a solver chart
// (its geometry image at res x res texels, exact positions and normals at texel centres)
// and as the triangles of its (res+1)^2 corner grid for visibility.
#pragma once

#include "solve/solver.h"

#include <functional>
#include <vector>

namespace mebake::solve::testing {

using Surface = std::function<Vec3d(double, double)>;

struct Patch {
    SolveChart chart;
    std::vector<float> xyz;
    std::vector<uint32_t> tris;
};

inline Patch MakePatch(const Surface& f, int res, uint32_t material, double scale) {
    Patch p;
    stream::GeometryImage img;
    img.resolution = uint32_t(res);
    int levels = 0;
    while ((1 << levels) < res)
        ++levels;
    img.levels.resize(size_t(levels) + 1);
    auto& fine = img.levels.back();
    fine.resize(size_t(res) * res);
    const double h = 1.0 / res, e = 1e-5;
    for (int j = 0; j < res; ++j) {
        for (int i = 0; i < res; ++i) {
            double u = (i + 0.5) * h, v = (j + 0.5) * h;
            Vec3d pu = (f(u + e, v) - f(u - e, v)) / (2 * e);
            Vec3d pv = (f(u, v + e) - f(u, v - e)) / (2 * e);
            Vec3d n = Cross(pu, pv);
            stream::GeometryTexel& t = fine[size_t(j) * res + i];
            t.position = Vec3f(f(u, v));
            t.normal = Vec3f(Normalize(n));
            t.vis_point = t.position;
            t.color = Vec3f(-1, -1, -1);
            t.area = float(Length(n) * h * h);
            t.coverage = 1;
            t.radius = float(0.75 * h * (Length(pu) + Length(pv)));
            t.material = material;
        }
    }
    img.BuildPyramid();
    p.chart.geometry = GeometryPyramid(std::move(img));
    p.chart.scale = scale;
    for (int j = 0; j <= res; ++j)
        for (int i = 0; i <= res; ++i) {
            Vec3d q = f(i * h, j * h);
            p.xyz.insert(p.xyz.end(), {float(q.x), float(q.y), float(q.z)});
        }
    for (int j = 0; j < res; ++j)
        for (int i = 0; i < res; ++i) {
            uint32_t a = uint32_t(j * (res + 1) + i), b = a + 1, c = a + uint32_t(res) + 1,
                     d = c + 1;
            p.tris.insert(p.tris.end(), {a, b, d, a, d, c});
        }
    return p;
}

}  // namespace mebake::solve::testing
