// A tiny solved bake directory built by hand for the export tests: two unit squares side by
// side in the plane z = 0 (normal +z), one chart each, sharing the edge x = 1, plus one
// input vertex no chart uses. Each chart's field is E = (0, 0, a_c + b_c u) per colour c, so
// with the scene's albedo rho = 0.5 the light map is B_c(u, v) = rho (a_c + b_c u) exactly.
//
//   global vertices: id = row * 3 + col at (col, row, 0) for col 0..2, row 0..1; id 6 unused
//   chart 0: x in [0, 1], ids 0 1 3 4;  chart 1: x in [1, 2], ids 1 2 4 5;  uv = (x - x0, y)
#pragma once

#include "core/error.h"
#include "core/paged_file.h"
#include "io/mesh_stream.h"
#include "solve/basis.h"
#include "solve/field.h"
#include "solve/solution.h"
#include "stream/bake_dir.h"
#include "stream/spill.h"
#include "stream/tile.h"
#include "stream/trimesh.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <unistd.h>
#include <vector>

namespace mebake::solve::testing {

constexpr float kAlbedo = 0.5f;

struct ChartLight {
    Vec3f a{2, 4, 6};  // E_z at u = 0, per colour
    Vec3f b{0, 0, 0};  // slope of E_z along u
};

struct TinyBakeOptions {
    uint32_t resolution = 8;
    int order = 1;
    ChartLight light[2];
    bool hole_fill_last = false;  // chart 1's second triangle is a hole fill (face id kNoId)
    int subdivide = 0;            // levels of uniform subdivision of each field (continuous)
    float leaf_step = 0;          // then added to E_z of chart 0's first leaf (a jump)
};

inline std::string FreshDir(const std::string& name) {
    auto p = std::filesystem::temp_directory_path() /
             ("mebake-" + name + "-" + std::to_string(::getpid()));
    std::filesystem::remove_all(p);
    std::filesystem::create_directories(p);
    return p.string();
}

inline Vec3f GlobalVertex(uint64_t id) {
    if (id == 6)
        return Vec3f(5, 5, 5);
    return Vec3f(float(id % 3), float(id / 3), 0);
}

// The expected radiosity of chart c at u.
inline Vec3f ExpectedB(const TinyBakeOptions& o, int c, double u) {
    Vec3f b;
    for (int k = 0; k < 3; ++k)
        b[k] = kAlbedo * float(o.light[c].a[k] + o.light[c].b[k] * u);
    return b;
}

inline void WriteTinyBake(const std::string& dir, const TinyBakeOptions& o) {
    namespace fs = std::filesystem;
    fs::create_directories(dir + "/tiles");
    fs::create_directories(dir + "/solve");
    stream::Manifest m;
    m.state = "ingested";
    stream::InputRecord in;
    in.path = "tiny.ply";
    in.vertices = 7;
    in.triangles = 4;
    m.inputs.push_back(in);
    m.texel_size = 1.0 / o.resolution;
    m.vertex_count = 7;
    m.face_count = 4;
    m.bbox_min = Vec3d(0, 0, 0);
    m.bbox_max = Vec3d(2, 1, 0);
    m.surface_area = 2;
    m.brick_count = 1;
    std::vector<ChartField> fields;
    for (uint32_t c = 0; c < 2; ++c) {
        const uint64_t x0 = c;
        stream::ChartTile t;
        const uint64_t ids[4] = {x0, x0 + 1, x0 + 3, x0 + 4};
        for (uint64_t id : ids) {
            const Vec3f p = GlobalVertex(id);
            t.position.push_back(p);
            t.normal.push_back(Vec3f(0, 0, 1));
            t.uv.push_back(Vec2f(p.x - float(x0), p.y));
            t.vertex_id.push_back(id);
        }
        t.triangles = {{0, 1, 3}, {0, 3, 2}};
        t.face_id = {2 * c, 2 * c + 1};
        if (c == 1 && o.hole_fill_last)
            t.face_id[1] = stream::kNoId;
        t.material = {0, 0};
        const int g = stream::DefaultGridResolution(t.triangles.size());
        t.grid = stream::BuildChartGrid(t.uv, t.triangles, g);
        const uint32_t r = o.resolution;
        t.geometry.resolution = r;
        int levels = 0;
        while ((1u << levels) < r)
            ++levels;
        t.geometry.levels.resize(size_t(levels) + 1);
        auto& fine = t.geometry.levels.back();
        fine.resize(size_t(r) * r);
        for (uint32_t j = 0; j < r; ++j)
            for (uint32_t i = 0; i < r; ++i) {
                auto& tx = fine[size_t(j) * r + i];
                tx.position = Vec3f(float(x0) + (i + 0.5f) / r, (j + 0.5f) / r, 0);
                tx.normal = Vec3f(0, 0, 1);
                tx.vis_point = tx.position;
                tx.color = Vec3f(-1, -1, -1);
                tx.area = 1.f / float(r * r);
                tx.coverage = 1;
                tx.radius = 1.f / float(r);
                tx.material = 0;
            }
        t.geometry.BuildPyramid();
        t.meta.chart = c;
        t.meta.vertex_count = 4;
        t.meta.triangle_count = 2;
        t.meta.resolution = r;
        t.meta.grid_resolution = uint32_t(g);
        t.meta.scale = 1;
        t.meta.area = 1;
        t.meta.bbox_min = Vec3f(float(x0), 0, 0);
        t.meta.bbox_max = Vec3f(float(x0) + 1, 1, 0);
        stream::WriteTile(stream::TilePath(dir, c), t);
        stream::ChartRecord rec;
        rec.triangles = 2;
        rec.vertices = 4;
        rec.resolution = r;
        rec.scale = 1;
        rec.area = 1;
        rec.bbox_min = t.meta.bbox_min;
        rec.bbox_max = t.meta.bbox_max;
        m.charts.push_back(rec);

        ChartField f(o.order, 9);
        const int n = NumCoeffs(o.order);
        for (int k = 0; k < 3; ++k) {
            float* z = f.value(0) + (3 * k + 2) * n;
            // a + b s = (a + b/2) P~0 + b / (2 sqrt 3) P~1(s).
            z[0] = o.light[c].a[k] + o.light[c].b[k] / 2;
            if (o.order >= 1)
                z[CoeffIndex(o.order, 1, 0)] = o.light[c].b[k] / (2 * std::sqrt(3.f));
        }
        for (int l = 0; l < o.subdivide; ++l) {
            const size_t nodes = f.node_count();
            for (size_t k = 0; k < nodes; ++k)
                if (f.node(k).leaf())
                    f.Subdivide(k);
        }
        if (c == 0 && o.leaf_step != 0) {
            size_t first = 0;
            while (!f.node(first).leaf())
                first = size_t(f.node(first).first_child);
            for (int k = 0; k < 3; ++k)
                f.value(first)[(3 * k + 2) * n] += o.leaf_step;
        }
        fields.push_back(std::move(f));
    }
    stream::WriteManifest(dir, m);
    {
        DiskArray<Vec3f> v(stream::Spill::VerticesPath(dir), true, 1 << 16);
        for (uint64_t id = 0; id < 7; ++id)
            v.Push(GlobalVertex(id));
        v.Flush();
    }
    WriteSolution(SolutionPath(dir), fields, false);
    std::ofstream(dir + "/solve/scene.json")
        << R"({"materials": [{"albedo": 0.5, "use_vertex_colors": false}],
              "sky": {"type": "uniform", "radiance": [0.1, 0.2, 0.3]}})";
}

// A sink that keeps what a reader delivers (vertices and triangles).
struct MeshCollector : io::MeshSink {
    io::MeshHeader header;
    std::vector<Vec3f> position, normal, color;
    std::vector<Vec2f> uv;
    std::vector<uint64_t> index;
    std::vector<uint32_t> face_size;
    void Begin(const io::MeshHeader& h) override { header = h; }
    void Vertices(const io::VertexBatch& b) override {
        position.insert(position.end(), b.position.begin(), b.position.end());
        normal.insert(normal.end(), b.normal.begin(), b.normal.end());
        color.insert(color.end(), b.color.begin(), b.color.end());
        uv.insert(uv.end(), b.uv.begin(), b.uv.end());
    }
    void Faces(const io::FaceBatch& b) override {
        face_size.insert(face_size.end(), b.size.begin(), b.size.end());
        index.insert(index.end(), b.index.begin(), b.index.end());
    }
    void End(const io::MeshSummary&) override {}
};

}  // namespace mebake::solve::testing
