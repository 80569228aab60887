// `mebake ingest`, `mebake solve`, `mebake bake` and `mebake info <bake directory>`: option
// parsing, then one call into the libraries (stream/ingest_job.h, solve/solve_job.h,
// output/bake_job.h).
#include "app/commands.h"
#include "app/export_commands.h"
#include "core/error.h"
#include "core/log.h"
#include "core/memory_budget.h"
#include "core/parallel.h"
#include "core/units.h"
#include "output/bake_job.h"
#include "solve/checkpoint.h"
#include "solve/solve_job.h"
#include "stream/bake_dir.h"
#include "stream/ingest_job.h"
#include "stream/up_axis.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>

namespace mebake::app {

uint64_t ParseMemory(const std::string& text) {
    auto bytes = ParseByteSize(text);
    if (!bytes)
        UsageError("--memory '{}': expected a size such as 512M or 2G", text);
    if (*bytes < (uint64_t(64) << 20))
        UsageError("--memory {}: at least 64M is needed", text);
    return *bytes;
}

namespace {

// --up: an axis name, or detected when not given.
std::optional<Vec3d> UpOption(const std::string& name) {
    if (name.empty())
        return std::nullopt;
    const auto axis = stream::ParseAxis(name);
    if (!axis)
        UsageError("--up {}: expected x, y, z, -x, -y or -z", name);
    return axis;
}

stream::IngestOptions ToIngestOptions(const IngestCommand& c) {
    stream::IngestOptions opt;
    opt.inputs = c.inputs;
    opt.format = c.format;
    opt.out_dir = c.output;
    opt.memory = ParseMemory(c.memory);
    opt.threads = c.threads;
    opt.texel_size = c.texel_size;
    opt.lightmap_resolution = c.lightmap_resolution;
    opt.max_distortion = c.max_distortion;
    opt.force = c.force;
    opt.ground = c.ground;
    opt.orient = !c.keep_winding;
    opt.merge_horizon_cells = c.merge_horizon_cells;
    opt.up = UpOption(c.up);
    return opt;
}

}  // namespace

int RunIngest(const IngestCommand& c) {
    const stream::Manifest m = stream::RunIngestJob(ToIngestOptions(c));
    spdlog::info("wrote {} ({} charts); peak memory {}", c.output, m.charts.size(),
                 FormatBytes(PeakRssBytes()));
    return 0;
}

int RunSolve(const SolveCommand& c) {
    solve::SolveJobOptions opt;
    opt.dir = c.dir;
    opt.scene_file = c.scene_file;
    opt.order = c.order;
    opt.tolerance = c.tolerance;
    opt.max_bounces = c.max_bounces;
    opt.time_limit = c.time_limit;
    opt.stop_fraction = c.stop_fraction;
    opt.unshot_tail = c.unshot_tail;
    opt.threads = c.threads;
    opt.memory = ParseMemory(c.memory);
    opt.radiosity = c.unknown == "radiosity";
    opt.multi_emitter = c.multi_emitter;
    opt.multi_emitter_debug = c.multi_emitter_debug;
    opt.stats_file = c.stats_file;
    opt.checkpoint_interval = c.checkpoint_interval;
    opt.resume = c.resume;
    opt.force = c.force;
    opt.paged_visibility = c.paged_visibility;
    if (!c.paged_cache.empty()) {
        const auto bytes = ParseByteSize(c.paged_cache);
        if (!bytes || *bytes == 0)
            UsageError("--paged-cache '{}': expected a size such as 16M", c.paged_cache);
        opt.paged_cache = *bytes;
    }
    auto st = solve::RunSolveJob(opt);
    if (st.stop_reason == "already solved")
        return 0;
    spdlog::info("wrote {}/solve/solution.bin; peak memory {}", c.dir, FormatBytes(PeakRssBytes()));
    return 0;
}

int RunBake(const BakeCommand& c) {
    ThreadLimit limit(c.threads);
    output::BakeJobOptions o;
    o.inputs = c.inputs;
    o.format = c.format;
    o.output = c.output;
    o.scene_file = c.scene_file;
    o.memory = ParseMemory(c.memory);
    o.threads = c.threads;
    o.order = c.order;
    o.tolerance = c.tolerance;
    o.max_bounces = c.max_bounces;
    o.lightmap_resolution = c.lightmap_resolution;
    o.ground = c.ground;
    o.up = UpOption(c.up);
    o.checkpoint_interval = c.checkpoint_interval;
    o.force = c.force;
    output::RunBakeJob(o);
    return 0;
}

int RunBakeInfo(const std::string& dir, bool json) {
    stream::Manifest m = stream::ReadManifest(dir);
    namespace fs = std::filesystem;
    uint64_t tile_bytes = 0, total_bytes = 0;
    for (const auto& e : fs::recursive_directory_iterator(dir)) {
        if (!e.is_regular_file())
            continue;
        total_bytes += e.file_size();
        if (e.path().parent_path().filename() == "tiles")
            tile_bytes += e.file_size();
    }
    double dist_mean = 0, dist_max = 0, virt = 0, area = 0;
    uint32_t res_min = ~0u, res_max = 0;
    for (const auto& c : m.charts) {
        dist_mean += c.area_distortion * c.area;
        dist_max = std::max(dist_max, c.area_distortion);
        virt += c.virtual_fraction;
        area += c.area;
        res_min = std::min(res_min, c.resolution);
        res_max = std::max(res_max, c.resolution);
    }
    const size_t nc = m.charts.size();
    if (json) {
        nlohmann::json j;
        j["state"] = m.state;
        j["inputs"] = nlohmann::json::array();
        for (const auto& in : m.inputs)
            j["inputs"].push_back(
                {{"path", in.path}, {"vertices", in.vertices}, {"triangles", in.triangles}});
        j["vertices"] = m.vertex_count;
        j["triangles"] = m.face_count;
        j["bricks"] = m.brick_count;
        j["up"] = {m.up.x, m.up.y, m.up.z};
        j["orientation"] = {{"components", m.orientation.components},
                            {"flipped", m.orientation.flipped},
                            {"flipped_triangles", m.orientation.flipped_triangles},
                            {"nested_kept", m.orientation.nested_kept}};
        j["charts"] = nc;
        j["texel_size"] = m.texel_size;
        j["distortion_mean"] = area > 0 ? dist_mean / area : 0;
        j["distortion_max"] = dist_max;
        j["virtual_fraction_mean"] = nc ? virt / double(nc) : 0;
        j["proxy_triangles"] = m.proxy_triangles;
        j["proxy_deviation"] = m.proxy_deviation;
        j["tile_bytes"] = tile_bytes;
        j["total_bytes"] = total_bytes;
        j["solved"] = fs::exists(dir + "/solve/solution.bin");
        j["checkpoint"] = solve::HasCheckpoint(dir);
        nlohmann::json shares = nlohmann::json::object();
        for (const MemoryShare& sh : MemoryBudget(m.memory_budget).Shares())
            shares[sh.name] = sh.bytes;
        j["memory"] = {{"budget_bytes", m.memory_budget}, {"shares", shares}};
        std::printf("%s\n", j.dump(2).c_str());
        return 0;
    }
    std::printf("bake directory  %s (%s)\n", dir.c_str(), m.state.c_str());
    for (const auto& in : m.inputs)
        std::printf("input           %s: %llu vertices, %llu triangles\n", in.path.c_str(),
                    (unsigned long long)in.vertices, (unsigned long long)in.triangles);
    std::printf("bounds          (%g, %g, %g) - (%g, %g, %g)\n", m.bbox_min.x, m.bbox_min.y,
                m.bbox_min.z, m.bbox_max.x, m.bbox_max.y, m.bbox_max.z);
    std::printf("surface area    %g\n", m.surface_area);
    std::printf("up              %s\n", stream::AxisName(m.up).c_str());
    std::printf("orientation     %llu component(s), %llu turned outwards (%llu triangles)\n",
                (unsigned long long)m.orientation.components,
                (unsigned long long)m.orientation.flipped,
                (unsigned long long)m.orientation.flipped_triangles);
    std::printf("bricks          %u (up to %llu triangles each)\n", m.brick_count,
                (unsigned long long)m.brick_faces);
    std::printf("charts          %zu, texel size %g, %u..%u texels per side\n", nc, m.texel_size,
                nc ? res_min : 0, res_max);
    std::printf("distortion      mean %.3g%%, worst chart %.3g%% (Jacobian deviation)\n",
                area > 0 ? 100 * dist_mean / area : 0.0, 100 * dist_max);
    std::printf("virtual area    %.3g%% of the squares on average\n",
                nc ? 100 * virt / double(nc) : 0.0);
    std::printf("visibility      %llu triangles, deviation %g\n",
                (unsigned long long)m.proxy_triangles, m.proxy_deviation);
    std::printf("on disk         %s (tiles %s)\n", FormatBytes(total_bytes).c_str(),
                FormatBytes(tile_bytes).c_str());
    std::printf("memory budget   %s at ingest:", FormatBytes(m.memory_budget).c_str());
    for (const MemoryShare& sh : MemoryBudget(m.memory_budget).Shares())
        std::printf(" %s %s", sh.name.c_str(), FormatBytes(sh.bytes).c_str());
    std::printf("\n");
    for (const auto& [k, v] : m.timings)
        std::printf("time %-10s %s\n", k.c_str(), FormatSeconds(v).c_str());
    std::printf("solution        %s\n",
                fs::exists(dir + "/solve/solution.bin") ? "yes" : "not solved yet");
    if (solve::HasCheckpoint(dir))
        std::printf(
            "checkpoint      an interrupted solve: `mebake solve --resume %s` continues it\n",
            dir.c_str());
    return 0;
}

}  // namespace mebake::app
