// Stitching across chart borders (seam_graph.h, seam_stitch.h, texel_stitch.h) on a plane
// split into a grid of charts with a closed-form field E_z = a + bx x + by y. Each chart's
// fitted field is off by its own offset (as independent fits are), so the charts disagree
// along every border. Asserted: the shown field is one value from both sides of every
// border (shader, vertex copies, render), a viewer's bilinear filtering of the light map
// agrees across every seam, and stitching keeps exact fields exact and moves a perturbed one
// no farther from the closed form than the perturbation.
#include "core/parallel.h"
#include "output/continuous_field.h"
#include "output/lightmap.h"
#include "output/render.h"
#include "output/seam_graph.h"
#include "output/seams.h"
#include "output/texel_stitch.h"
#include "support/bake_fixture.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace mebake::output {
namespace {

using solve::testing::kAlbedo;

struct GridOptions {
    int kx = 3, ky = 2;          // charts along x and y, each a unit square
    int m = 3;                   // quads per chart side (2 triangles each)
    uint32_t resolution = 16;    // texels per chart side
    float inset = 0.125f;        // uv = inset + span (x - cx): a virtual part around the chart
    Vec3f a{2, 4, 6};            // E_z at the origin per colour
    float bx = 0.6f, by = 0.3f;  // gradient of E_z
    std::vector<float> offset;   // per chart, added to its fitted E_z (all colours)
    float tilt = 0;              // odd charts' vertex normals (tilt, 0, 1): per-chart normals
    bool reversed = false;       // odd charts' vertex normals (0, 0, -1): behind their faces
    float bend = 0;              // the tiles right of x = 1 turned up by this angle (radians)
};

float Span(const GridOptions& o) {
    return 1 - 2 * o.inset;
}

// Closed-form B at world (x, y) for colour k.
double ExactB(const GridOptions& o, double x, double y, int k) {
    return kAlbedo * (o.a[k] + o.bx * x + o.by * y);
}

// Writes a solved bake of the grid (order 1 fields, subdivided once: continuous leaves).
void WriteGridBake(const std::string& dir, const GridOptions& o) {
    namespace fs = std::filesystem;
    fs::create_directories(dir + "/tiles");
    fs::create_directories(dir + "/solve");
    const int cols = o.kx * o.m + 1, rows = o.ky * o.m + 1;
    const uint64_t nv = uint64_t(cols) * rows;
    auto lattice = [&](int c, int r) {
        return Vec3f(float(c) / o.m, float(r) / o.m, 0);
    };
    stream::Manifest man;
    man.state = "ingested";
    stream::InputRecord in;
    in.path = "grid.ply";
    in.vertices = nv;
    in.triangles = uint64_t(2 * o.m * o.m * o.kx * o.ky);
    man.inputs.push_back(in);
    man.texel_size = 1.0 / (Span(o) * o.resolution);
    man.vertex_count = nv;
    man.face_count = in.triangles;
    man.bbox_min = Vec3d(0, 0, 0);
    man.bbox_max = Vec3d(o.kx, o.ky, 0);
    man.surface_area = double(o.kx * o.ky);
    man.brick_count = 1;
    std::vector<solve::ChartField> fields;
    const float span = Span(o);
    const uint32_t res = o.resolution;
    for (int cy = 0; cy < o.ky; ++cy)
        for (int cx = 0; cx < o.kx; ++cx) {
            const uint32_t c = uint32_t(cy * o.kx + cx);
            stream::ChartTile t;
            for (int r = 0; r <= o.m; ++r)
                for (int q = 0; q <= o.m; ++q) {
                    const int gc = cx * o.m + q, gr = cy * o.m + r;
                    const Vec3f p = lattice(gc, gr);
                    // A bend of the surface along x = 1 (faces only: the field and the
                    // shading normals stay those of the plane).
                    const float lift = std::max(0.f, p.x - 1) * std::tan(o.bend);
                    t.position.push_back(p + Vec3f(0, 0, lift));
                    t.normal.push_back(o.reversed && c % 2
                                           ? Vec3f(0, 0, -1)
                                           : Normalize(Vec3f(c % 2 ? o.tilt : 0.f, 0, 1)));
                    t.uv.push_back(Vec2f(o.inset + span * (p.x - float(cx)),
                                         o.inset + span * (p.y - float(cy))));
                    t.vertex_id.push_back(uint64_t(gr) * uint64_t(cols) + uint64_t(gc));
                }
            const uint32_t w = uint32_t(o.m + 1);
            for (uint32_t r = 0; r < uint32_t(o.m); ++r)
                for (uint32_t q = 0; q < uint32_t(o.m); ++q) {
                    const uint32_t v00 = r * w + q, v10 = v00 + 1, v01 = v00 + w, v11 = v01 + 1;
                    t.triangles.push_back({v00, v10, v11});
                    t.triangles.push_back({v00, v11, v01});
                }
            for (size_t k = 0; k < t.triangles.size(); ++k) {
                t.face_id.push_back(c * 1000 + k);
                t.material.push_back(0);
            }
            const int g = stream::DefaultGridResolution(t.triangles.size());
            t.grid = stream::BuildChartGrid(t.uv, t.triangles, g);
            t.geometry.resolution = res;
            int levels = 0;
            while ((1u << levels) < res)
                ++levels;
            t.geometry.levels.resize(size_t(levels) + 1);
            auto& fine = t.geometry.levels.back();
            fine.resize(size_t(res) * res);
            for (uint32_t j = 0; j < res; ++j)
                for (uint32_t i = 0; i < res; ++i) {
                    auto& tx = fine[size_t(j) * res + i];
                    tx.position = Vec3f(float(cx) + ((i + 0.5f) / res - o.inset) / span,
                                        float(cy) + ((j + 0.5f) / res - o.inset) / span, 0);
                    tx.normal = Vec3f(0, 0, 1);
                    tx.vis_point = tx.position;
                    tx.color = Vec3f(-1, -1, -1);
                    tx.area = 1.f / float(res * res);
                    tx.coverage = 1;
                    tx.radius = 1.f / float(res);
                    tx.material = 0;
                }
            t.geometry.BuildPyramid();
            t.meta.chart = c;
            t.meta.vertex_count = uint32_t(t.position.size());
            t.meta.triangle_count = uint32_t(t.triangles.size());
            t.meta.resolution = res;
            t.meta.grid_resolution = uint32_t(g);
            t.meta.scale = 1;
            t.meta.area = 1;
            t.meta.bbox_min = Vec3f(float(cx), float(cy), 0);
            t.meta.bbox_max = Vec3f(float(cx + 1), float(cy + 1), 0);
            stream::WriteTile(stream::TilePath(dir, c), t);
            stream::ChartRecord rec;
            rec.triangles = t.meta.triangle_count;
            rec.vertices = t.meta.vertex_count;
            rec.resolution = res;
            rec.scale = 1;
            rec.area = 1;
            rec.bbox_min = t.meta.bbox_min;
            rec.bbox_max = t.meta.bbox_max;
            man.charts.push_back(rec);

            // E_z in chart coordinates: A + Bu u + Bv v, as Legendre coefficients on the root.
            solve::ChartField f(1, 9);
            const int n = solve::NumCoeffs(1);
            const double bu = o.bx / span, bv = o.by / span;
            const float off = c < o.offset.size() ? o.offset[c] : 0.f;
            for (int k = 0; k < 3; ++k) {
                const double a0 =
                    o.a[k] + o.bx * (cx - o.inset / span) + o.by * (cy - o.inset / span) + off;
                float* z = f.value(0) + (3 * k + 2) * n;
                z[0] = float(a0 + bu / 2 + bv / 2);
                z[solve::CoeffIndex(1, 1, 0)] = float(bu / (2 * std::sqrt(3.0)));
                z[solve::CoeffIndex(1, 0, 1)] = float(bv / (2 * std::sqrt(3.0)));
            }
            const size_t nodes = f.node_count();
            for (size_t k = 0; k < nodes; ++k)
                f.Subdivide(k);
            fields.push_back(std::move(f));
        }
    stream::WriteManifest(dir, man);
    {
        DiskArray<Vec3f> v(stream::Spill::VerticesPath(dir), true, 1 << 16);
        for (int r = 0; r < rows; ++r)
            for (int q = 0; q < cols; ++q)
                v.Push(lattice(q, r));
        v.Flush();
    }
    solve::WriteSolution(solve::SolutionPath(dir), fields, false);
    std::ofstream(dir + "/solve/scene.json")
        << R"({"materials": [{"albedo": 0.5, "use_vertex_colors": false}],
              "sky": {"type": "uniform", "radiance": [0.1, 0.2, 0.3]}})";
}

