#include "output/export_job.h"

#include "core/error.h"
#include "core/log.h"
#include "core/memory_budget.h"
#include "core/parallel.h"
#include "core/progress.h"
#include "core/temp_file.h"
#include "core/units.h"
#include "io/byte_stream.h"
#include "output/bake_view.h"
#include "output/export_mesh.h"
#include "output/node_seams.h"
#include "output/seam_graph.h"
#include "output/seams.h"
#include "output/vertex_colors.h"

#include <atomic>
#include <chrono>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <unistd.h>

namespace mebake::output {

namespace {

using Clock = std::chrono::steady_clock;

double Since(Clock::time_point t) {
    return std::chrono::duration<double>(Clock::now() - t).count();
}

// Nothing the user already had is overwritten unless asked.
void CheckFresh(const std::string& path, bool force) {
    if (path.empty() || path == "-" || force)
        return;
    if (std::filesystem::exists(path))
        UsageError("{} exists; use --force to overwrite it", path);
}

void WriteJson(const std::string& path, const nlohmann::json& j) {
    auto out = io::OutputStream::Open(path);
    out->Write(j.dump(2) + "\n");
    out->Commit();
}

// Throws Error(Usage) when nothing is asked for or two outputs go to stdout.
void CheckRequested(const ExportJobOptions& c) {
    int to_stdout = 0, given = 0;
    for (const auto& o : {c.lightmap, c.irradiance, c.mesh, c.vertex_colors, c.stats}) {
        given += !o.empty();
        to_stdout += o == "-";
    }
    if (given == 0)
        UsageError("nothing to export: give --lightmap, --irradiance, --mesh, --vertex-colors "
                   "or --stats");
    if (to_stdout > 1)
        UsageError("only one output can go to stdout ('-')");
    if (!c.lightmap_png.empty() && c.lightmap.empty())
        UsageError("{}: a light-map PNG companion needs the .exr light map", c.lightmap_png);
}

// Throws Error(Usage) when an output exists and force is not set (before anything is
// written).
void CheckFreshOutputs(const ExportJobOptions& c, const Atlas& atlas) {
    const uint32_t pages = uint32_t(atlas.pages.size());
    for (uint32_t p = 0; p < pages; ++p) {
        if (!c.lightmap.empty())
            CheckFresh(PagePath(c.lightmap, p, pages), c.force);
        if (!c.lightmap_png.empty())
            CheckFresh(PagePath(c.lightmap_png, p, pages), c.force);
        if (!c.irradiance.empty())
            CheckFresh(PagePath(c.irradiance, p, pages), c.force);
    }
    for (const auto& o : {c.mesh, c.vertex_colors, c.stats})
        CheckFresh(o, c.force);
}

nlohmann::json AtlasJson(const Atlas& atlas) {
    nlohmann::json jp = nlohmann::json::array();
    for (const auto& p : atlas.pages)
        jp.push_back({{"width", p.width}, {"height", p.height}});
    return {{"pages", jp},
            {"gutter", atlas.gutter},
            {"texels", atlas.texels()},
            {"fill", atlas.fill()}};
}

nlohmann::json JumpJson(const JumpSummary& s) {
    return {{"mean", s.mean}, {"p95", s.p95}, {"max", s.max}};
}

// The seam metric across chart borders and node borders (seams.h, node_seams.h).
struct AllSeams {
    SeamStats chart;
    NodeSeamStats node;
};

AllSeams MeasureAllSeams(const BakeView& view) {
    return {MeasureSeams(view), MeasureNodeSeams(view)};
}

void ReportAllSeams(const AllSeams& all, nlohmann::json* j) {
    const SeamStats& s = all.chart;
    const NodeSeamStats& ns = all.node;
    (*j)["seams"] = {{"edges", s.seam_edges},
                     {"open_edges", s.open_edges},
                     {"fold_edges", s.fold_edges},
                     {"samples", s.samples},
                     {"mean_relative_jump", s.mean_relative},
                     {"p95_relative_jump", s.p95_relative},
                     {"max_relative_jump", s.max_relative},
                     {"mean_level", s.mean_level},
                     {"worst_edge", {s.worst_v0, s.worst_v1}},
                     {"display_jump", JumpJson(s.display)}};
    (*j)["node_seams"] = {{"edges", ns.edges},
                          {"samples", ns.display.samples},
                          {"display_jump", JumpJson(ns.display)}};
    spdlog::info(
        "seams: {} edges ({} on folds not measured), relative jump mean {:.3g}, p95 {:.3g}, "
        "max {:.3g}",
        s.seam_edges, s.fold_edges, s.mean_relative, s.p95_relative, s.max_relative);
    spdlog::info("display jumps (tone-mapped sRGB, 0..1): chart borders mean {:.4f}, p95 {:.4f}, "
                 "max {:.4f}; node borders ({} edges) mean {:.4f}, p95 {:.4f}, max {:.4f}",
                 s.display.mean, s.display.p95, s.display.max, ns.edges, ns.display.mean,
                 ns.display.p95, ns.display.max);
}

// The light map's PNG pages for a .glb when the user asked for no PNG: temporary files,
// removed when the export ends (or fails).
struct TemporaryPngPages {
    std::string path;  // PagePath's base; empty: none
    uint32_t pages = 0;
    ~TemporaryPngPages() {
        std::error_code ec;
        for (uint32_t p = 0; !path.empty() && p < pages; ++p)
            std::filesystem::remove(PagePath(path, p, pages), ec);
    }
};

}  // namespace

void RunExportJob(const ExportJobOptions& c) {
    const auto t0 = Clock::now();
    CheckRequested(c);
    // Fields are read a chart at a time: memory follows the charts being written.
    BakeView view = OpenBakeView(c.dir, FieldLoading::OnDemand,
                                 c.stitch ? SeamStitching::On : SeamStitching::Off,
                                 size_t(MemoryBudget(c.memory).StitchCache()));
    const Atlas atlas = PackAtlas(ChartResolutions(view), c.atlas);
    CheckFreshOutputs(c, atlas);
    spdlog::info("{} charts in {} atlas page{} ({} texels, {:.1f}% filled)", view.chart_count(),
                 atlas.pages.size(), atlas.pages.size() == 1 ? "" : "s",
                 FormatCount(double(atlas.texels())), 100 * atlas.fill());

    nlohmann::json j;
    j["charts"] = view.chart_count();
    j["unknown"] = view.solution.radiosity ? "radiosity" : "irradiance";
    j["atlas"] = AtlasJson(atlas);
    j["tone_map"] = {{"exposure", c.maps.tone.exposure}, {"curve", c.tone_curve}};
    nlohmann::json seconds = nlohmann::json::object();
    // Counted per output written (each goes through every chart): the light-map and mesh
    // writers report nothing finer yet.
    uint64_t outputs = 0;
    for (const auto* o : {&c.lightmap, &c.irradiance, &c.mesh, &c.vertex_colors, &c.stats})
        outputs += o->empty() ? 0 : 1;
    ProgressStage progress("export", outputs * view.chart_count(), "charts");

    // A .glb beside an .exr light map embeds the light map's PNG pages written from the
    // EXR's texels (the same bytes it would shade itself), so the light map is shaded and
    // stitched once; without --lightmap-png they go to temporary files.
    std::string png = c.lightmap_png;
    TemporaryPngPages temporary;
    if (png.empty() && !c.lightmap.empty() && c.lightmap != "-" &&
        Extension(c.lightmap) == ".exr" && c.mesh != "-" && Extension(c.mesh) == ".glb") {
        static std::atomic<int> serial{0};
        temporary.path = fmt::format("{}/mebake-{}-{}-lightmap.png", TemporaryDirectory(),
                                     getpid(), serial++);
        temporary.pages = uint32_t(atlas.pages.size());
        png = temporary.path;
    }

    // The seam metric and the vertex colours write no file the other outputs read, nor read
    // one they write: they run beside the light map as tasks, so their own parallel loops
    // fill the cores that the light map leaves idle (the stitch's three colour channels on
    // two threads, the EXR's ZIP stream beside the shorter PNG one, the .glb). Their numbers
    // and log lines are taken after the light map and the mesh, in the order they had.
    AllSeams seams;
    double seams_seconds = 0, colors_seconds = 0;
    VertexColorStats colors;
    TaskGroup beside;
    if (!c.stats.empty())
        beside.Run([&] {
            const auto t = Clock::now();
            seams = MeasureAllSeams(view);
            seams_seconds = Since(t);
        });
    if (!c.vertex_colors.empty())
        beside.Run([&] {
            const auto t = Clock::now();
            VertexColorOptions vo;
            vo.tone = c.maps.tone;
            vo.float_colors = c.float_colors;
            vo.cache_bytes = size_t(MemoryBudget(c.memory).ExportCache());
            colors = WriteVertexColors(view, c.vertex_colors, vo);
            colors_seconds = Since(t);
        });

    struct Map {
        const std::string& path;
        MapContent content;
        const char *key, *what;
    };
    for (const Map& m :
         {Map{c.lightmap, MapContent::Radiosity, "lightmap", "light map"},
          Map{c.irradiance, MapContent::Irradiance, "irradiance", "vector irradiance"}}) {
        if (m.path.empty())
            continue;
        const auto t = Clock::now();
        MapWriteOptions mo = c.maps;
        mo.stitch_memory = MemoryBudget(c.memory).StitchRows();
        if (m.content == MapContent::Radiosity)
            mo.png_path = png;
        auto files = WriteMapPages(view, atlas, m.path, m.content, mo);
        if (m.content == MapContent::Radiosity && !temporary.path.empty())
            files.resize(atlas.pages.size());  // the temporary PNG pages are not outputs
        seconds[m.key] = Since(t);
        j[m.key] = files;
        progress.Add(view.chart_count());
        spdlog::info("{}: {} ({})", m.what, fmt::join(files, ", "), FormatSeconds(Since(t)));
    }
    if (!c.mesh.empty()) {
        const auto t = Clock::now();
        MeshExportOptions me;
        me.glb_mode = c.glb_mode;
        me.tone = c.maps.tone;
        for (uint32_t p = 0; !png.empty() && p < atlas.pages.size(); ++p)
            me.light_map_pngs.push_back(PagePath(png, p, uint32_t(atlas.pages.size())));
        const auto st = WriteBakedMesh(view, atlas, c.mesh, me);
        seconds["mesh"] = Since(t);
        progress.Add(view.chart_count());
        j["mesh"] = {{"path", c.mesh}, {"vertices", st.vertices}, {"triangles", st.triangles}};
        spdlog::info("mesh: {} ({} vertices, {} triangles, {})", c.mesh,
                     FormatCount(double(st.vertices)), FormatCount(double(st.triangles)),
                     FormatSeconds(Since(t)));
    }
    beside.Wait();
    if (!c.vertex_colors.empty()) {
        const VertexColorStats& st = colors;
        seconds["vertex_colors"] = colors_seconds;
        progress.Add(view.chart_count());
        j["vertex_colors"] = {
            {"path", c.vertex_colors},     {"vertices", st.vertices},
            {"referenced", st.referenced}, {"shared", st.shared},
            {"faces", st.faces},           {"hole_fill_faces_dropped", st.hole_fill_faces}};
        spdlog::info("vertex colours: {} ({} vertices, {} faces, {})", c.vertex_colors,
                     FormatCount(double(st.vertices)), FormatCount(double(st.faces)),
                     FormatSeconds(colors_seconds));
    }
    if (!c.stats.empty()) {
        ReportAllSeams(seams, &j);
        seconds["seams"] = seams_seconds;
        progress.Add(view.chart_count());
    }
    progress.Finish();
    if (view.stitcher) {
        const uint64_t hits = view.stitcher->hits(), misses = view.stitcher->misses();
        j["stitch_cache"] = {{"hits", hits}, {"misses", misses}};
        spdlog::info("stitch data: charts' sampled borders {} times from the cache, {} sampled "
                     "({:.1f}% hits)",
                     hits, misses, 100.0 * double(hits) / double(std::max<uint64_t>(1, hits + misses)));
    }
    seconds["total"] = Since(t0);
    j["seconds"] = seconds;
    j["peak_rss_bytes"] = PeakRssBytes();
    if (!c.stats.empty())
        WriteJson(c.stats, j);
}

void RunRenderJob(const RenderJobOptions& c) {
    const auto t0 = Clock::now();
    CheckFresh(c.output, c.force);
    // Fields are read a chart at a time while the hit samples are shaded (render.h).
    BakeView view = OpenBakeView(c.dir, FieldLoading::OnDemand,
                                 c.stitch ? SeamStitching::On : SeamStitching::Off);
    RenderOptions ro;
    ro.camera = DefaultCamera(view, c.width, c.height, c.fov);
    if (c.eye)
        ro.camera.eye = *c.eye;
    if (c.target)
        ro.camera.target = *c.target;
    if (c.up)
        ro.camera.up = *c.up;
    ro.glossy = c.glossy;
    ro.samples = c.samples;
    if (c.background)
        ro.background = *c.background;
    const RenderedImage img = Render(view, ro);
    WriteRenderedImage(img, c.output, c.tone, c.exr_type);
    const Vec3d& e = ro.camera.eye;
    spdlog::info("rendered {}x{} from ({:.4g}, {:.4g}, {:.4g}): {} rays, {:.1f}% hit, {}", c.width,
                 c.height, e.x, e.y, e.z, FormatCount(double(img.rays)),
                 img.rays ? 100.0 * double(img.hits) / double(img.rays) : 0.0,
                 FormatSeconds(Since(t0)));
}

}  // namespace mebake::output
