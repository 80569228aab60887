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

namespace {

// A camera sample's closest hit so far: the chart (kNoHit: none yet), its triangle and
// barycentrics, and whether the ray meets the triangle's back.
struct SampleHit {
    float t = INFINITY;
    float u = 0, v = 0;
    uint32_t chart = solve::kNoHit, prim = 0;
    bool back = false;
};

// Runs of consecutive charts with at most `max_triangles` triangles in all (a larger chart
// alone), in chart order: each becomes one Embree scene in turn.
std::vector<std::pair<uint32_t, uint32_t>> ChartGroups(const stream::Manifest& m,
                                                       uint64_t max_triangles) {
    std::vector<std::pair<uint32_t, uint32_t>> groups;
    uint64_t in_group = 0;
    for (uint32_t c = 0; c < m.charts.size(); ++c) {
        const uint64_t n = m.charts[c].triangles;
        if (groups.empty() || (in_group + n > max_triangles && in_group > 0)) {
            groups.push_back({c, c});
            in_group = 0;
        }
        groups.back().second = c + 1;
        in_group += n;
    }
    return groups;
}

// Pass 1 for rows [y0, y1): every sample's closest hit over the charts of `group`, traced
// against one Embree scene of that group; a hit replaces the one found in earlier groups
// only when it is nearer (a tie keeps the earlier: the lower chart id).
void TraceGroup(const BakeView& view, std::pair<uint32_t, uint32_t> group,
                const PinholeRays& rays, const Camera& cam, int k, int y0, int y1,
                std::vector<SampleHit>* hits) {
    solve::VisibilityScene vis;
    std::vector<uint32_t> geom_chart;
    std::vector<uint32_t> charts(group.second - group.first);
    for (uint32_t c = group.first; c < group.second; ++c)
        charts[c - group.first] = c;
    std::vector<float> xyz;
    std::vector<uint32_t> idx;
    // Tiles read in parallel batches, added in chart order (the geometry ids are the same
    // whatever the thread count); Embree copies them, so one batch is in memory at a time.
    ForEachTile(
        view, charts, stream::TileParts::Mesh, [](uint32_t, stream::ChartTile&) { return 0; },
        [&](uint32_t c, stream::ChartTile& tile, int) {
            if (tile.triangles.empty())
                return;
            xyz.clear();
            idx.clear();
            for (const Vec3f& p : tile.position)
                xyz.insert(xyz.end(), {p.x, p.y, p.z});
            for (const auto& t : tile.triangles)
                idx.insert(idx.end(), t.begin(), t.end());
            const uint32_t id = vis.AddTriangles(xyz, idx, "chart");
            CHECK_EQ(id, geom_chart.size());
            geom_chart.push_back(c);
        });
    std::vector<float>().swap(xyz);
    std::vector<uint32_t>().swap(idx);
    if (geom_chart.empty())
        return;
    vis.Commit();
    const size_t per_row = size_t(cam.width) * size_t(k) * size_t(k);
    ParallelFor(y0, y1, [&](int64_t py) {
        std::vector<solve::Segment> segs(per_row);
        std::vector<solve::Hit> found(per_row);
        SampleHit* row = &(*hits)[size_t(py - y0) * per_row];
        size_t r = 0;
        for (int px = 0; px < cam.width; ++px)
            for (int sy = 0; sy < k; ++sy)
                for (int sx = 0; sx < k; ++sx, ++r) {
                    const Vec3f d = rays.Direction(px, int(py), sx, sy, k);
                    segs[r] = solve::Segment{float(cam.eye.x), float(cam.eye.y), float(cam.eye.z),
                                             0.f, d.x, d.y, d.z, row[r].t};
                }
        vis.Intersect(segs, found);
        r = 0;
        for (int px = 0; px < cam.width; ++px)
            for (int s = 0; s < k * k; ++s, ++r) {
                const solve::Hit& h = found[r];
                if (h.geom_id == solve::kNoHit || !(h.t < row[r].t))
                    continue;
                const solve::Segment& g = segs[r];
                row[r] = SampleHit{h.t, h.u, h.v, geom_chart[h.geom_id], h.prim_id,
                                   h.ng_x * g.dx + h.ng_y * g.dy + h.ng_z * g.dz >= 0};
            }
    });
}

// Pass 2: each hit sample's radiance, chart by chart (one tile and shader per chart in
// flight per worker); samples that miss or meet a back are left alone.
void ShadeSamples(const BakeView& view, const RenderOptions& opt, const PinholeRays& rays,
                  int y0, const std::vector<SampleHit>& hits, std::vector<Vec3f>* radiance) {
    const Camera& cam = opt.camera;
    const int k = opt.samples;
    const size_t per_row = size_t(cam.width) * size_t(k) * size_t(k);
    // Samples by chart (counting sort, in sample order within a chart).
    const size_t n = view.chart_count();
    std::vector<uint32_t> first(n + 1, 0);
    for (const SampleHit& h : hits)
        if (h.chart != solve::kNoHit && !h.back)
            ++first[h.chart + 1];
    for (size_t c = 0; c < n; ++c)
        first[c + 1] += first[c];
    std::vector<uint32_t> order(first[n]), fill(first.begin(), first.end() - 1);
    for (size_t i = 0; i < hits.size(); ++i)
        if (hits[i].chart != solve::kNoHit && !hits[i].back)
            order[fill[hits[i].chart]++] = uint32_t(i);
    std::vector<uint32_t> charts;
    for (uint32_t c = 0; c < n; ++c)
        if (first[c + 1] > first[c])
            charts.push_back(c);
    ForEachTile(
        view, charts, stream::TileParts::Mesh,
        [&](uint32_t c, stream::ChartTile& tile) {
            tile.grid = {};  // shading here needs triangles and barycentrics only
            const std::shared_ptr<const ChartField> field = view.Field(c);
            const ChartShader sh(tile, *field, view.solution.radiosity, view.scene,
                                 view.TilePath(c), view.Seams(c));
            for (uint32_t j = first[c]; j < first[c + 1]; ++j) {
                const uint32_t i = order[j];
                const SampleHit& h = hits[i];
                const ShadingPoint p = sh.AtTriangle(h.prim, 1 - h.u - h.v, h.u, h.v);
                if (opt.glossy) {
                    const size_t in_row = i % per_row, s = in_row % size_t(k * k);
                    const Vec3f d = rays.Direction(int(in_row / size_t(k * k)),
                                                   y0 + int(i / per_row), int(s) % k,
                                                   int(s) / k, k);
                    (*radiance)[i] = sh.Glossy(p, -d);
                } else {
                    (*radiance)[i] = sh.Radiosity(p) / kPi;
                }
            }
            return 0;
        },
        [](uint32_t, stream::ChartTile&, int) {});
}

// Camera samples traced and shaded at once: 1M (36 MB of hits and radiance); taller
// images go in bands of rows, each band tracing every group again.
constexpr size_t kBandSamples = size_t(1) << 20;

}  // namespace