// Chart of world point (x, y) and its uv there.
struct ChartPoint {
    uint32_t chart;
    Vec2f uv;
};

ChartPoint Locate(const GridOptions& o, int cx, int cy, double x, double y) {
    return {uint32_t(cy * o.kx + cx),
            Vec2f(float(o.inset + Span(o) * (x - cx)), float(o.inset + Span(o) * (y - cy)))};
}

// A seam point: world (x, y) on the border of charts (cx0, cy0) and (cx1, cy1).
struct SeamPoint {
    double x, y;
    int cx0, cy0, cx1, cy1;
};

std::vector<SeamPoint> SeamPoints(const GridOptions& o, int per_unit) {
    std::vector<SeamPoint> pts;
    for (int k = 0; k < per_unit; ++k) {
        const double s = (k + 0.37) / per_unit;  // off the lattice's vertices
        for (int cy = 0; cy < o.ky; ++cy)
            for (int cx = 0; cx + 1 < o.kx; ++cx)
                pts.push_back({double(cx + 1), cy + s, cx, cy, cx + 1, cy});
        for (int cy = 0; cy + 1 < o.ky; ++cy)
            for (int cx = 0; cx < o.kx; ++cx)
                pts.push_back({cx + s, double(cy + 1), cx, cy, cx, cy + 1});
    }
    return pts;
}

class StitchTest : public ::testing::Test {
protected:
    void SetUp() override { dir_ = solve::testing::FreshDir("stitch"); }
    void TearDown() override { std::filesystem::remove_all(dir_); }

    // The grid bake of `o`, written afresh: its views without and with the stitch, and the
    // stitch's edge counts.
    struct Stitched {
        BakeView raw, view;
        SeamGraphStats gs;
    };
    Stitched BakeAndStitch(const GridOptions& o) {
        std::filesystem::remove_all(dir_);
        WriteGridBake(dir_, o);
        Stitched s{OpenBakeView(dir_, FieldLoading::All, SeamStitching::Off), OpenBakeView(dir_),
                   {}};
        BuildSeamStitch(s.view, &s.gs);
        return s;
    }

