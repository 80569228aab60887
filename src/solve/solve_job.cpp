#include "solve/solve_job.h"

#include "core/check.h"
#include "core/checksum.h"
#include "core/error.h"
#include "core/log.h"
#include "core/memory_budget.h"
#include "core/parallel.h"
#include "core/progress.h"
#include "core/units.h"
#include "io/byte_stream.h"
#include "io/chunk_file.h"
#include "solve/checkpoint.h"
#include "solve/field_pool.h"
#include "solve/geometry_cache.h"
#include "solve/paged_visibility.h"
#include "solve/polygon_light.h"
#include "solve/rays.h"
#include "solve/solve_eta.h"
#include "solve/solution.h"
#include "solve/visibility.h"
#include "stream/bake_dir.h"
#include "stream/proxy_cluster.h"
#include "stream/tile.h"

#include <algorithm>
#include <bit>
#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <memory>
#include <mutex>
#include <optional>
#include <nlohmann/json.hpp>
#include <signal.h>
#include <sstream>

namespace mebake::solve {

namespace fs = std::filesystem;

namespace {

// Emissive surfaces with at most this many triangles become polygon lights (exact
// direct light); larger ones shoot their emission through the solver.
constexpr size_t kMaxEmissiveTriangles = 256;

// The visibility mesh's Embree scene as ingest sized it: 56 B per triangle of the full
// mesh, 100 B of a clustered proxy (stream/proxy_cluster.h).
uint64_t VisibilitySceneBytes(const stream::Manifest& m) {
    return m.proxy_triangles * (m.proxy_cell_size > 0 ? stream::kEmbreeBytesPerProxyTriangle
                                                      : stream::kEmbreeBytesPerTriangle);
}

// Pages the visibility mesh when VisibilityIsPaged says so, or when forced. Resident pieces
// take a quarter of the cap, pieces a quarter of that each: Embree stays well under its cap
// with a piece pinned per thread and one being built, and the solve's peak RSS under
// --memory (16M sphere at 128M: 104 MiB; with half the cap resident, 136).
void ConfigurePaging(const SolveJobOptions& opt, const stream::Manifest& m,
                     const MemoryBudget& budget, VisibilityScene& vis) {
    const uint64_t share = budget.EmbreeLimit() / 2;
    if (opt.paged_visibility == 0 && !VisibilityIsPaged(m, budget))
        return;
    const uint64_t scene_bytes = VisibilitySceneBytes(m);
    PagingOptions po;
    po.cache_bytes = opt.paged_cache > 0 ? opt.paged_cache : share / 2;
    po.piece_triangles = opt.paged_visibility > 0
                             ? opt.paged_visibility
                             : uint32_t(std::max<uint64_t>(share / 8 / kPieceBytesPerTriangle, 1));
    spdlog::info("visibility paged: {} triangles (~{} of Embree scene, share {}) in pieces of at "
                 "most {}, {} resident",
                 FormatCount(double(m.proxy_triangles)), FormatBytes(scene_bytes),
                 FormatBytes(share), FormatCount(double(po.piece_triangles)),
                 FormatBytes(po.cache_bytes));
    vis.EnablePaging(po);
}

nlohmann::json VisibilityJson(const VisibilityScene& vis) {
    nlohmann::json j;
    j["paged"] = vis.paged() != nullptr;
    j["triangles"] = vis.triangle_count();
    if (!vis.paged())
        return j;
    const PagingStats st = vis.paged()->stats();
    j["pieces"] = st.pieces;
    j["largest_piece"] = st.largest_piece;
    j["segments"] = st.segments;
    j["requests"] = st.requests;
    j["hits"] = st.hits;
    j["hit_rate"] = st.requests ? double(st.hits) / double(st.requests) : 1.0;
    j["loads"] = st.loads;
    j["rentals"] = st.rentals;
    j["built_triangles"] = st.built_triangles;
    j["rays"] = st.rays;
    j["rays_per_build"] =
        st.loads + st.rentals ? double(st.rays) / double(st.loads + st.rentals) : 0.0;
    j["rays_per_segment"] = st.segments ? double(st.rays) / double(st.segments) : 0.0;
    return j;
}

void LoadProxy(const std::string& dir, VisibilityScene& vis) {
    io::ChunkReader r(stream::ProxyPath(dir), io::Tag("PRXY"), 1, 1);
    for (auto [tag, index] : r.List()) {
        if (tag != io::Tag("PPOS"))
            continue;
        auto pos = r.ReadArray<float>(io::Tag("PPOS"), index);
        auto tri = r.ReadArray<uint32_t>(io::Tag("PTRI"), index);
        if (!tri.empty())
            vis.AddTriangles(pos, tri, "proxy");
    }
    vis.Commit();
}

// SIGINT / SIGTERM during the solve: the handler only sets the flag; the solver stops at
// the next batch boundary (or skips the rest of the direct pass) and a checkpoint is
// written. SA_RESETHAND: a second signal kills at once.
std::atomic<bool> g_stop{false};
void OnStopSignal(int) {
    g_stop.store(true);
}

class StopSignals {
public:
    StopSignals() {
        g_stop.store(false);
        struct sigaction sa {};
        sa.sa_handler = OnStopSignal;
        sa.sa_flags = SA_RESETHAND;
        sigemptyset(&sa.sa_mask);
        ::sigaction(SIGINT, &sa, &old_int_);
        ::sigaction(SIGTERM, &sa, &old_term_);
    }
    ~StopSignals() {
        ::sigaction(SIGINT, &old_int_, nullptr);
        ::sigaction(SIGTERM, &old_term_, nullptr);
    }

private:
    struct sigaction old_int_ {
    }, old_term_{};
};

// Resident memory at a stage boundary (where memory goes, issue 7).
void LogMemory(const char* stage) {
    spdlog::debug("memory after {}: {} resident, {} peak", stage, FormatBytes(CurrentRssBytes()),
                  FormatBytes(PeakRssBytes()));
}

// Canonical text of everything besides the tiles that the solution depends on.
std::string SettingsText(const Scene& scene, const std::string& scene_file) {
    const SolverSettings& s = scene.solver;
    std::string scene_hash = "default";
    if (!scene_file.empty()) {
        std::ifstream f(scene_file, std::ios::binary);
        std::stringstream text;
        text << f.rdbuf();
        const std::string bytes = text.str();
        scene_hash = fmt::format("{:08x}", Crc32(bytes.data(), bytes.size()));
    }
    return fmt::format(
        "checkpoint {} order {} tolerance {:.17g} bounces {} stop {:.17g} time {:.17g} sky {} "
        "light {} radiosity {} scene {}",
        kCheckpointVersion, s.order, s.tolerance, s.max_bounces, s.stop_fraction, s.time_limit,
        s.sky_directions, s.light_samples, s.radiosity ? 1 : 0, scene_hash) +
        (s.multi_emitter_simplify ? " multi-emitter simplify" : "") +
        (s.unshot_tail ? " unshot tail" : "");
}

using Clock = std::chrono::steady_clock;

double Since(Clock::time_point t) {
    return std::chrono::duration<double>(Clock::now() - t).count();
}

// The scene the solve uses: the scene file's (or the inputs' materials and the default
// rig), with the command line's solver settings on top.
Scene PrepareScene(const stream::Manifest& m, const SolveJobOptions& opt) {
    Scene scene = LoadScene(m, opt.scene_file);
    if (opt.order >= 0)
        scene.solver.order = opt.order;
    if (opt.tolerance > 0)
        scene.solver.tolerance = opt.tolerance;
    if (opt.max_bounces >= 0)
        scene.solver.max_bounces = opt.max_bounces;
    if (opt.time_limit > 0)
        scene.solver.time_limit = opt.time_limit;
    if (opt.stop_fraction >= 0)
        scene.solver.stop_fraction = opt.stop_fraction;
    if (!opt.unshot_tail.empty())
        scene.solver.unshot_tail = opt.unshot_tail == "on";
    scene.solver.radiosity = opt.radiosity;
    if (!opt.multi_emitter.empty())
        scene.solver.multi_emitter_simplify = opt.multi_emitter == "simplify";
    spdlog::info("scene: {}", scene.description);
    return scene;
}

// What --force, --resume and an existing checkpoint or solution mean: true when a finished
// solution made from the same tiles and settings (`key`) is kept as it is.
bool KeepFinishedSolution(const SolveJobOptions& opt, uint64_t key) {
    if (opt.force) {
        RemoveCheckpoints(opt.dir);
        return false;
    }
    if (HasCheckpoint(opt.dir) && !opt.resume)
        UsageError("{} holds the checkpoint of an interrupted solve; pass --resume to continue "
                   "it, or --force to start over",
                   opt.dir);
    if (!opt.resume || HasCheckpoint(opt.dir) || !fs::exists(SolutionPath(opt.dir)))
        return false;
    const uint64_t had = ReadSolutionKey(SolutionPath(opt.dir));
    if (had != key)
        UsageError("{} was solved from other tiles or settings (order, tolerance, bounces, "
                   "scene); pass --force to solve again",
                   SolutionPath(opt.dir));
    try {
        ReadSolution(SolutionPath(opt.dir));  // every chunk's checksum
        spdlog::info("{} is already solved with these settings; kept", opt.dir);
        return true;
    } catch (const Error& e) {
        if (e.kind() != ErrorKind::Corrupt)
            throw;
        spdlog::warn("{}; solving again", e.what());
        return false;
    }
}

// Every chart's geometry pyramid, into `cache` (or into memory when null), tiles read a
// batch at a time.
void ReadGeometry(const std::string& dir, GeometryCache* cache, std::vector<SolveChart>* charts) {
    const size_t batch = size_t(std::max(1, 2 * MaxThreads()));
    std::vector<stream::ChartTile> tiles;
    for (size_t first = 0; first < charts->size(); first += batch) {
        tiles.assign(std::min(batch, charts->size() - first), {});
        ParallelFor(0, int64_t(tiles.size()), [&](int64_t k) {
            tiles[size_t(k)] =
                stream::ReadTile(stream::TilePath(dir, uint32_t(first) + uint32_t(k)),
                                 stream::TileParts::GeometryImage);
        });
        for (size_t k = 0; k < tiles.size(); ++k) {
            stream::ChartTile& tile = tiles[k];
            SolveChart& sc = (*charts)[first + k];
            if (cache)
                CHECK_EQ(cache->Add(tile.geometry), first + k);
            else
                sc.geometry = GeometryPyramid(std::move(tile.geometry));
            sc.scale = tile.meta.scale;
            int level = 0;
            while ((1u << level) < tile.meta.resolution)
                ++level;
            sc.max_level = level;
            // A power of two or 0 (ReadTile checks it).
            const uint32_t er = tile.meta.emitter_resolution;
            sc.emitter_level = er ? std::countr_zero(er) : -1;
        }
    }
    if (cache)
        for (uint32_t c = 0; c < charts->size(); ++c)
            (*charts)[c].geometry = cache->View(c);
}

// Charts' geometry pyramids, in a memory-mapped file whose resident part stays under the
// budget's share beyond the pinned charts (geometry_cache.h): a pass over the charts
// faults evicted pyramids back from the page cache, which costs far less than the
// pyramids' memory. Without room on disk for the file, the pyramids stay in memory (the
// same bytes, so the same solution); the cache is then null.
std::unique_ptr<GeometryCache> LoadCharts(const std::string& dir, const MemoryBudget& budget,
                                          std::vector<SolveChart>* charts) {
    std::unique_ptr<GeometryCache> geometry;
    try {
        geometry = std::make_unique<GeometryCache>(dir + "/solve", budget.GeometryPyramids());
        ReadGeometry(dir, geometry.get(), charts);
    } catch (const Error& e) {
        if (e.kind() != ErrorKind::Io)
            throw;
        spdlog::warn("{}; the geometry pyramids stay in memory", e.what());
        geometry.reset();
        ReadGeometry(dir, nullptr, charts);
    }
    LogMemory("geometry pyramids loaded");
    return geometry;
}

// The coefficient pools in a memory-mapped file under the budget's share (field_pool.h);
// null (the fields stay in memory, the same values) when the file cannot be made.
std::unique_ptr<FieldPool> MakeFieldPool(const std::string& dir, const MemoryBudget& budget,
                                         size_t charts) {
    try {
        return std::make_unique<FieldPool>(dir + "/solve", charts, budget.CoefficientPools());
    } catch (const Error& e) {
        if (e.kind() != ErrorKind::Io)
            throw;
        spdlog::warn("{}; the coefficient pools stay in memory", e.what());
        return nullptr;
    }
}

// Small emissive surfaces become exact polygon lights of the scene; returns true when they
// are too large for that and must shoot their emission through the solver.
bool AddEmissiveLights(const std::string& dir, const stream::Manifest& m, Scene* scene) {
    bool any_emissive = false;
    for (const auto& mats : scene->per_input)
        for (const auto& mat : mats)
            any_emissive |= mat.emissive();
    if (!any_emissive)
        return false;
    std::vector<PolygonLight> lights;
    for (uint32_t c = 0; c < m.charts.size() && lights.size() <= kMaxEmissiveTriangles; ++c) {
        auto tile = stream::ReadTile(stream::TilePath(dir, c), stream::TileParts::Mesh);
        for (size_t t = 0; t < tile.triangles.size(); ++t) {
            const Material& mat = scene->MaterialOf(tile.material[t]);
            if (!mat.emissive())
                continue;
            PolygonLight pl;
            for (uint32_t v : tile.triangles[t])
                pl.vertices.push_back(Vec3d(tile.position[v]));
            pl.radiance = Vec3d(mat.emission);
            if (PolygonArea(pl.vertices) > 0)
                lights.push_back(pl);
        }
    }
    if (lights.size() > kMaxEmissiveTriangles) {
        spdlog::info("emissive surfaces shoot through the solver");
        return true;
    }
    scene->lights.insert(scene->lights.end(), lights.begin(), lights.end());
    spdlog::info("{} emissive triangles lit as exact polygon lights", lights.size());
    return false;
}

// When to write a checkpoint at a batch boundary: on a stop signal, and every interval
// seconds; a positive interval is stretched to 32 times the last checkpoint's duration,
// so checkpoints never take more than ~3% of the solve (large fields on slow disks).
class CheckpointSchedule {
public:
    CheckpointSchedule(const std::string& dir, double interval, uint64_t key)
        : dir_(dir), interval_(interval), key_(key), last_(Clock::now()) {}

