// Test helper: a parametric surface patch f(u, v), (u, v) in [0,1]^2, as a solver chart
// (its geometry image at res x res texels, exact positions and normals at texel centres)
// and as the triangles of its (res+1)^2 corner grid for visibility.
#pragma once

#include "solve/checkpoint.h"
#include "solve/polygon_light.h"
#include "solve/scene.h"
#include "solve/solver.h"
#include "solve/visibility.h"

#include <cstring>
#include <filesystem>
#include <functional>
#include <string>
#include <unistd.h>
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

// An open box seen from inside (the first `faces` of: floor, back wall, left wall, right
// wall, ceiling of the unit cube; 1..5) lit by a small square light below its ceiling,
// charts `res` texels wide: several bounces of coloured interreflection. With `block`, a
// sixth chart, a square table top over the floor's middle, casts shadows and hides parts
// of the floor from the ceiling and walls (partly visible links).
struct LitBox {
    Scene scene;
    std::vector<SolveChart> charts;
    VisibilityScene vis;

    LitBox(int faces, int res, bool block = false) {
        Material m;
        m.albedo = Vec3f(0.7f, 0.6f, 0.5f);
        m.use_vertex_colors = false;
        scene.per_input = {{m}};
        PolygonLight light;
        light.vertices = {{0.4, 0.95, 0.4}, {0.6, 0.95, 0.4}, {0.6, 0.95, 0.6}, {0.4, 0.95, 0.6}};
        light.radiance = {5, 4, 3};
        scene.lights.push_back(light);
        const Surface all[] = {
            [](double u, double v) { return Vec3d(u, 0, 1 - v); },  // floor, normal +y
            [](double u, double v) { return Vec3d(u, v, 0); },      // back wall, +z
            [](double u, double v) { return Vec3d(0, u, v); },      // left wall, +x
            [](double u, double v) { return Vec3d(1, v, u); },      // right wall, -x
            [](double u, double v) { return Vec3d(v, 1, u); },      // ceiling, -y
        };
        for (int k = 0; k < faces && k < 5; ++k) {
            Patch p = MakePatch(all[k], res, 0, 1);
            charts.push_back(std::move(p.chart));
            vis.AddTriangles(p.xyz, p.tris, "box");
        }
        if (block) {
            Patch p = MakePatch(
                [](double u, double v) { return Vec3d(0.3 + 0.4 * u, 0.35, 0.7 - 0.4 * v); }, res,
                0, 1);  // normal +y
            charts.push_back(std::move(p.chart));
            vis.AddTriangles(p.xyz, p.tris, "table");
        }
        vis.Commit();
    }
};

// A fresh, empty directory under the temporary directory, for this process; with
// `solve`, a bake directory's solve/ inside (where checkpoints and pools go).
inline std::string FreshDir(const std::string& name, bool solve = true) {
    namespace fs = std::filesystem;
    fs::path p = fs::temp_directory_path() / ("mebake-" + name + "-" + std::to_string(::getpid()));
    fs::remove_all(p);
    fs::create_directories(solve ? p / "solve" : p);
    return p.string();
}

// Every field's value and unshot coefficients, chart after chart (each pinned to be read).
inline std::vector<float> FieldBits(const Solver& s) {
    std::vector<float> all;
    for (const auto& f : s.fields()) {
        const RegionPin pin = f.Pin();
        all.insert(all.end(), f.values().begin(), f.values().end());
        all.insert(all.end(), f.unshots().begin(), f.unshots().end());
    }
    return all;
}

// Makes `s` write a checkpoint into `dir` and stop at the boundary before batch `stop_at`.
inline void StopWithCheckpointAt(Solver& s, const std::string& dir, uint64_t key, int stop_at) {
    s.SetBatchHook([&s, dir, key, stop_at](int next) {
        if (next < stop_at)
            return true;
        WriteCheckpoint(dir, s, key);
        return false;
    });
}

inline bool SameBits(const std::vector<float>& a, const std::vector<float>& b) {
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

}  // namespace mebake::solve::testing