    // Per-chart shaders of a view (tiles and fields kept by the fixture).
    void LoadShaders(const BakeView& view) {
        const size_t n = view.chart_count();
        tiles_.assign(n, {});
        shaders_.clear();
        for (uint32_t c = 0; c < n; ++c)
            tiles_[c] = stream::ReadTile(view.TilePath(c), stream::TileParts::Mesh);
        for (uint32_t c = 0; c < n; ++c)
            shaders_.push_back(std::make_unique<ChartShader>(tiles_[c], view.solution.fields[c],
                                                             view.solution.radiosity, view.scene,
                                                             view.TilePath(c), view.Seams(c)));
    }
    Vec3f B(const ChartPoint& p) const {
        return shaders_[p.chart]->Radiosity(shaders_[p.chart]->AtUv(p.uv));
    }
    // B in every chart (cx, cy) of `view` at the world points (cx + x, cy + y).
    std::vector<Vec3f> BInEveryChart(const GridOptions& o, const BakeView& view,
                                     std::initializer_list<double> xs,
                                     std::initializer_list<double> ys) {
        LoadShaders(view);
        std::vector<Vec3f> out;
        for (int cy = 0; cy < o.ky; ++cy)
            for (int cx = 0; cx < o.kx; ++cx)
                for (double y : ys)
                    for (double x : xs)
                        out.push_back(B(Locate(o, cx, cy, cx + x, cy + y)));
        return out;
    }
    static void ExpectSame(const std::vector<Vec3f>& shown, const std::vector<Vec3f>& own) {
        ASSERT_EQ(own.size(), shown.size());
        for (size_t i = 0; i < own.size(); ++i)
            for (int k = 0; k < 3; ++k)
                EXPECT_NEAR(shown[i][k], own[i][k], 1e-5 * own[i][k]) << "point " << i;
    }

    // The light map (one page) as a viewer filters it bilinearly at chart point uv.
    Vec3f Filtered(const Atlas& atlas, const std::vector<float>& page, const ChartPoint& p) const {
        const AtlasChart& ac = atlas.charts[p.chart];
        const uint32_t w = atlas.pages[0].width;
        const double x = ac.x + atlas.gutter + double(p.uv.x) * ac.resolution - 0.5;
        const double y = ac.y + atlas.gutter + double(p.uv.y) * ac.resolution - 0.5;
        const int x0 = int(std::floor(x)), y0 = int(std::floor(y));
        const double fx = x - x0, fy = y - y0;
        Vec3f out{};
        for (int dy = 0; dy < 2; ++dy)
            for (int dx = 0; dx < 2; ++dx) {
                const float* px = &page[(size_t(y0 + dy) * w + size_t(x0 + dx)) * 4];
                const float wgt = float((dx ? fx : 1 - fx) * (dy ? fy : 1 - fy));
                out += Vec3f(px[0], px[1], px[2]) * wgt;
            }
        return out;
    }

    std::vector<float> Page(const BakeView& view, const Atlas& atlas) const {
        const auto stitch = StitchForView(view, atlas, MapContent::Radiosity);
        std::vector<float> page(size_t(atlas.pages[0].width) * atlas.pages[0].height * 4);
        ComputePage(
            view, atlas, 0, MapContent::Radiosity,
            [&](std::span<const float> px, uint32_t first, uint32_t) {
                std::copy(px.begin(), px.end(),
                          page.begin() + ptrdiff_t(first) * atlas.pages[0].width * 4);
            },
            64, 0, stitch.get());
        return page;
    }

    // Largest relative step of the filtered light map across the seams.
    double WorstFilteredStep(const GridOptions& o, const BakeView& view) const {
        const Atlas atlas = PackAtlas(ChartResolutions(view));
        EXPECT_EQ(atlas.pages.size(), 1u);
        const std::vector<float> page = Page(view, atlas);
        double worst = 0;
        for (const SeamPoint& s : SeamPoints(o, 40)) {
            const Vec3f b0 = Filtered(atlas, page, Locate(o, s.cx0, s.cy0, s.x, s.y));
            const Vec3f b1 = Filtered(atlas, page, Locate(o, s.cx1, s.cy1, s.x, s.y));
            for (int k = 0; k < 3; ++k)
                worst = std::max(worst, std::abs(double(b0[k] - b1[k])) / ExactB(o, s.x, s.y, k));
        }
        return worst;
    }

    std::string dir_;
    std::vector<stream::ChartTile> tiles_;
    std::vector<std::unique_ptr<ChartShader>> shaders_;
};

GridOptions Perturbed() {
    GridOptions o;
    o.offset = {0.3f, -0.25f, 0.2f, -0.3f, 0.15f, 0.f};  // 5-15 % of E_z
    return o;
}
// ... and neighbouring charts' vertex normals 17 degrees apart.
GridOptions PerturbedAndTilted() {
    GridOptions o = Perturbed();
    o.tilt = 0.3f;
    return o;
}

