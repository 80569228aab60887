#include "output/bake_view.h"

#include "core/check.h"
#include "core/error.h"
#include "output/seam_graph.h"
#include "solve/shading.h"

#include <algorithm>
#include <cmath>
#include <filesystem>

namespace mebake::output {

BakeView OpenBakeView(const std::string& dir, FieldLoading fields, SeamStitching stitching,
                      size_t stitch_cache_bytes) {
    BakeView v;
    v.dir = dir;
    v.manifest = stream::ReadManifest(dir);
    if (v.manifest.state != "ingested")
        UsageError("{}: ingest did not finish (state '{}'); run `mebake ingest` again", dir,
                   v.manifest.state);
    const std::string sol = solve::SolutionPath(dir);
    if (!std::filesystem::exists(sol))
        UsageError("{}: not solved yet; run `mebake solve {}` first", dir, dir);
    size_t charts = 0;
    int blocks = 0;
    if (fields == FieldLoading::All) {
        v.solution = solve::ReadSolution(sol);
        charts = v.solution.fields.size();
        for (const auto& f : v.solution.fields)
            if (f.blocks() != (v.solution.radiosity ? 3 : 9))
                blocks = f.blocks();
    } else {
        v.solution_reader = std::make_shared<const SolutionReader>(sol);
        v.solution.radiosity = v.solution_reader->radiosity();
        charts = v.solution_reader->chart_count();
        if (v.solution_reader->blocks() != (v.solution.radiosity ? 3 : 9))
            blocks = v.solution_reader->blocks();
    }
    if (charts != v.manifest.charts.size())
        CorruptError({sol}, "{} charts solved but the manifest lists {}", charts,
                     v.manifest.charts.size());
    if (blocks != 0)
        CorruptError({sol}, "{} blocks per node for a {} solution", blocks,
                     v.solution.radiosity ? "radiosity" : "vector irradiance");
    const std::string kept = dir + "/solve/scene.json";
    v.scene = solve::LoadScene(v.manifest, std::filesystem::exists(kept) ? kept : "");
    if (stitching == SeamStitching::On)
        v.stitcher = std::make_shared<const SeamStitcher>(v, stitch_cache_bytes);
    return v;
}

std::shared_ptr<const ChartField> BakeView::Field(uint32_t c) const {
    if (solution_reader)
        return std::make_shared<const ChartField>(solution_reader->Read(c));
    CHECK_LT(c, solution.fields.size());
    // Not owning: the view holds the field.
    return std::shared_ptr<const ChartField>(std::shared_ptr<const ChartField>(),
                                             &solution.fields[c]);
}

std::shared_ptr<const ChartSeams> BakeView::Seams(uint32_t c) const {
    if (!stitcher)
        return nullptr;
    return stitcher->Chart(*this, c);
}

std::vector<uint32_t> ChartResolutions(const BakeView& view) {
    std::vector<uint32_t> res;
    res.reserve(view.manifest.charts.size());
    for (size_t c = 0; c < view.manifest.charts.size(); ++c) {
        const uint32_t r = view.manifest.charts[c].resolution;
        if (r == 0 || r > 65536 || (r & (r - 1)) != 0)
            CorruptError({stream::ManifestPath(view.dir)},
                         "chart {} has resolution {}; expected a power of two up to 65536", c, r);
        res.push_back(r);
    }
    return res;
}

std::vector<uint32_t> AllCharts(const BakeView& view) {
    std::vector<uint32_t> all(view.chart_count());
    for (size_t c = 0; c < all.size(); ++c)
        all[c] = uint32_t(c);
    return all;
}

ChartShader::ChartShader(const stream::ChartTile& tile, const ChartField& field,
                         bool radiosity_unknown, const Scene& scene, const std::string& tile_path,
                         std::shared_ptr<const ChartSeams> seams)
    : tile_(tile),
      field_(field),
      display_(field, 1.0 / double(std::max<uint32_t>(1, tile.meta.resolution))),
      seams_(seams && !seams->empty() ? std::move(seams) : nullptr),
      radiosity_(radiosity_unknown),
      scene_(scene) {
    default_material_.use_vertex_colors = true;
    for (size_t t = 0; t < tile.material.size(); ++t) {
        const uint32_t packed = tile.material[t];
        const uint32_t input = packed >> 16, local = packed & 0xFFFF;
        if (input >= scene.per_input.size() || local >= scene.per_input[input].size())
            CorruptError({tile_path},
                         "triangle {} has material {}:{} which the scene does not have", t, input,
                         local);
    }
    CHECK_EQ(tile.material.size(), tile.triangles.size());
    if (seams_ && !seams_->normals().empty()) {
        normal_ = tile.normal;
        for (const auto& [v, n] : seams_->normals()) {
            CHECK_LT(v, normal_.size());
            normal_[v] = n;
        }
    }
    vertex_triangle_.assign(tile.position.size(), stream::kNoTriangle);
    for (size_t t = tile.triangles.size(); t-- > 0;)
        for (uint32_t v : tile.triangles[t])
            vertex_triangle_[v] = uint32_t(t);
}

Vec3f ChartShader::Color(uint32_t v) const {
    return tile_.color.empty() ? Vec3f(-1, -1, -1) : tile_.color[v];
}

ShadingPoint ChartShader::AtTriangle(uint32_t t, float b0, float b1, float b2) const {
    const auto& f = tile_.triangles[t];
    const float b[3] = {b0, b1, b2};
    ShadingPoint p;
    Vec3d n{}, c{};
    Vec2f uv{};
    bool colored = !tile_.color.empty();
    Vec3d shared{};
    for (int k = 0; k < 3; ++k) {
        uv += tile_.uv[f[k]] * b[k];
        n += Vec3d(tile_.normal[f[k]]) * double(b[k]);
        shared += Vec3d(Normals()[f[k]]) * double(b[k]);
        const Vec3f ck = Color(f[k]);
        if (ck.x < 0)
            colored = false;
        c += Vec3d(ck) * double(b[k]);
    }
    // The stitched normals of border vertices hold on the border and fade out with the
    // stitch's band: spread over whole triangles they turned lucy's shading from the
    // mesh's (bench/RESULTS.md, "Issue 14 (session 9)").
    // Where the stitch left the three normals alone (shared == n), the fade multiplies
    // zeros (+-0, whatever fade in [0, 1] is): it is not looked up.
    if (!normal_.empty()) {
        const bool same = shared.x == n.x && shared.y == n.y && shared.z == n.z;
        n += (shared - n) * (same ? 0.0 : seams_->Fade(uv.x, uv.y));
    }
    n = Normalize(n);
    // A shading normal on the wrong side of its triangle (vertex normals averaged over a
    // fold that turns back on itself), or none, falls back to the triangle's plane, as the
    // reference path tracer has it (reference.cpp, SurfaceAt): with the reversed normal
    // (n . E)+ is 0 and the pixel showed black (lucy's away picture, bench/RESULTS.md
    // "Issue 14 (session 15)").
    const Vec3d p0(tile_.position[f[0]]), p1(tile_.position[f[1]]), p2(tile_.position[f[2]]);
    const Vec3d face = Cross(p1 - p0, p2 - p0);  // normalized only when it is taken
    if (!(Dot(n, face) > 0) && Dot(face, face) > 0)
        n = Normalize(face);
    if (!(Dot(n, n) > 0))
        n = Vec3d(0, 0, 1);
    p.uv = uv;
    p.normal = Vec3f(n);
    p.material = &scene_.MaterialOf(tile_.material[t]);
    const Vec3f color = colored ? Vec3f(c) : Vec3f(-1, -1, -1);
    p.albedo = solve::SurfaceAlbedo(*p.material, color);
    return p;
}

ShadingPoint ChartShader::AtLocation(Vec2f u, const stream::GridLocation& loc) const {
    if (loc.triangle == stream::kNoTriangle) {  // a chart without triangles
        ShadingPoint p;
        p.uv = u;
        p.normal = Vec3f(0, 0, 1);
        p.material = &default_material_;
        p.albedo = solve::SurfaceAlbedo(default_material_, Vec3f(-1, -1, -1));
        return p;
    }
    ShadingPoint p =
        AtTriangle(loc.triangle, loc.barycentric[0], loc.barycentric[1], loc.barycentric[2]);
    p.uv = u;
    return p;
}

ShadingPoint ChartShader::AtUv(Vec2f u) const {
    u = Vec2f(std::clamp(u.x, 0.f, 1.f), std::clamp(u.y, 0.f, 1.f));
    return AtLocation(u, tile_.grid.Locate(u));
}

std::optional<ShadingPoint> ChartShader::AtUvInside(Vec2f u) const {
    u = Vec2f(std::clamp(u.x, 0.f, 1.f), std::clamp(u.y, 0.f, 1.f));
    const stream::GridLocation loc = tile_.grid.LocateReal(u);
    if (loc.triangle == stream::kNoTriangle || !loc.real)
        return std::nullopt;
    return AtLocation(u, loc);
}

ShadingPoint ChartShader::AtVertex(uint32_t v) const {
    ShadingPoint p;
    p.uv = tile_.uv[v];
    Vec3f n = Normalize(Normals()[v]);
    p.normal = Dot(n, n) > 0 ? n : Vec3f(0, 0, 1);
    const uint32_t t = vertex_triangle_[v];
    p.material =
        t == stream::kNoTriangle ? &default_material_ : &scene_.MaterialOf(tile_.material[t]);
    p.albedo = solve::SurfaceAlbedo(*p.material, Color(v));
    return p;
}

void ChartShader::FieldAt(Vec2f uv, float* val) const {
    display_.Eval(uv.x, uv.y, val);
    if (seams_)
        seams_->Apply(display_, uv.x, uv.y, val);
}

Vec3f ChartShader::Radiosity(const ShadingPoint& p) const {
    float val[9];
    FieldAt(p.uv, val);
    Vec3f b = solve::ShadeRadiosity(val, radiosity_, p.normal, p.albedo, *p.material);
    for (int c = 0; c < 3; ++c) {
        CHECK(std::isfinite(b[c]));
        b[c] = std::max(0.f, b[c]);
    }
    return b;
}

Vec3f ChartShader::Glossy(const ShadingPoint& p, const Vec3f& view) const {
    float val[9];
    FieldAt(p.uv, val);
    Vec3f l = solve::ShadeGlossy(val, radiosity_, p.normal, view, p.albedo, *p.material);
    for (int c = 0; c < 3; ++c) {
        CHECK(std::isfinite(l[c]));
        l[c] = std::max(0.f, l[c]);
    }
    return l;
}

void ChartShader::Irradiance(Vec2f uv, Vec3f e[3]) const {
    float val[9];
    FieldAt(uv, val);
    solve::VectorIrradianceAt(val, radiosity_, e);
    for (int c = 0; c < 3; ++c)
        CHECK(std::isfinite(e[c].x + e[c].y + e[c].z));
}

}  // namespace mebake::output
