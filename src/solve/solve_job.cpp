#include "solve/solve_job.h"

#include <nlohmann/json.hpp>

#include <chrono>
#include <filesystem>
#include <fstream>

#include "core/error.h"
#include "core/log.h"
#include "core/parallel.h"
#include "core/units.h"
#include "io/byte_stream.h"
#include "io/chunk_file.h"
#include "solve/polygon_light.h"
#include "solve/rays.h"
#include "solve/solution.h"
#include "solve/visibility.h"
#include "stream/bake_dir.h"
#include "stream/tile.h"

namespace mebake::solve {

namespace fs = std::filesystem;

namespace {

// Emissive surfaces with at most this many triangles become polygon lights (exact
// direct light); larger ones shoot their emission through the solver.
constexpr size_t kMaxEmissiveTriangles = 256;

void LoadProxy(const std::string& dir, VisibilityScene& vis) {
    io::ChunkReader r(stream::ProxyPath(dir), io::Tag("PRXY"), 1, 1);
    for (auto [tag, index] : r.List()) {
        if (tag != io::Tag("PPOS")) continue;
        auto pos = r.ReadArray<float>(io::Tag("PPOS"), index);
        auto tri = r.ReadArray<uint32_t>(io::Tag("PTRI"), index);
        if (!tri.empty()) vis.AddTriangles(pos, tri, "proxy");
    }
    vis.Commit();
}

}  // namespace

SolveStats RunSolveJob(const SolveJobOptions& opt) {
    using Clock = std::chrono::steady_clock;
    auto t0 = Clock::now();
    ThreadLimit limit(opt.threads);
    stream::Manifest m = stream::ReadManifest(opt.dir);
    if (m.state != "ingested")
        UsageError("{}: ingest did not finish (state '{}'); run `mebake ingest` again", opt.dir,
                   m.state);
    Scene scene = LoadScene(m, opt.scene_file);
    if (opt.order >= 0) scene.solver.order = opt.order;
    if (opt.tolerance > 0) scene.solver.tolerance = opt.tolerance;
    if (opt.max_bounces >= 0) scene.solver.max_bounces = opt.max_bounces;
    if (opt.time_limit > 0) scene.solver.time_limit = opt.time_limit;
    scene.solver.radiosity = opt.radiosity;
    spdlog::info("scene: {}", scene.description);

    // Charts' geometry images (in memory for now; a tile cache will bound this).
    std::vector<SolveChart> charts(m.charts.size());
    ParallelFor(0, int64_t(charts.size()), [&](int64_t c) {
        auto tile = stream::ReadTile(stream::TilePath(opt.dir, uint32_t(c)),
                                     stream::TileParts::GeometryImage);
        charts[size_t(c)].geometry = std::move(tile.geometry);
        charts[size_t(c)].scale = tile.meta.scale;
        int level = 0;
        while ((1u << level) < tile.meta.resolution) ++level;
        charts[size_t(c)].max_level = level;
    });

    // Small emissive surfaces -> polygon lights.
    bool any_emissive = false;
    for (const auto& mats : scene.per_input)
        for (const auto& mat : mats) any_emissive |= mat.emissive();
    bool shoot_emission = false;
    if (any_emissive) {
        std::vector<PolygonLight> lights;
        for (uint32_t c = 0; c < m.charts.size() && lights.size() <= kMaxEmissiveTriangles; ++c) {
            auto tile = stream::ReadTile(stream::TilePath(opt.dir, c), stream::TileParts::Mesh);
            for (size_t t = 0; t < tile.triangles.size(); ++t) {
                const Material& mat = scene.MaterialOf(tile.material[t]);
                if (!mat.emissive()) continue;
                PolygonLight pl;
                for (uint32_t v : tile.triangles[t]) pl.vertices.push_back(Vec3d(tile.position[v]));
                pl.radiance = Vec3d(mat.emission);
                if (PolygonArea(pl.vertices) > 0) lights.push_back(pl);
            }
        }
        if (lights.size() <= kMaxEmissiveTriangles) {
            scene.lights.insert(scene.lights.end(), lights.begin(), lights.end());
            spdlog::info("{} emissive triangles lit as exact polygon lights", lights.size());
        } else {
            shoot_emission = true;
            spdlog::info("emissive surfaces shoot through the solver");
        }
    }

    VisibilityScene vis;
    LoadProxy(opt.dir, vis);
    const double diag = Length(m.bbox_max - m.bbox_min);
    SolveOptions so;
    so.settings = scene.solver;
    so.scene_size = float(diag);
    so.ray_offset = float(diag * 2e-5 + m.proxy_deviation);
    so.shoot_emission = shoot_emission;
    spdlog::info("solving {} charts, order M{}, {}, tolerance {}", charts.size(), so.settings.order,
                 so.settings.radiosity ? "radiosity" : "vector irradiance", so.settings.tolerance);

    Solver solver(scene, charts, vis, so);
    const bool tty = StderrIsTerminal();
    auto t_run = Clock::now();
    solver.Run([&](int batch, double unshot, uint64_t rays) {
        double secs = std::chrono::duration<double>(Clock::now() - t_run).count();
        if (tty)
            std::fprintf(stderr, "\r  batch %d: unshot %.3g%%, %s rays, %s rays/s   ", batch,
                         unshot * 100, FormatCount(double(rays)).c_str(),
                         FormatCount(secs > 0 ? double(rays) / secs : 0).c_str());
    });
    if (tty) std::fprintf(stderr, "\n");
    const SolveStats& st = solver.stats();
    double total = std::chrono::duration<double>(Clock::now() - t0).count();
    spdlog::info("solved in {} ({} batches, {} rays, {} leaves, stop: {}, unshot {:.3g}%)",
                 FormatSeconds(total), st.batches, FormatCount(double(st.rays)),
                 FormatCount(double(st.leaves)), st.stop_reason,
                 st.emitted_power > 0 ? 100 * st.unshot_power / st.emitted_power : 0.0);

    fs::create_directories(opt.dir + "/solve");
    WriteSolution(SolutionPath(opt.dir), solver.fields(), so.settings.radiosity);
    // Export and render shade with the same materials: keep the scene file beside the
    // solution (without one, the inputs' materials and the default rig are rebuilt).
    const std::string kept = opt.dir + "/solve/scene.json";
    if (!opt.scene_file.empty()) {
        fs::copy_file(opt.scene_file, kept + ".tmp", fs::copy_options::overwrite_existing);
        fs::rename(kept + ".tmp", kept);
    } else {
        fs::remove(kept);
    }

    nlohmann::json j;
    j["order"] = so.settings.order;
    j["unknown"] = so.settings.radiosity ? "radiosity" : "irradiance";
    j["charts"] = charts.size();
    j["batches"] = st.batches;
    j["shots"] = st.shots;
    j["rays"] = st.rays;
    for (size_t k = 0; k < st.rays_by_kind.size(); ++k)
        j["rays_by_kind"][kRayKindNames[k]] = st.rays_by_kind[k];
    j["seconds"] = {{"total", total}, {"direct", st.seconds_direct}, {"indirect", st.seconds_indirect}};
    j["rays_per_second"] = st.seconds_direct + st.seconds_indirect > 0
                               ? double(st.rays) / (st.seconds_direct + st.seconds_indirect)
                               : 0.0;
    j["nodes_per_level"] = st.nodes_per_level;
    j["leaves"] = st.leaves;
    j["field_bytes"] = st.field_bytes;
    j["embree_bytes"] = EmbreePeakMemoryBytes();
    j["peak_rss_bytes"] = PeakRssBytes();
    j["emitted_power"] = st.emitted_power;
    j["unshot_power"] = st.unshot_power;
    j["stop_reason"] = st.stop_reason;
    std::string text = j.dump(2) + "\n";
    for (const auto& path : {opt.dir + "/solve/stats.json", opt.stats_file}) {
        if (path.empty()) continue;
        auto out = io::OutputStream::Open(path);
        out->Write(text);
        out->Commit();
    }
    return st;
}

}  // namespace mebake::solve