TEST_F(StitchTest, ExactFieldStaysExact) {
    const GridOptions o;
    WriteGridBake(dir_, o);
    const BakeView view = OpenBakeView(dir_);
    SeamGraphStats gs;
    BuildSeamStitch(view, &gs);
    EXPECT_EQ(gs.stitched_edges, uint64_t(o.m * ((o.kx - 1) * o.ky + o.kx * (o.ky - 1))));
    EXPECT_EQ(gs.fold_edges, 0u);
    LoadShaders(view);
    for (int cy = 0; cy < o.ky; ++cy)
        for (int cx = 0; cx < o.kx; ++cx)
            for (double fy : {0.0, 0.01, 0.3, 0.99, 1.0})
                for (double fx : {0.0, 0.02, 0.5, 0.98, 1.0}) {
                    const Vec3f b = B(Locate(o, cx, cy, cx + fx, cy + fy));
                    for (int k = 0; k < 3; ++k)
                        EXPECT_NEAR(b[k], ExactB(o, cx + fx, cy + fy, k), 1e-5 * b[k]);
                }
    // The filtered light map is within bilinear interpolation of a linear field: exact.
    EXPECT_LT(WorstFilteredStep(o, view), 1e-5);
}

TEST_F(StitchTest, BordersShowOneValue) {
    const GridOptions o = PerturbedAndTilted();
    WriteGridBake(dir_, o);
    const BakeView raw = OpenBakeView(dir_, FieldLoading::All, SeamStitching::Off);
    const BakeView view = OpenBakeView(dir_);
    for (const BakeView* v : {&raw, &view}) {
        LoadShaders(*v);
        double worst = 0;
        for (const SeamPoint& s : SeamPoints(o, 25)) {
            const Vec3f b0 = B(Locate(o, s.cx0, s.cy0, s.x, s.y));
            const Vec3f b1 = B(Locate(o, s.cx1, s.cy1, s.x, s.y));
            for (int k = 0; k < 3; ++k)
                worst = std::max(worst, std::abs(double(b0[k] - b1[k])) / ExactB(o, s.x, s.y, k));
        }
        if (v == &raw) {
            EXPECT_GT(worst, 0.05);  // the perturbation shows
        } else {
            EXPECT_LT(worst, 1e-5);
        }
    }
    // The seam metric (B at points of every border edge with each side's own attributes).
    SeamOptions so;
    so.samples = 16;
    EXPECT_GT(MeasureSeams(raw, so).display.max, 0.01);
    const SeamStats s = MeasureSeams(view, so);
    EXPECT_EQ(s.seam_edges, uint64_t(o.m * ((o.kx - 1) * o.ky + o.kx * (o.ky - 1))));
    EXPECT_LT(s.max_relative, 1e-5);
    EXPECT_LT(s.display.max, 1e-5);
}

// A crease in the shading normals: neighbouring charts' vertex normals 56 degrees apart (a
// scan's hard edge, a normal per side), or 35 (a fold where ingest kept each chart's own
// normal: more than 30 degrees from the brick's). Each chart's E holds the light above its
// own horizon and B follows its own normal, so the sides differ there in any correct
// solution: stitching leaves each chart its own field and normals (before, it averaged both
// and moved nefertiti's crown from the reference's 1.84 to 0.61; at 31 degrees, a point of
// lucy's from -1.4 to -26 %).
TEST_F(StitchTest, CreaseInTheShadingNormalsKeepsEachSidesField) {
    for (const float tilt : {1.5f, 0.7f}) {
        SCOPED_TRACE(tilt);
        GridOptions o = Perturbed();
        o.tilt = tilt;
        const auto [raw, view, gs] = BakeAndStitch(o);
        const uint64_t all = uint64_t(o.m * ((o.kx - 1) * o.ky + o.kx * (o.ky - 1)));
        EXPECT_EQ(gs.stitched_edges, 0u);
        EXPECT_EQ(gs.fold_edges, all);
        // Nor measured: B is discontinuous on the mesh itself there.
        EXPECT_EQ(MeasureSeams(view, SeamOptions{}).fold_edges, all);
        const auto xs = {0.0, 0.02, 0.5, 0.98, 1.0}, ys = {0.0, 0.01, 0.3, 0.99, 1.0};
        ExpectSame(BInEveryChart(o, view, xs, ys), BInEveryChart(o, raw, xs, ys));
        LoadShaders(view);
        // Nor does the light map's seam solve pull the texels of the two sides together: each
        // side, filtered, shows its own B (linear per chart, so bilinear filtering is exact).
        const Atlas atlas = PackAtlas(ChartResolutions(view));
        const std::vector<float> page = Page(view, atlas);
        for (const SeamPoint& sp : SeamPoints(o, 10))
            for (const ChartPoint& p : {Locate(o, sp.cx0, sp.cy0, sp.x, sp.y),
                                        Locate(o, sp.cx1, sp.cy1, sp.x, sp.y)}) {
                const Vec3f f = Filtered(atlas, page, p), b = B(p);
                for (int k = 0; k < 3; ++k)
                    EXPECT_NEAR(f[k], b[k], 1e-3 * b[k]) << sp.x << ", " << sp.y;
            }
    }
}