RenderedImage Render(const BakeView& view, const RenderOptions& opt) {
    const Camera& cam = opt.camera;
    const PinholeRays rays(cam);  // validates the camera
    if (opt.samples < 1 || opt.samples > 16)
        UsageError("--samples {}: expected 1 to 16", opt.samples);
    if (opt.group_triangles == 0)
        UsageError("render: group_triangles must be at least 1");

    RenderedImage img;
    img.width = cam.width;
    img.height = cam.height;
    img.rgb.assign(size_t(cam.width) * size_t(cam.height) * 3, 0.f);
    const int k = opt.samples;
    const size_t per_row = size_t(cam.width) * size_t(k) * size_t(k);
    const int band = int(std::clamp<size_t>(kBandSamples / per_row, 1, size_t(cam.height)));
    const auto groups = ChartGroups(view.manifest, opt.group_triangles);
    ProgressStage progress("render", uint64_t(cam.height) * (groups.size() + 1), "rows");
    std::vector<SampleHit> hits;
    std::vector<Vec3f> radiance;
    for (int y0 = 0; y0 < cam.height; y0 += band) {
        const int y1 = std::min(cam.height, y0 + band);
        hits.assign(size_t(y1 - y0) * per_row, SampleHit{});
        for (const auto& g : groups) {
            TraceGroup(view, g, rays, cam, k, y0, y1, &hits);
            progress.Add(uint64_t(y1 - y0));
        }
        radiance.assign(hits.size(), Vec3f{});
        ShadeSamples(view, opt, rays, y0, hits, &radiance);
        // Each pixel sums its samples in sample order, as one pass over them would.
        const float weight = 1.f / float(k * k);
        for (int py = y0; py < y1; ++py) {
            for (int px = 0; px < cam.width; ++px) {
                Vec3f sum{};
                for (int s = 0; s < k * k; ++s) {
                    const size_t i = size_t(py - y0) * per_row + size_t(px) * size_t(k * k) +
                                     size_t(s);
                    const SampleHit& h = hits[i];
                    if (h.chart == solve::kNoHit) {
                        sum += opt.background
                                   ? *opt.background
                                   : solve::SkyRadiance(view.scene.sky,
                                                        rays.Direction(px, py, s % k, s / k, k));
                        continue;
                    }
                    ++img.hits;
                    // The back of a surface is black, as the solver and the reference path
                    // tracer have it: light is solved on the side the triangles face.
                    if (h.back)
                        continue;
                    sum += radiance[i];
                }
                float* out = &img.rgb[(size_t(py) * size_t(cam.width) + size_t(px)) * 3];
                for (int c = 0; c < 3; ++c)
                    out[c] = sum[c] * weight;
            }
        }
        progress.Add(uint64_t(y1 - y0));
    }
    progress.Finish();
    img.rays = uint64_t(per_row) * uint64_t(cam.height);
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
