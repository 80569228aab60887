#include "output/render.h"

#include "core/check.h"
#include "core/error.h"
#include "core/parallel.h"
#include "core/progress.h"
#include "io/png_writer.h"
#include "solve/visibility.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <memory>
#include <numbers>

namespace mebake::output {

namespace {

// Radiance = B / pi, divided as shading.cpp does so the glossy path agrees to the bit.
constexpr float kPi = float(std::numbers::pi);

}  // namespace

// Charts of the object: all, or with --ground those inside the object's box (the ground's
// charts reach outside it).
static std::vector<uint32_t> ObjectCharts(const stream::Manifest& m) {
    std::vector<uint32_t> charts;
    const Vec3d lo = m.object_bbox_min, hi = m.object_bbox_max;
    const Vec3d eps = (hi - lo) * 1e-3;
    auto inside = [&](const Vec3f& q) {
        const Vec3d p(q);
        return p.x >= lo.x - eps.x && p.y >= lo.y - eps.y && p.z >= lo.z - eps.z &&
               p.x <= hi.x + eps.x && p.y <= hi.y + eps.y && p.z <= hi.z + eps.z;
    };
    for (uint32_t c = 0; c < m.charts.size(); ++c)
        if (!m.ground || (inside(m.charts[c].bbox_min) && inside(m.charts[c].bbox_max)))
            charts.push_back(c);
    return charts;
}

Camera DefaultCamera(const BakeView& view, int width, int height, double fov) {
    Camera cam;
    cam.width = width;
    cam.height = height;
    cam.fov = fov > 0 && fov < 180 ? fov : 50;
    const stream::Manifest& m = view.manifest;
    const Vec3d lo = m.ground ? m.object_bbox_min : m.bbox_min;
    const Vec3d hi = m.ground ? m.object_bbox_max : m.bbox_max;
    const Vec3d center = (lo + hi) * 0.5;
    const Vec3d up = Normalize(view.scene.sky.up);
    // The frame of the default rig (solve/scene.cpp): the key light stands at the side
    // (+side), 40 degrees up; the camera looks from a three-quarter view on the same side,
    // lower, so that the shadows the key casts fall across the faces it sees.
    Vec3d side = std::abs(up.x) < 0.9 ? Vec3d(1, 0, 0) : Vec3d(0, 0, 1);
    const Vec3d front = Normalize(Cross(side, up));
    side = Normalize(Cross(up, front));
    const Vec3d dir = Normalize(front * 1.0 + side * 0.75 + up * 0.4);  // towards the eye
    const Vec3d right = Normalize(Cross(-dir, up)), cam_up = Cross(right, -dir);
    // The distance at which every vertex of the object projects inside 85 % of the frame
    // (tighter than its bounding sphere, which leaves a round object at half the frame).
    // A max over the charts: the same for any thread count.
    const double tan_v = std::tan(cam.fov * 0.5 * std::numbers::pi / 180);
    const double tan_h = tan_v * double(width) / std::max(height, 1);
    constexpr double kFill = 0.85;
    auto need = [&](const Vec3d& p) {
        const Vec3d q = p - center;
        const double z = Dot(q, dir);
        return std::max({z + std::abs(Dot(q, right)) / (kFill * tan_h),
                         z + std::abs(Dot(q, cam_up)) / (kFill * tan_v), 2 * z});
    };
    const std::vector<uint32_t> charts = ObjectCharts(m);
    std::vector<double> dist(charts.size(), 0);
    ParallelFor(0, int64_t(charts.size()), [&](int64_t k) {
        const auto tile =
            stream::ReadTile(view.TilePath(charts[size_t(k)]), stream::TileParts::Mesh);
        for (const Vec3f& p : tile.position)
            dist[size_t(k)] = std::max(dist[size_t(k)], need(Vec3d(p)));
    });
    double d = 1e-9 * std::max(Length(hi - lo), 1e-9);
    for (double v : dist)
        d = std::max(d, v);
    if (charts.empty()) {  // nothing to frame: the box
        for (int k = 0; k < 8; ++k)
            d = std::max(d, need(Vec3d(k & 1 ? hi.x : lo.x, k & 2 ? hi.y : lo.y,
                                       k & 4 ? hi.z : lo.z)));
    }
    cam.eye = center + dir * d;
    cam.target = center;
    cam.up = up;
    return cam;
}

RenderedImage Render(const BakeView& view, const RenderOptions& opt) {
    const Camera& cam = opt.camera;
    const PinholeRays rays(cam);  // validates the camera
    if (opt.samples < 1 || opt.samples > 16)
        UsageError("--samples {}: expected 1 to 16", opt.samples);

    // The full-resolution mesh: one Embree geometry per chart with triangles.
    const size_t n = view.chart_count();
    std::vector<stream::ChartTile> tiles(n);
    std::vector<std::unique_ptr<ChartShader>> shaders(n);
    ParallelFor(0, int64_t(n), [&](int64_t c) {
        const std::string path = view.TilePath(uint32_t(c));
        auto& tile = tiles[size_t(c)];
        tile = stream::ReadTile(path, stream::TileParts::Mesh);
        tile.grid = {};  // shading here needs triangles and barycentrics only
        shaders[size_t(c)] = std::make_unique<ChartShader>(
            tile, view.solution.fields[size_t(c)], view.solution.radiosity, view.scene, path,
            view.Seams(uint32_t(c)));
    });
    solve::VisibilityScene vis;
    std::vector<uint32_t> geom_chart;
    std::vector<float> xyz;
    std::vector<uint32_t> idx;
    for (size_t c = 0; c < n; ++c) {
        const auto& tile = tiles[c];
        if (tile.triangles.empty())
            continue;
        xyz.clear();
        idx.clear();
        for (const Vec3f& p : tile.position)
            xyz.insert(xyz.end(), {p.x, p.y, p.z});
        for (const auto& t : tile.triangles)
            idx.insert(idx.end(), t.begin(), t.end());
        const uint32_t id = vis.AddTriangles(xyz, idx, "chart");
        CHECK_EQ(id, geom_chart.size());
        geom_chart.push_back(uint32_t(c));
    }
    vis.Commit();

    RenderedImage img;
    img.width = cam.width;
    img.height = cam.height;
    img.rgb.assign(size_t(cam.width) * size_t(cam.height) * 3, 0.f);
    const int k = opt.samples;
    const size_t per_row = size_t(cam.width) * size_t(k) * size_t(k);
    std::vector<uint64_t> row_hits(size_t(cam.height), 0);
    ProgressStage progress("render", uint64_t(cam.height), "rows");
    ParallelFor(0, cam.height, [&](int64_t py) {
        std::vector<solve::Segment> segs(per_row);
        std::vector<solve::Hit> hits(per_row);
        std::vector<Vec3f> dirs(per_row);
        size_t r = 0;
        for (int px = 0; px < cam.width; ++px)
            for (int sy = 0; sy < k; ++sy)
                for (int sx = 0; sx < k; ++sx, ++r) {
                    dirs[r] = rays.Direction(px, int(py), sx, sy, k);
                    segs[r] =
                        solve::Segment{float(cam.eye.x), float(cam.eye.y), float(cam.eye.z), 0.f,
                                dirs[r].x,        dirs[r].y,        dirs[r].z,        INFINITY};
                }
        vis.Intersect(segs, hits);
        uint64_t count = 0;
        const float weight = 1.f / float(k * k);
        for (int px = 0; px < cam.width; ++px) {
            Vec3f sum{};
            for (int s = 0; s < k * k; ++s) {
                const size_t i = size_t(px) * size_t(k * k) + size_t(s);
                const solve::Hit& h = hits[i];
                if (h.geom_id == solve::kNoHit) {
                    sum += opt.background ? *opt.background : solve::SkyRadiance(view.scene.sky, dirs[i]);
                    continue;
                }
                ++count;
                // The back of a surface is black, as the solver and the reference path
                // tracer have it: light is solved on the side the triangles face.
                if (h.ng_x * dirs[i].x + h.ng_y * dirs[i].y + h.ng_z * dirs[i].z >= 0)
                    continue;
                const ChartShader& sh = *shaders[geom_chart[h.geom_id]];
                const ShadingPoint p = sh.AtTriangle(h.prim_id, 1 - h.u - h.v, h.u, h.v);
                sum += opt.glossy ? sh.Glossy(p, -dirs[i]) : sh.Radiosity(p) / kPi;
            }
            float* out = &img.rgb[(size_t(py) * size_t(cam.width) + size_t(px)) * 3];
            for (int c = 0; c < 3; ++c)
                out[c] = sum[c] * weight;
        }
        row_hits[size_t(py)] = count;
        progress.Add();
    });
    progress.Finish();
    img.rays = uint64_t(per_row) * uint64_t(cam.height);
    for (uint64_t h : row_hits)
        img.hits += h;
    return img;
}

void WriteRenderedImage(const RenderedImage& image, const std::string& path, const ToneMap& tone,
                        io::ExrPixelType exr_type) {
    std::string ext = path == "-" ? ".exr" : std::filesystem::path(path).extension().string();
    for (char& ch : ext)
        ch = char(std::tolower(static_cast<unsigned char>(ch)));
    if (ext == ".exr") {
        io::ExrOptions eo;
        eo.type = exr_type;
        eo.comments = "mebake render: linear radiance (W/m^2/sr) in R G B";
        io::WriteExr(path, image.width, image.height, {"R", "G", "B"}, image.rgb, eo);
        return;
    }
    if (ext != ".png")
        UsageError("{}: expected a .exr or .png file name", path);
    std::vector<uint8_t> bytes(image.rgb.size());
    for (size_t p = 0; p < image.rgb.size() / 3; ++p)
        ToneMapPixel(Vec3f(image.rgb[3 * p], image.rgb[3 * p + 1], image.rgb[3 * p + 2]), tone,
                     &bytes[3 * p]);
    io::WritePng(path, image.width, image.height, 3, bytes);
}

}  // namespace mebake::output