// A bend of the surface between charts: faces 35 degrees apart along x = 1. Each chart's own
// field was the closer to the path tracer beside such bends (lucy's point 0.7 texel from a
// 40-degree border: own +0.9 %, stitched +17.6 %; bench/RESULTS.md, "Issue 13 (session
// 19)"): neither the field's stitch nor the light map's pulls that border's sides together.
// At 20 degrees it is stitched like the rest.
TEST_F(StitchTest, BendOfMoreThanThirtyDegreesKeepsEachSidesField) {
    for (const double degrees : {35.0, 20.0}) {
        SCOPED_TRACE(degrees);
        GridOptions o = Perturbed();
        o.bend = float(degrees * std::acos(-1.0) / 180);
        const auto [raw, view, gs] = BakeAndStitch(o);
        const uint64_t all = uint64_t(o.m * ((o.kx - 1) * o.ky + o.kx * (o.ky - 1)));
        const uint64_t bend = degrees > 30 ? uint64_t(o.m * o.ky) : 0;
        EXPECT_EQ(gs.fold_edges, bend);
        EXPECT_EQ(gs.stitched_edges, all - bend);
        LoadShaders(raw);
        std::vector<Vec3f> own;
        std::vector<SeamPoint> on_bend;
        for (const SeamPoint& sp : SeamPoints(o, 10))
            if (sp.x == 1.0) {
                on_bend.push_back(sp);
                own.push_back(B(Locate(o, sp.cx0, sp.cy0, sp.x, sp.y)));
                own.push_back(B(Locate(o, sp.cx1, sp.cy1, sp.x, sp.y)));
            }
        LoadShaders(view);
        const Atlas atlas = PackAtlas(ChartResolutions(view));
        const std::vector<float> page = Page(view, atlas);
        double worst = 0, worst_map = 0;  // largest step across the bend, field and light map
        for (size_t i = 0; i < on_bend.size(); ++i) {
            const SeamPoint& sp = on_bend[i];
            const ChartPoint p0 = Locate(o, sp.cx0, sp.cy0, sp.x, sp.y);
            const ChartPoint p1 = Locate(o, sp.cx1, sp.cy1, sp.x, sp.y);
            const Vec3f b0 = B(p0), b1 = B(p1), f0 = Filtered(atlas, page, p0),
                        f1 = Filtered(atlas, page, p1);
            for (int k = 0; k < 3; ++k) {
                const double exact = ExactB(o, sp.x, sp.y, k);
                worst = std::max(worst, std::abs(double(b0[k] - b1[k])) / exact);
                worst_map = std::max(worst_map, std::abs(double(f0[k] - f1[k])) / exact);
                // Each side its own field (to 0.1 %: the stitched edges that meet the bend at
                // its ends reach in a little; the perturbation is 5-15 %).
                if (degrees > 30) {
                    EXPECT_NEAR(b0[k], own[2 * i][k], 1e-3 * own[2 * i][k]);
                    EXPECT_NEAR(b1[k], own[2 * i + 1][k], 1e-3 * own[2 * i + 1][k]);
                }
            }
        }
        if (degrees > 30) {
            EXPECT_GT(worst, 0.05);  // the perturbation shows across the bend
            EXPECT_GT(worst_map, 0.05);
        } else {
            EXPECT_LT(worst, 1e-5);
            EXPECT_LT(worst_map, 1e-3);
        }
    }
}

// Per-chart vertex normals 17 degrees apart (not a crease), exact fields: the stitched
// normals make B one value on the border (BordersShowOneValue), and beyond the stitch's band
// each chart shades with its own normals, as the mesh and the path tracer do. Spread over
// whole triangles, the mean normal of a border vertex reached 0.3 of a chart inside here and
// six texels into lucy's triangles, and lowered its pictures (bench/RESULTS.md, issue 14
// session 9).
TEST_F(StitchTest, OwnNormalsBeyondTheBand) {
    GridOptions o;
    o.tilt = 0.3f;
    WriteGridBake(dir_, o);
    const BakeView raw = OpenBakeView(dir_, FieldLoading::All, SeamStitching::Off);
    const BakeView view = OpenBakeView(dir_);
    ExpectSame(BInEveryChart(o, view, {0.3, 0.5, 0.7}, {0.3, 0.5, 0.7}),
               BInEveryChart(o, raw, {0.3, 0.5, 0.7}, {0.3, 0.5, 0.7}));
}

// A vertex normal behind its triangle (averaged over a fold that turns back on itself)
// shades with the triangle's plane, as the reference path tracer does; with the reversed
// normal (n . E)+ was 0 and lucy's away picture showed a black pixel there.
TEST_F(StitchTest, ReversedShadingNormalsFallBackToTheFace) {
    GridOptions o;
    o.reversed = true;
    WriteGridBake(dir_, o);
    const BakeView view = OpenBakeView(dir_);
    LoadShaders(view);
    for (int cy = 0; cy < o.ky; ++cy)
        for (int cx = 0; cx < o.kx; ++cx)
            for (const double f : {0.04, 0.5, 0.93}) {
                const double x = cx + f, y = cy + 1 - f;
                const ChartPoint p = Locate(o, cx, cy, x, y);
                const ShadingPoint sp = shaders_[p.chart]->AtUv(p.uv);
                EXPECT_GT(sp.normal.z, 0.999f) << "chart " << p.chart;
                const Vec3f b = shaders_[p.chart]->Radiosity(sp);
                for (int k = 0; k < 3; ++k)
                    EXPECT_NEAR(b[k], ExactB(o, x, y, k), 1e-4 * ExactB(o, x, y, k))
                        << "chart " << p.chart << " at (" << x << ", " << y << ")";
            }
}

