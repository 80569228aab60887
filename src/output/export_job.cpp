#include "output/export_job.h"

#include "core/error.h"
#include "core/log.h"
#include "core/parallel.h"
#include "core/units.h"
#include "io/byte_stream.h"
#include "output/bake_view.h"
#include "output/export_mesh.h"
#include "output/node_seams.h"
#include "output/seams.h"
#include "output/vertex_colors.h"

#include <chrono>
#include <filesystem>
#include <nlohmann/json.hpp>

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

}  // namespace

void RunExportJob(const ExportJobOptions& c) {
    const auto t0 = Clock::now();
    const std::vector<std::string> outputs = {c.lightmap, c.irradiance, c.mesh, c.vertex_colors,
                                              c.stats};
    int to_stdout = 0, given = 0;
    for (const auto& o : outputs) {
        given += !o.empty();
        to_stdout += o == "-";
    }
    if (given == 0)
        UsageError("nothing to export: give --lightmap, --irradiance, --mesh, --vertex-colors "
                   "or --stats");
    if (to_stdout > 1)
        UsageError("only one output can go to stdout ('-')");

    // Fields are read a chart at a time: memory follows the charts being written.
    BakeView view = OpenBakeView(c.dir, FieldLoading::OnDemand);
    const Atlas atlas = PackAtlas(ChartResolutions(view), c.atlas);
    const uint32_t pages = uint32_t(atlas.pages.size());
    for (uint32_t p = 0; p < pages; ++p) {
        if (!c.lightmap.empty())
            CheckFresh(PagePath(c.lightmap, p, pages), c.force);
        if (!c.irradiance.empty())
            CheckFresh(PagePath(c.irradiance, p, pages), c.force);
    }
    for (const auto& o : {c.mesh, c.vertex_colors, c.stats})
        CheckFresh(o, c.force);
    spdlog::info("{} charts in {} atlas page{} ({} texels, {:.1f}% filled)", view.chart_count(),
                 pages, pages == 1 ? "" : "s", FormatCount(double(atlas.texels())),
                 100 * atlas.fill());

    nlohmann::json j;
    j["charts"] = view.chart_count();
    j["unknown"] = view.solution.radiosity ? "radiosity" : "irradiance";
    nlohmann::json jp = nlohmann::json::array();
    for (const auto& p : atlas.pages)
        jp.push_back({{"width", p.width}, {"height", p.height}});
    j["atlas"] = {{"pages", jp},
                  {"gutter", atlas.gutter},
                  {"texels", atlas.texels()},
                  {"fill", atlas.fill()}};
    j["tone_map"] = {{"exposure", c.maps.tone.exposure}, {"curve", c.tone_curve}};
    nlohmann::json seconds = nlohmann::json::object();

    if (!c.lightmap.empty()) {
        auto t = Clock::now();
        auto files =
            WriteMapPages(view, atlas, c.lightmap, MapContent::Radiosity, c.maps);
        seconds["lightmap"] = Since(t);
        j["lightmap"] = files;
        spdlog::info("light map: {} ({})", fmt::join(files, ", "), FormatSeconds(Since(t)));
    }
    if (!c.irradiance.empty()) {
        auto t = Clock::now();
        auto files =
            WriteMapPages(view, atlas, c.irradiance, MapContent::Irradiance, c.maps);
        seconds["irradiance"] = Since(t);
        j["irradiance"] = files;
        spdlog::info("vector irradiance: {} ({})", fmt::join(files, ", "), FormatSeconds(Since(t)));
    }
    if (!c.mesh.empty()) {
        auto t = Clock::now();
        MeshExportOptions me;
        me.glb_mode = c.glb_mode;
        me.tone = c.maps.tone;
        auto st = WriteBakedMesh(view, atlas, c.mesh, me);
        seconds["mesh"] = Since(t);
        j["mesh"] = {{"path", c.mesh}, {"vertices", st.vertices}, {"triangles", st.triangles}};
        spdlog::info("mesh: {} ({} vertices, {} triangles, {})", c.mesh,
                     FormatCount(double(st.vertices)), FormatCount(double(st.triangles)),
                     FormatSeconds(Since(t)));
    }
    if (!c.vertex_colors.empty()) {
        auto t = Clock::now();
        VertexColorOptions vo;
        vo.tone = c.maps.tone;
        vo.float_colors = c.float_colors;
        auto st = WriteVertexColors(view, c.vertex_colors, vo);
        seconds["vertex_colors"] = Since(t);
        j["vertex_colors"] = {
            {"path", c.vertex_colors},     {"vertices", st.vertices},
            {"referenced", st.referenced}, {"shared", st.shared},
            {"faces", st.faces},           {"hole_fill_faces_dropped", st.hole_fill_faces}};
        spdlog::info("vertex colours: {} ({} vertices, {} faces, {})", c.vertex_colors,
                     FormatCount(double(st.vertices)), FormatCount(double(st.faces)),
                     FormatSeconds(Since(t)));
    }
    if (!c.stats.empty()) {
        auto t = Clock::now();
        const SeamStats s = MeasureSeams(view);
        seconds["seams"] = Since(t);
        j["seams"] = {{"edges", s.seam_edges},
                      {"open_edges", s.open_edges},
                      {"fold_edges", s.fold_edges},
                      {"samples", s.samples},
                      {"mean_relative_jump", s.mean_relative},
                      {"p95_relative_jump", s.p95_relative},
                      {"max_relative_jump", s.max_relative},
                      {"mean_level", s.mean_level},
                      {"worst_edge", {s.worst_v0, s.worst_v1}},
                      {"display_jump", {{"mean", s.display.mean},
                                        {"p95", s.display.p95},
                                        {"max", s.display.max}}}};
        const NodeSeamStats ns = MeasureNodeSeams(view);
        j["node_seams"] = {{"edges", ns.edges},
                           {"samples", ns.display.samples},
                           {"display_jump", {{"mean", ns.display.mean},
                                             {"p95", ns.display.p95},
                                             {"max", ns.display.max}}}};
        spdlog::info(
            "seams: {} edges ({} on folds not measured), relative jump mean {:.3g}, p95 {:.3g}, "
            "max {:.3g}",
            s.seam_edges, s.fold_edges, s.mean_relative, s.p95_relative, s.max_relative);
        spdlog::info("display jumps (tone-mapped sRGB, 0..1): chart borders mean {:.4f}, p95 "
                     "{:.4f}, max {:.4f}; node borders ({} edges) mean {:.4f}, p95 {:.4f}, max "
                     "{:.4f}",
                     s.display.mean, s.display.p95, s.display.max, ns.edges, ns.display.mean,
                     ns.display.p95, ns.display.max);
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
    BakeView view = OpenBakeView(c.dir);
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
    spdlog::info("rendered {}x{} from ({:.4g}, {:.4g}, {:.4g}): {} rays, {:.1f}% hit, {}", c.width, c.height,
                 e.x, e.y, e.z, FormatCount(double(img.rays)),
                 img.rays ? 100.0 * double(img.hits) / double(img.rays) : 0.0,
                 FormatSeconds(Since(t0)));
}

}  // namespace mebake::output