    // The solver's batch hook: false stops the solve (after the checkpoint).
    bool AtBoundary(const Solver& solver, int next_batch) {
        LogMemory(fmt::format("batch {}", next_batch - 1).c_str());
        const bool stop = g_stop.load();
        const double interval =
            interval_ > 0 ? std::max(interval_, 32 * last_duration_) : interval_;
        if (stop || (interval >= 0 && Since(last_) >= interval)) {
            const auto t = Clock::now();
            bytes = WriteCheckpoint(dir_, solver, key_);
            last_ = Clock::now();
            last_duration_ = std::chrono::duration<double>(last_ - t).count();
            seconds += last_duration_;
            ++count;
            spdlog::debug("checkpoint before batch {}: {} in {}", next_batch, FormatBytes(bytes),
                          FormatSeconds(last_duration_));
        }
        return !stop;
    }

    uint64_t count = 0, bytes = 0;
    double seconds = 0;

private:
    std::string dir_;
    double interval_;
    uint64_t key_;
    Clock::time_point last_;
    double last_duration_ = 0;
};

// Runs the solver with progress lines (the direct pass, then the batches with the time
// left from SolveEta); throws Error(Cancelled) with what to do next when a signal stopped it.
void RunSolver(Solver& solver, const SolverSettings& set, size_t charts, const std::string& dir) {
    std::optional<ProgressStage> direct, bounces;
    if (solver.next_batch() < 0)
        direct.emplace("direct", charts, "charts");
    SolveEta eta(set.stop_fraction, set.max_bounces);
    std::mutex mutex;  // the callback runs on worker threads
    Clock::time_point t_batches{};
    solver.Run([&](const Solver::ProgressInfo& p) {
        if (p.batch < 0) {
            direct->Set(p.done);  // from several threads: the stage's counter is atomic
            return;
        }
        std::lock_guard lock(mutex);
        if (direct)
            direct->Finish();
        if (!bounces) {
            bounces.emplace("solve", 0, "gathers");
            t_batches = Clock::now();
        }
        const double secs = Since(t_batches);
        if (p.done == 0) {
            eta.BatchStart(p.batch, p.unshot, secs);
            bounces->SetDetail(fmt::format("batch {} of ~{}, unshot {:.3g}%", p.batch,
                                           std::max(eta.EstimatedBatches(), p.batch + 1),
                                           100 * p.unshot));
            return;
        }
        const double within = p.total ? double(p.done) / double(p.total) : 0;
        bounces->SetEstimate(eta.Fraction(within, secs), eta.Eta(within, secs));
        bounces->Add();
    });
    if (direct)
        direct->Finish();
    if (bounces)
        bounces->Finish();
    LogMemory("solver finished");
    if (solver.stats().stop_reason != "interrupted")
        return;
    if (solver.next_batch() < 0)
        throw Error(ErrorKind::Cancelled,
                    fmt::format("interrupted during the direct pass, before the first "
                                "checkpoint; run `mebake solve --resume {}` to solve again",
                                dir));
    throw Error(ErrorKind::Cancelled,
                fmt::format("interrupted; the solve is saved in {} (next batch {}); continue "
                            "with `mebake solve --resume {}` or the same `mebake bake` command",
                            CheckpointPath(dir), solver.next_batch(), dir));
}

// Export and render shade with the same materials: the scene file is kept beside the
// solution (without one, the inputs' materials and the default rig are rebuilt).
void KeepSceneFile(const SolveJobOptions& opt) {
    const std::string kept = opt.dir + "/solve/scene.json";
    if (!opt.scene_file.empty()) {
        fs::copy_file(opt.scene_file, kept + ".tmp", fs::copy_options::overwrite_existing);
        fs::rename(kept + ".tmp", kept);
    } else {
        fs::remove(kept);
    }
}

nlohmann::json StatsJson(const SolveJobOptions& opt, const SolveOptions& so, size_t charts,
                         const SolveStats& st, double total, const GeometryCache* geometry,
                         const FieldPool* pool, const CheckpointSchedule& checkpoints) {
    nlohmann::json j;
    j["order"] = so.settings.order;
    j["unknown"] = so.settings.radiosity ? "radiosity" : "irradiance";
    j["charts"] = charts;
    j["batches"] = st.batches;
    j["shots"] = st.shots;
    j["rays"] = st.rays;
    for (size_t k = 0; k < st.rays_by_kind.size(); ++k)
        j["rays_by_kind"][kRayKindNames[k]] = st.rays_by_kind[k];
    j["seconds"] = {
        {"total", total}, {"direct", st.seconds_direct}, {"indirect", st.seconds_indirect}};
    j["rays_per_second"] = st.seconds_direct + st.seconds_indirect > 0
                               ? double(st.rays) / (st.seconds_direct + st.seconds_indirect)
                               : 0.0;
    j["cluster_links"] = st.cluster_links;
    j["opened_links"] = st.opened_links;
    j["nodes_per_level"] = st.nodes_per_level;
    j["leaves"] = st.leaves;
    j["field_bytes"] = st.field_bytes;
    j["embree_bytes"] = EmbreePeakMemoryBytes();
    nlohmann::json shares = nlohmann::json::array();
    for (const MemoryShare& sh : MemoryBudget(opt.memory).Shares())
        shares.push_back({{"name", sh.name}, {"bytes", sh.bytes}, {"rule", sh.rule}});
    j["memory"] = {{"budget_bytes", opt.memory}, {"shares", shares}};
    if (geometry) {
        const GeometryCache::Stats gs = geometry->stats();
        j["geometry"] = {{"file_bytes", geometry->file_bytes()},
                         {"budget_bytes", geometry->budget_bytes()},
                         {"peak_resident_bytes", gs.peak_resident_bytes},
                         {"evictions", gs.evictions}};
    }
    if (pool) {
        const FieldPool::Stats ps = pool->stats();
        j["coefficient_pools"] = {{"file_bytes", pool->file_bytes()},
                                  {"budget_bytes", pool->budget_bytes()},
                                  {"peak_resident_bytes", ps.peak_resident_bytes},
                                  {"evictions", ps.evictions}};
    }
    j["peak_rss_bytes"] = PeakRssBytes();
    j["emitted_power"] = st.emitted_power;
    j["unshot_power"] = st.unshot_power;
    j["unshot_tail_gain"] = st.tail_gain;
    j["stop_reason"] = st.stop_reason;
    j["checkpoints"] = {{"count", checkpoints.count},
                        {"bytes", checkpoints.bytes},
                        {"seconds", checkpoints.seconds},
                        {"interval", opt.checkpoint_interval}};
    return j;
}

}  // namespace

SolveStats RunSolveJob(const SolveJobOptions& opt) {
    const auto t0 = Clock::now();
    ThreadLimit limit(opt.threads);
    const MemoryBudget budget(opt.memory);
    // Embree's allocations are capped for this solve (the render and the path tracer that
    // may follow in the same process build other scenes and set no cap).
    const EmbreeMemoryCap embree_cap(budget.EmbreeLimit());
    stream::Manifest m = stream::ReadManifest(opt.dir);
    if (m.state != "ingested")
        UsageError("{}: ingest did not finish (state '{}'); run `mebake ingest` again", opt.dir,
                   m.state);
    Scene scene = PrepareScene(m, opt);
    // What a checkpoint or a finished solution must have been made from to be reused.
    const uint64_t key = SolveKey(opt.dir, m.charts.size(), SettingsText(scene, opt.scene_file));
    fs::create_directories(opt.dir + "/solve");
    if (KeepFinishedSolution(opt, key)) {
        SolveStats done;
        done.stop_reason = "already solved";
        return done;
    }
    std::vector<SolveChart> charts(m.charts.size());
    const std::unique_ptr<GeometryCache> geometry = LoadCharts(opt.dir, budget, &charts);
    const bool shoot_emission = AddEmissiveLights(opt.dir, m, &scene);

    VisibilityOptions vopt;
    vopt.compact = opt.paged_visibility != 0 || VisibilityIsCompact(m, budget);
    spdlog::debug("visibility: Embree's {} BVH", vopt.compact ? "compact" : "full");
    VisibilityScene vis(vopt);
    ConfigurePaging(opt, m, budget, vis);
    LoadProxy(opt.dir, vis);
    LogMemory("visibility scene built");
    const double diag = Length(m.bbox_max - m.bbox_min);
    SolveOptions so;
    so.settings = scene.solver;
    so.scene_size = float(diag);
    so.ray_offset = float(diag * 2e-5 + m.proxy_deviation);
    so.shoot_emission = shoot_emission;
    so.multi_emitter_debug = opt.multi_emitter_debug;
    if (!opt.multi_emitter_debug.empty())
        fs::create_directories(opt.multi_emitter_debug);
    so.cluster_links = scene.solver.cluster_links;
    so.link_tolerance = scene.solver.link_tolerance;
    if (!scene.solver.cluster_links)
        so.link_probes = 0;  // the chart-by-chart solve of before, for comparisons
    spdlog::info("solving {} charts, order M{}, {}, tolerance {}", charts.size(), so.settings.order,
                 so.settings.radiosity ? "radiosity" : "vector irradiance", so.settings.tolerance);

    const std::unique_ptr<FieldPool> pool = MakeFieldPool(opt.dir, budget, charts.size());
    Solver solver(scene, charts, vis, so);
    solver.SetFieldPool(pool.get());
    if (opt.resume && !opt.force) {
        // Fields go to the solver (and its pool) one at a time.
        auto cp = LoadCheckpoint(opt.dir, key, so.settings.order, so.settings.radiosity ? 3 : 9,
                                 charts.size(), [&](uint32_t c, ChartField&& f) {
                                     solver.RestoreField(c, std::move(f));
                                 });
        if (cp) {
            spdlog::info("resuming from {} at batch {}", cp->path, cp->next_batch);
            solver.Restore(cp->reference, cp->next_batch, cp->stats);
        }
    }
    StopSignals signals;
    solver.SetStopFlag(&g_stop);
    CheckpointSchedule checkpoints(opt.dir, opt.checkpoint_interval, key);
    solver.SetBatchHook([&](int next_batch) { return checkpoints.AtBoundary(solver, next_batch); });
    RunSolver(solver, so.settings, charts.size(), opt.dir);
    const SolveStats& st = solver.stats();
    const double total = Since(t0);
    spdlog::info("solved in {} ({} batches, {} rays, {} leaves, stop: {}, unshot {:.3g}%)",
                 FormatSeconds(total), st.batches, FormatCount(double(st.rays)),
                 FormatCount(double(st.leaves)), st.stop_reason,
                 st.emitted_power > 0 ? 100 * st.unshot_power / st.emitted_power : 0.0);

    // The scene file and the statistics go first: solution.bin is the commit point.
    KeepSceneFile(opt);
    nlohmann::json stats =
        StatsJson(opt, so, charts.size(), st, total, geometry.get(), pool.get(), checkpoints);
    stats["visibility"] = VisibilityJson(vis);
    if (vis.paged()) {
        const PagingStats ps = vis.paged()->stats();
        spdlog::info("visibility pieces: {} of {} requests resident ({:.1f}%), {} pieces "
                     "loaded, {} leaf sets rented, {} triangles built, {} rays per build",
                     ps.hits, ps.requests, ps.requests ? 100.0 * ps.hits / ps.requests : 100.0,
                     ps.loads, ps.rentals, FormatCount(double(ps.built_triangles)),
                     ps.loads + ps.rentals ? ps.rays / (ps.loads + ps.rentals) : 0);
    }
    const std::string text = stats.dump(2) + "\n";
    for (const auto& path : {opt.dir + "/solve/stats.json", opt.stats_file}) {
        if (path.empty())
            continue;
        auto out = io::OutputStream::Open(path);
        out->Write(text);
        out->Commit();
    }
    WriteSolution(SolutionPath(opt.dir), solver.fields(), so.settings.radiosity, key);
    RemoveCheckpoints(opt.dir);
    io::SyncDirectory(opt.dir + "/solve");
    if (checkpoints.count)
        spdlog::info("{} checkpoints of {} took {}", checkpoints.count,
                     FormatBytes(checkpoints.bytes), FormatSeconds(checkpoints.seconds));
    return st;
}

bool VisibilityIsPaged(const stream::Manifest& m, const MemoryBudget& budget) {
    return VisibilitySceneBytes(m) > budget.EmbreeLimit() / 2;
}

// Embree's compact BVH (triangles by index) or its full one (vertices copied into the
// leaves): the full one traces the scans' rays in ~12 % less CPU (igea's solve 16.9 -> 14.8
// CPU-s) for 151 B per triangle instead of 116 (Embree's count on igea's 269K; the ingest's
// estimate, VisibilitySceneBytes, says 56: the full scene is taken as 3x it). Full while
// that fits the visibility share (64 MiB whatever the budget from 256M up, so the bytes do
// not follow --memory: up to ~400K triangles), compact beyond and when paged (the pieces
// are sized for it). The two trace a few rays differently (watertight either way).
bool VisibilityIsCompact(const stream::Manifest& m, const MemoryBudget& budget) {
    constexpr uint64_t kFullBvhFactor = 3;
    return VisibilityIsPaged(m, budget) ||
           kFullBvhFactor * VisibilitySceneBytes(m) >
               std::min(budget.Visibility(), budget.EmbreeLimit() / 2);
}

}  // namespace mebake::solve