TEST_F(StitchTest, StitchingStaysWithinThePerturbation) {
    const GridOptions o = Perturbed();
    WriteGridBake(dir_, o);
    const BakeView view = OpenBakeView(dir_);
    LoadShaders(view);
    // Band: at most 6 texels of the chart square.
    const double band = 6.0 / o.resolution / Span(o);
    // The shown field blends leaves within delta of their node borders, each evaluated on
    // its own node only: a linear field moves there by at most (|dB/du| + |dB/dv|) delta / 8
    // (continuous_field.h).
    const ContinuousField shown(*view.Field(0), 1.0 / o.resolution);
    const double blend = kAlbedo * (o.bx + o.by) / Span(o) * shown.delta() / 8 + 1e-5;
    for (int cy = 0; cy < o.ky; ++cy)
        for (int cx = 0; cx < o.kx; ++cx) {
            const float off = o.offset[size_t(cy * o.kx + cx)];
            for (int j = 0; j <= 20; ++j)
                for (int i = 0; i <= 20; ++i) {
                    const double x = cx + i / 20.0, y = cy + j / 20.0;
                    const Vec3f b = B(Locate(o, cx, cy, x, y));
                    // Near a border: between the charts' own values (|offset| <= 0.3).
                    for (int k = 0; k < 3; ++k)
                        EXPECT_LE(std::abs(b[k] - ExactB(o, x, y, k)), kAlbedo * 0.3 + blend);
                    // Beyond every band: the chart's own fit, untouched.
                    const bool bordered =
                        (x - cx < band && cx > 0) || (cx + 1 - x < band && cx + 1 < o.kx) ||
                        (y - cy < band && cy > 0) || (cy + 1 - y < band && cy + 1 < o.ky);
                    if (bordered)
                        continue;
                    for (int k = 0; k < 3; ++k)
                        EXPECT_NEAR(b[k], ExactB(o, x, y, k) + kAlbedo * off, blend);
                }
        }
}

TEST_F(StitchTest, LightMapFilteredAcrossSeamsAgrees) {
    const GridOptions o = Perturbed();
    WriteGridBake(dir_, o);
    // Unstitched the filtered step is the perturbation (5-15 %); stitched, the least-squares
    // texels leave a residue of the seam weight's order (lambda = 100: about 1 %), then
    // bilinear interpolation of the stitched field adds nothing for a linear field.
    const double raw =
        WorstFilteredStep(o, OpenBakeView(dir_, FieldLoading::All, SeamStitching::Off));
    const double stitched = WorstFilteredStep(o, OpenBakeView(dir_));
    EXPECT_GT(raw, 0.05);
    EXPECT_LT(stitched, 0.005);
}

// The stitched texels go to temporary files as the charts are prepared and come back a chart
// at a time (TexelStitch::Chart): every chart of the grid has seams, its texels ascending in
// its own square, and the charts' lists add up to the unknowns the CG solved.
TEST_F(StitchTest, TexelsComeBackPerChart) {
    const GridOptions o = Perturbed();
    WriteGridBake(dir_, o);
    const BakeView view = OpenBakeView(dir_);
    const Atlas atlas = PackAtlas(ChartResolutions(view));
    TexelStitchStats stats;
    const TexelStitch stitch = StitchTexels(view, atlas, MapContent::Radiosity, &stats);
    EXPECT_EQ(stitch.size(), stats.texels);
    size_t total = 0;
    for (uint32_t c = 0; c < view.chart_count(); ++c) {
        const StitchedTexels t = stitch.Chart(c);
        const uint32_t res = atlas.charts[c].resolution;
        ASSERT_FALSE(t.texel.empty()) << "chart " << c;
        ASSERT_EQ(t.values.size(), t.texel.size() * 4);
        EXPECT_TRUE(std::is_sorted(t.texel.begin(), t.texel.end()));
        EXPECT_LT(t.texel.back(), res * res);
        for (size_t k = 0; k < t.texel.size(); ++k) {
            EXPECT_EQ(t.Find(t.texel[k], 4), &t.values[k * 4]);
            EXPECT_EQ(t.values[k * 4 + 3], 1.f);  // A is not stitched
        }
        total += t.texel.size();
    }
    EXPECT_EQ(total, stitch.size());
    EXPECT_TRUE(stitch.Chart(uint32_t(view.chart_count())).texel.empty());
}

