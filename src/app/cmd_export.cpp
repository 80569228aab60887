// `mebake export` and `mebake render`: option checks and calls into solve/, nothing else.
#include "app/export_commands.h"
#include "core/error.h"
#include "core/log.h"
#include "core/parallel.h"
#include "core/units.h"
#include "io/byte_stream.h"
#include "output/atlas.h"
#include "output/bake_view.h"
#include "output/export_mesh.h"
#include "output/lightmap.h"
#include "output/render.h"
#include "output/seams.h"
#include "output/tonemap.h"
#include "output/vertex_colors.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <numbers>

namespace mebake::app {

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

output::ToneMap ParseTone(double exposure, const std::string& curve) {
    auto c = output::ParseToneCurve(curve);
    if (!c)
        UsageError("--tonemap '{}': expected filmic, reinhard or clamp", curve);
    return output::ToneMap{float(exposure), *c};
}

io::ExrCompression ParseCompression(const std::string& s) {
    if (s == "zip")
        return io::ExrCompression::Zip;
    if (s == "piz")
        return io::ExrCompression::Piz;
    if (s == "none")
        return io::ExrCompression::None;
    UsageError("--compression '{}': expected zip, piz or none", s);
}

Vec3d ToVec3(const std::vector<double>& v, const char* option) {
    if (v.size() != 3)
        UsageError("{}: expected three numbers", option);
    for (double x : v)
        if (!std::isfinite(x))
            UsageError("{}: not a finite number", option);
    return Vec3d(v[0], v[1], v[2]);
}

void WriteJson(const std::string& path, const nlohmann::json& j) {
    auto out = io::OutputStream::Open(path);
    out->Write(j.dump(2) + "\n");
    out->Commit();
}

}  // namespace