// The stitch's share decides where the seam samples live (memory or a temporary file) and
// whether the colour channels' CGs run in parallel; the texels, the iterations and the
// mismatch must be the same bits in all three ways, for any thread count.
TEST_F(StitchTest, TexelsAreTheSameWhereverTheRowsLive) {
    const GridOptions o = Perturbed();
    WriteGridBake(dir_, o);
    const BakeView view = OpenBakeView(dir_);
    const Atlas atlas = PackAtlas(ChartResolutions(view));
    auto solve = [&](uint64_t memory_bytes, int threads, TexelStitchStats* stats) {
        ThreadLimit limit(threads);
        return StitchTexels(view, atlas, MapContent::Radiosity, stats, memory_bytes);
    };
    // 0: every row goes to the file; 64 rows: the first rows in memory, then all moved to
    // the file; 256 KiB: one block of rows in memory, too little left for three channels'
    // CGs (channels in turn); 64 MiB: rows and every channel's CG in memory (in parallel).
    TexelStitchStats stats[4];
    const TexelStitch on_disk = solve(0, 2, &stats[0]);
    const TexelStitch moved = solve(64 * 64, 2, &stats[1]);
    const TexelStitch in_turn = solve(256 * 1024, 2, &stats[2]);
    const TexelStitch parallel = solve(uint64_t(64) << 20, 2, &stats[3]);
    const TexelStitch one_thread = solve(uint64_t(64) << 20, 1, nullptr);
    ASSERT_GT(stats[3].samples, 64u);
    ASSERT_LT(stats[3].samples, 4096u);  // one block of rows
    ASSERT_GT(stats[3].iterations, 1);
    const bool in_memory[4] = {false, false, true, true}, in_parallel[4] = {false, false, false, true};
    for (int k = 0; k < 4; ++k) {
        EXPECT_EQ(stats[k].rows_in_memory, in_memory[k]) << k;
        EXPECT_EQ(stats[k].channels_in_parallel, in_parallel[k]) << k;
    }
    for (int k = 0; k < 3; ++k) {
        EXPECT_EQ(stats[k].texels, stats[3].texels);
        EXPECT_EQ(stats[k].samples, stats[3].samples);
        EXPECT_EQ(stats[k].iterations, stats[3].iterations);
        EXPECT_EQ(stats[k].rms_before, stats[3].rms_before);
        EXPECT_EQ(stats[k].rms_after, stats[3].rms_after);
    }
    for (uint32_t c = 0; c < view.chart_count(); ++c) {
        const StitchedTexels p = parallel.Chart(c);
        for (const TexelStitch* other : {&on_disk, &moved, &in_turn, &one_thread}) {
            const StitchedTexels t = other->Chart(c);
            EXPECT_EQ(t.texel, p.texel) << "chart " << c;
            EXPECT_EQ(t.values, p.values) << "chart " << c;
        }
    }
}

TEST_F(StitchTest, VertexCopiesAgree) {
    const GridOptions o = PerturbedAndTilted();
    WriteGridBake(dir_, o);
    const BakeView view = OpenBakeView(dir_);
    LoadShaders(view);
    // Every copy of a global vertex (one per chart using it) shades to the same B, so the
    // vertex colour, their mean, is that value.
    std::map<uint64_t, std::vector<Vec3f>> copies;
    for (uint32_t c = 0; c < tiles_.size(); ++c)
        for (uint32_t v = 0; v < tiles_[c].vertex_id.size(); ++v)
            copies[tiles_[c].vertex_id[v]].push_back(
                shaders_[c]->Radiosity(shaders_[c]->AtVertex(v)));
    int shared = 0;
    for (const auto& [id, bs] : copies) {
        shared += bs.size() > 1;
        for (const Vec3f& b : bs)
            for (int k = 0; k < 3; ++k)
                EXPECT_NEAR(b[k], bs[0][k], 1e-5 * bs[0][k]) << "vertex " << id;
    }
    EXPECT_EQ(shared, (o.kx - 1) * (o.ky * o.m + 1) + (o.ky - 1) * (o.kx * o.m + 1) -
                          (o.kx - 1) * (o.ky - 1));
}

// AtUvInside (node_seams.cpp's one search per sample) is InsideTriangle's test and AtUv's
// point: inside the triangles, on their borders, in the inset's virtual margin and outside
// the unit square (clamped).
TEST_F(StitchTest, AtUvInsideIsInsideTriangleAndAtUv) {
    const GridOptions o = PerturbedAndTilted();
    WriteGridBake(dir_, o);
    const BakeView view = OpenBakeView(dir_);
    LoadShaders(view);
    int inside = 0, outside = 0;
    for (uint32_t c = 0; c < tiles_.size(); ++c)
        for (int j = 0; j <= 40; ++j)
            for (int i = 0; i <= 40; ++i) {
                const Vec2f u(-0.02f + 1.04f * float(i) / 40, -0.02f + 1.04f * float(j) / 40);
                const bool want = tiles_[c].grid.InsideTriangle(u) != stream::kNoTriangle;
                const std::optional<ShadingPoint> got = shaders_[c]->AtUvInside(u);
                ASSERT_EQ(got.has_value(), want) << "chart " << c << " at " << u.x << ", " << u.y;
                (want ? inside : outside)++;
                if (!got)
                    continue;
                const ShadingPoint at = shaders_[c]->AtUv(u);
                EXPECT_EQ(got->uv, at.uv);
                EXPECT_EQ(got->normal, at.normal);
                EXPECT_EQ(got->albedo, at.albedo);
                EXPECT_EQ(got->material, at.material);
            }
    EXPECT_GT(inside, 0);
    EXPECT_GT(outside, 0);
}

TEST_F(StitchTest, RenderShowsNoStepAtBorders) {
    const GridOptions o = Perturbed();
    WriteGridBake(dir_, o);
    RenderOptions ro;
    ro.camera.eye = Vec3d(1.5, 1, 4);
    ro.camera.target = Vec3d(1.5, 1, 0);
    ro.camera.up = Vec3d(0, 1, 0);
    ro.camera.fov = 45;
    ro.camera.width = 160;
    ro.camera.height = 120;
    ro.background = Vec3f(0, 0, 0);
    // The largest step between horizontally neighbouring pixels both on the plane, relative.
    auto worst_step = [&](const BakeView& v) {
        const RenderedImage img = Render(v, ro);
        double worst = 0;
        for (int y = 0; y < img.height; ++y)
            for (int x = 0; x + 1 < img.width; ++x) {
                const Vec3f p = img.At(x, y), q = img.At(x + 1, y);
                if (p.x <= 0 || q.x <= 0)
                    continue;
                worst = std::max(worst, std::abs(double(p.y - q.y)) / double(p.y));
            }
        return worst;
    };
    const double raw = worst_step(OpenBakeView(dir_, FieldLoading::All, SeamStitching::Off));
    const double stitched = worst_step(OpenBakeView(dir_));
    // A pixel spans about 0.024 world units: the closed form's gradient moves B by < 0.5 %
    // per pixel; the bands (<= 6 texels, ~0.5 world units) spread a 15 % offset over ~20
    // pixels each side.
    EXPECT_GT(raw, 0.05);
    EXPECT_LT(stitched, 0.02);
}