int RunExport(const ExportCommand& c) {
    const auto t0 = Clock::now();
    ThreadLimit limit(c.threads);
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
    const output::ToneMap tone = ParseTone(c.exposure, c.tonemap);
    output::MapWriteOptions mo;
    mo.exr_type = c.float_output ? io::ExrPixelType::Float : io::ExrPixelType::Half;
    mo.compression = ParseCompression(c.compression);
    mo.tone = tone;

    // Fields are read a chart at a time: memory follows the charts being written.
    output::BakeView view = output::OpenBakeView(c.dir, output::FieldLoading::OnDemand);
    output::AtlasOptions ao;
    ao.max_size = c.max_atlas;
    ao.gutter = c.gutter;
    ao.power_of_two = !c.npot;
    const output::Atlas atlas = output::PackAtlas(output::ChartResolutions(view), ao);
    const uint32_t pages = uint32_t(atlas.pages.size());
    for (uint32_t p = 0; p < pages; ++p) {
        if (!c.lightmap.empty())
            CheckFresh(output::PagePath(c.lightmap, p, pages), c.force);
        if (!c.irradiance.empty())
            CheckFresh(output::PagePath(c.irradiance, p, pages), c.force);
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
    j["tone_map"] = {{"exposure", tone.exposure}, {"curve", c.tonemap}};
    nlohmann::json seconds = nlohmann::json::object();

    if (!c.lightmap.empty()) {
        auto t = Clock::now();
        auto files =
            output::WriteMapPages(view, atlas, c.lightmap, output::MapContent::Radiosity, mo);
        seconds["lightmap"] = Since(t);
        j["lightmap"] = files;
        spdlog::info("light map: {} ({})", fmt::join(files, ", "), FormatSeconds(Since(t)));
    }
    if (!c.irradiance.empty()) {
        auto t = Clock::now();
        auto files =
            output::WriteMapPages(view, atlas, c.irradiance, output::MapContent::Irradiance, mo);
        seconds["irradiance"] = Since(t);
        j["irradiance"] = files;
        spdlog::info("vector irradiance: {} ({})", fmt::join(files, ", "), FormatSeconds(Since(t)));
    }
    if (!c.mesh.empty()) {
        auto t = Clock::now();
        output::MeshExportOptions me;
        me.glb_mode = c.unlit ? io::GlbLightMapMode::Unlit : io::GlbLightMapMode::Emissive;
        me.tone = tone;
        auto st = output::WriteBakedMesh(view, atlas, c.mesh, me);
        seconds["mesh"] = Since(t);
        j["mesh"] = {{"path", c.mesh}, {"vertices", st.vertices}, {"triangles", st.triangles}};
        spdlog::info("mesh: {} ({} vertices, {} triangles, {})", c.mesh,
                     FormatCount(double(st.vertices)), FormatCount(double(st.triangles)),
                     FormatSeconds(Since(t)));
    }
    if (!c.vertex_colors.empty()) {
        auto t = Clock::now();
        output::VertexColorOptions vo;
        vo.tone = tone;
        vo.float_colors = c.float_output;
        auto st = output::WriteVertexColors(view, c.vertex_colors, vo);
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
        const output::SeamStats s = output::MeasureSeams(view);
        seconds["seams"] = Since(t);
        j["seams"] = {{"edges", s.seam_edges},
                      {"open_edges", s.open_edges},
                      {"fold_edges", s.fold_edges},
                      {"samples", s.samples},
                      {"mean_relative_jump", s.mean_relative},
                      {"p95_relative_jump", s.p95_relative},
                      {"max_relative_jump", s.max_relative},
                      {"mean_level", s.mean_level},
                      {"worst_edge", {s.worst_v0, s.worst_v1}}};
        spdlog::info(
            "seams: {} edges ({} on folds not measured), relative jump mean {:.3g}, p95 {:.3g}, "
            "max {:.3g}",
            s.seam_edges, s.fold_edges, s.mean_relative, s.p95_relative, s.max_relative);
    }
    seconds["total"] = Since(t0);
    j["seconds"] = seconds;
    j["peak_rss_bytes"] = PeakRssBytes();
    if (!c.stats.empty())
        WriteJson(c.stats, j);
    return 0;
}

int RunRender(const RenderCommand& c) {
    const auto t0 = Clock::now();
    ThreadLimit limit(c.threads);
    int w = 0, h = 0;
    {
        char x = 0, extra = 0;
        if (std::sscanf(c.size.c_str(), "%d%c%d%c", &w, &x, &h, &extra) != 3 ||
            (x != 'x' && x != 'X'))
            UsageError("--size '{}': expected WIDTHxHEIGHT, e.g. 800x600", c.size);
    }
    const output::ToneMap tone = ParseTone(c.exposure, c.tonemap);
    CheckFresh(c.output, c.force);
    output::BakeView view = output::OpenBakeView(c.dir);
    output::RenderOptions ro;
    ro.camera = output::DefaultCamera(view, w, h, c.fov);
    if (!c.eye.empty())
        ro.camera.eye = ToVec3(c.eye, "--eye");
    if (!c.target.empty())
        ro.camera.target = ToVec3(c.target, "--target");
    if (!c.up.empty())
        ro.camera.up = ToVec3(c.up, "--up");
    ro.glossy = c.glossy;
    ro.samples = c.samples;
    if (!c.background.empty())
        ro.background = Vec3f(ToVec3(c.background, "--background"));
    const output::RenderedImage img = output::Render(view, ro);
    output::WriteRenderedImage(img, c.output, tone,
                              c.float_output ? io::ExrPixelType::Float : io::ExrPixelType::Half);
    const Vec3d& e = ro.camera.eye;
    spdlog::info("rendered {}x{} from ({:.4g}, {:.4g}, {:.4g}): {} rays, {:.1f}% hit, {}", w, h,
                 e.x, e.y, e.z, FormatCount(double(img.rays)),
                 img.rays ? 100.0 * double(img.hits) / double(img.rays) : 0.0,
                 FormatSeconds(Since(t0)));
    return 0;
}

}  // namespace mebake::app