TEST_F(StitchTest, SameForAnyThreadCount) {
    const GridOptions o = Perturbed();
    WriteGridBake(dir_, o);
    std::vector<float> pages[2];
    for (int threads : {1, 2}) {
        ThreadLimit limit(threads);
        const BakeView view = OpenBakeView(dir_, FieldLoading::OnDemand);
        const Atlas atlas = PackAtlas(ChartResolutions(view));
        pages[threads - 1] = Page(view, atlas);
    }
    EXPECT_EQ(pages[0], pages[1]);
}

// Each chart's stitch data is built on demand from its neighbourhood; what is cached
// between charts (and in which order charts are asked for) changes the work, not the data.
TEST_F(StitchTest, SameDataWhateverTheCacheAndTheOrder) {
    const GridOptions o = Perturbed();
    WriteGridBake(dir_, o);
    const BakeView none = OpenBakeView(dir_, FieldLoading::All, SeamStitching::On, 0);
    const BakeView all = OpenBakeView(dir_, FieldLoading::All, SeamStitching::On, size_t(1) << 30);
    const uint32_t n = uint32_t(none.chart_count());
    std::vector<std::shared_ptr<const ChartSeams>> a(n), b(n);
    for (uint32_t c = 0; c < n; ++c)
        a[c] = none.Seams(c);
    for (uint32_t c = n; c-- > 0;)
        b[c] = all.Seams(c);
    EXPECT_EQ(none.stitcher->hits(), 0u);
    EXPECT_GT(all.stitcher->hits(), 0u);
    EXPECT_EQ(all.stitcher->misses(), n);  // each chart sampled once
    auto expect_same = [](const ChartSeams& x, const ChartSeams& y) {
        ASSERT_EQ(x.edge_count(), y.edge_count());
        for (size_t k = 0; k < x.edge_count(); ++k) {
            const SeamEdge &ex = x.edges()[k], &ey = y.edges()[k];
            EXPECT_EQ(ex.a, ey.a);
            EXPECT_EQ(ex.b, ey.b);
            EXPECT_EQ(ex.band, ey.band);
            EXPECT_EQ(ex.count, ey.count);
            for (uint32_t s = 0; s < ex.count; ++s) {
                float tx[9], ty[9];
                x.Target(ex, double(s) / (ex.count - 1), tx);
                y.Target(ey, double(s) / (ey.count - 1), ty);
                for (int k9 = 0; k9 < 9; ++k9)
                    EXPECT_EQ(tx[k9], ty[k9]);
            }
        }
        EXPECT_EQ(x.normals(), y.normals());
    };
    for (uint32_t c = 0; c < n; ++c) {
        EXPECT_GT(a[c]->edge_count(), 0u);
        expect_same(*a[c], *b[c]);
        expect_same(*a[c], *none.Seams(c));  // read back from the view's file
        expect_same(*a[c], none.stitcher->Build(none, c));
    }
    const Atlas atlas = PackAtlas(ChartResolutions(none));
    EXPECT_EQ(Page(none, atlas), Page(all, atlas));
}

// The pairing of border sides in chart order (seam_graph.h): first side waits, a later
// chart's side pairs with it, a second side from the same chart is ignored, a third chart's
// side waits again, and a chart's unpaired sides are dropped as open once its last
// neighbour is done (so a later non-neighbour's side of the same key waits on its own).
TEST(BorderPairingTest, PairsInChartOrderAndDropsSidesNoLaterChartCanMeet) {
    BorderPairing<std::string> pairing(std::vector<uint32_t>{1, 3, 3, 3});
    std::vector<std::pair<std::string, std::string>> pairs;
    auto add = [&](uint32_t c, uint64_t key, const std::string& side) {
        pairing.Add(c, {key, key + 1}, side, [&](const std::string& w, const std::string& s) {
            pairs.emplace_back(w, s);
        });
    };
    add(0, 10, "0a");
    add(0, 20, "0b");
    add(0, 10, "0a'");  // a split vertex inside chart 0: not a pair
    pairing.Done(0);
    EXPECT_EQ(pairing.waiting(), 2u);
    add(1, 10, "1a");
    pairing.Done(1);  // chart 0's last neighbour: its side of key 20 is open
    EXPECT_EQ(pairing.waiting(), 0u);
    EXPECT_EQ(pairing.open(), 1u);
    add(2, 20, "2b");
    add(2, 10, "2a");  // a third chart on key 10 waits again
    pairing.Done(2);
    add(3, 10, "3a");
    pairing.Done(3);
    EXPECT_EQ(pairing.waiting(), 0u);
    EXPECT_EQ(pairing.open(), 2u);  // 0b and 2b
    const std::vector<std::pair<std::string, std::string>> want = {{"0a", "1a"}, {"2a", "3a"}};
    EXPECT_EQ(pairs, want);
}

}  // namespace
}  // namespace mebake::output
