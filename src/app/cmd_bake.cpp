// `mebake ingest`, `mebake solve` and `mebake info <bake directory>`.
#include "app/commands.h"
#include "app/export_commands.h"
#include "core/checksum.h"
#include "core/error.h"
#include "core/log.h"
#include "core/units.h"
#include "io/byte_stream.h"
#include "io/mesh_format.h"
#include "solve/checkpoint.h"
#include "solve/solve_job.h"
#include "stream/bake_dir.h"
#include "stream/ingest.h"

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <fcntl.h>
#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <stdlib.h>
#include <sys/stat.h>
#include <thread>
#include <unistd.h>

namespace mebake::app {

namespace {
uint64_t ParseMemory(const std::string& text) {
    auto bytes = ParseByteSize(text);
    if (!bytes)
        UsageError("--memory '{}': expected a size such as 512M or 2G", text);
    if (*bytes < (uint64_t(64) << 20))
        UsageError("--memory {}: at least 64M is needed", text);
    return *bytes;
}

bool IsRegularFile(const std::string& path) {
    struct stat st {};
    return path != "-" && ::stat(path.c_str(), &st) == 0 && S_ISREG(st.st_mode);
}

// The ingest options that decide the tiles, as the manifest records them.
std::vector<std::pair<std::string, std::string>> IngestOptionsRecord(const IngestCommand& c) {
    return {{"format", c.format ? std::string(io::FormatName(*c.format)) : std::string()},
            {"lightmap_resolution", std::to_string(c.lightmap_resolution)},
            {"max_distortion", fmt::format("{:.17g}", c.max_distortion)},
            {"memory", std::to_string(ParseMemory(c.memory))},
            {"texel_size", fmt::format("{:.17g}", c.texel_size)}};
}

// Throws Error(Usage) unless `path` (a file, or all of stdin) has the recorded identity.
void CheckSameInput(const std::string& path, const stream::InputRecord& rec,
                    const std::string& dir) {
    uint64_t size = 0;
    uint32_t crc = 0;
    stream::HashFile(path, &size, &crc);
    if (size != rec.file_size || crc != rec.crc32)
        UsageError("{} changed since it was ingested into {} (size {} -> {}, CRC-32 {:08x} -> "
                   "{:08x}); pass --force to start over with the new input",
                   path == "-" ? "stdin" : path, dir, rec.file_size, size, rec.crc32, crc);
}

// Stdin passed through a pipe to the ingest on fd 0 by a thread that hashes it on the
// way, so the manifest can record the identity of what was read. Finish() drains what
// the reader left (the identity covers all of stdin) and restores fd 0.
class StdinTee {
public:
    StdinTee() {
        int fds[2];
        orig_ = ::dup(0);
        if (orig_ < 0 || ::pipe(fds) != 0)
            IoError({"<stdin>"}, "cannot set up a pipe: {}", ErrnoString(errno));
        old_pipe_ = std::signal(SIGPIPE, SIG_IGN);  // the reader may stop early
        ::dup2(fds[0], 0);
        ::close(fds[0]);
        state_ = std::make_shared<State>();
        thread_ = std::thread([state = state_, in = orig_, out = fds[1]] {
            std::vector<uint8_t> buf(size_t(1) << 20);
            bool forward = true;
            for (;;) {
                ssize_t n = ::read(in, buf.data(), buf.size());
                if (n < 0 && errno == EINTR)
                    continue;
                if (n <= 0) {
                    state->failed = n < 0;
                    break;
                }
                state->crc = Crc32(buf.data(), size_t(n), state->crc);
                state->size += uint64_t(n);
                for (ssize_t done = 0; forward && done < n;) {
                    ssize_t w = ::write(out, buf.data() + done, size_t(n - done));
                    if (w < 0 && errno == EINTR)
                        continue;
                    if (w < 0)
                        forward = false;  // the reader is gone: keep hashing
                    else
                        done += w;
                }
                if (!forward && state->abandon)
                    break;
            }
            ::close(out);
        });
    }
    ~StdinTee() {
        if (thread_.joinable()) {
            // Error path: stop feeding the reader; the thread stops at its next read.
            state_->abandon = true;
            CloseReader();
            thread_.detach();
        }
    }
    // False when reading stdin failed (the identity is then not recorded).
    bool Finish(uint64_t* size, uint32_t* crc) {
        CloseReader();
        thread_.join();
        ::dup2(orig_, 0);
        ::close(orig_);
        std::signal(SIGPIPE, old_pipe_);
        *size = state_->size;
        *crc = state_->crc;
        return !state_->failed;
    }

private:
    struct State {
        uint64_t size = 0;
        uint32_t crc = 0;
        bool failed = false;
        std::atomic<bool> abandon{false};
    };
    static void CloseReader() {
        int null = ::open("/dev/null", O_RDONLY | O_CLOEXEC);
        if (null >= 0) {
            ::dup2(null, 0);  // closes the pipe's read end: the pump's writes fail now
            ::close(null);
        }
    }
    int orig_ = -1;
    void (*old_pipe_)(int) = SIG_DFL;
    std::shared_ptr<State> state_;
    std::thread thread_;
};

// The reason a finished ingest in `dir` cannot be reused for `c`, or "" when it can.
// Throws Error(Usage) when an input or an option changed: never mixed silently.
std::string CheckIngestReusable(const std::string& dir, const IngestCommand& c) {
    if (!stream::IsBakeDirectory(dir))
        return "ingest did not finish";
    stream::Manifest m = stream::ReadManifest(dir);
    if (m.state != "ingested")
        return "ingest did not finish (state '" + m.state + "')";
    if (m.options.empty())
        return "the bake directory does not record its options";
    if (m.inputs.size() != c.inputs.size())
        UsageError("{} was ingested from {} inputs, not {}; pass --force to start over", dir,
                   m.inputs.size(), c.inputs.size());
    // Everything but stdin first: reading stdin consumes it, so it is checked last, when
    // the only outcomes left are "reuse" and "refuse".
    for (size_t k = 0; k < c.inputs.size(); ++k) {
        const auto& rec = m.inputs[k];
        const std::string& path = c.inputs[k];
        if (rec.path != path)
            UsageError("input {} was {} when {} was ingested; pass --force to start over", k + 1,
                       rec.path, dir);
        if (!rec.hashed)
            return path + " cannot be verified (its identity was not recorded)";
        if (path == "-")
            continue;
        if (!IsRegularFile(path))
            return path + " is not a regular file any more";
        CheckSameInput(path, rec, dir);
    }
    const auto want = IngestOptionsRecord(c);
    for (const auto& [key, value] : want) {
        auto it = std::find_if(m.options.begin(), m.options.end(),
                               [&](const auto& kv) { return kv.first == key; });
        const std::string had = it == m.options.end() ? "(none)" : it->second;
        if (had != value)
            UsageError("{} was ingested with {} {}, this run asks for {}; pass --force to start "
                       "over",
                       dir, key, had, value);
    }
    for (size_t k = 0; k < c.inputs.size(); ++k)
        if (c.inputs[k] == "-")
            CheckSameInput("-", m.inputs[k], dir);
    return "";
}
}  // namespace

int RunIngest(const IngestCommand& c) {
    // Identities of the file inputs, taken before they are read, for resume checks.
    std::vector<stream::InputRecord> ids(c.inputs.size());
    std::unique_ptr<StdinTee> tee;
    for (size_t k = 0; k < c.inputs.size(); ++k) {
        if (c.inputs[k] == "-") {
            tee = std::make_unique<StdinTee>();
        } else if (IsRegularFile(c.inputs[k])) {
            stream::HashFile(c.inputs[k], &ids[k].file_size, &ids[k].crc32);
            ids[k].hashed = true;
        }
    }
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
    auto m = stream::Ingest(opt);
    for (size_t k = 0; k < c.inputs.size(); ++k)
        if (c.inputs[k] == "-")
            ids[k].hashed = tee->Finish(&ids[k].file_size, &ids[k].crc32);
    // A second manifest write adds what resume needs; killed before it, the directory
    // is taken as not ingested and ingest starts over.
    for (size_t k = 0; k < m.inputs.size() && k < ids.size(); ++k) {
        m.inputs[k].hashed = ids[k].hashed;
        m.inputs[k].file_size = ids[k].file_size;
        m.inputs[k].crc32 = ids[k].crc32;
    }
    m.options = IngestOptionsRecord(c);
    stream::WriteManifest(c.output, m);
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
    opt.threads = c.threads;
    opt.memory = ParseMemory(c.memory);
    opt.radiosity = c.unknown == "radiosity";
    opt.stats_file = c.stats_file;
    opt.checkpoint_interval = c.checkpoint_interval;
    opt.resume = c.resume;
    opt.force = c.force;
    auto st = solve::RunSolveJob(opt);
    if (st.stop_reason == "already solved")
        return 0;
    spdlog::info("wrote {}/solve/solution.bin; peak memory {}", c.dir, FormatBytes(PeakRssBytes()));
    return 0;
}

int RunBake(const BakeCommand& c) {
    namespace fs = std::filesystem;
    const bool to_stdout = c.output == "-";
    std::string out_dir = c.output;
    // A directory a bake has written to: it resumes there (docs/resume.md).
    const std::string marker = out_dir + "/.mebake-bake";
    const std::string dir = out_dir + "/scene.mebake";
    bool resuming = false;
    if (to_stdout) {
        char tmpl[] = "/tmp/mebake-bake-XXXXXX";
        if (!::mkdtemp(tmpl))
            IoError({"/tmp"}, "cannot create a temporary directory");
        out_dir = tmpl;
    } else if (fs::exists(out_dir) && !fs::is_empty(out_dir) && !c.force) {
        if (!fs::exists(marker) && !stream::IsBakeDirectory(dir))
            UsageError("{} exists, is not empty and is not the output of `mebake bake`; pass "
                       "--force to replace its outputs",
                       out_dir);
        resuming = true;
    }
    fs::create_directories(out_dir);
    if (!to_stdout && !fs::exists(marker)) {
        auto out = io::OutputStream::Open(marker);
        out->Write("mebake bake output directory: rerunning the same command resumes here\n");
        out->Commit();
    }

    IngestCommand ing;
    ing.inputs = c.inputs;
    ing.format = c.format;
    ing.output = to_stdout ? out_dir + "/scene.mebake" : dir;
    ing.memory = c.memory;
    ing.threads = c.threads;
    ing.lightmap_resolution = c.lightmap_resolution;
    ing.force = true;
    std::string reason = resuming ? CheckIngestReusable(dir, ing) : "new";
    if (reason.empty()) {
        spdlog::info("resuming in {}: ingest is done, inputs and options unchanged", out_dir);
    } else {
        if (resuming)
            spdlog::info("resuming in {}: {}; ingest starts over", out_dir, reason);
        // An ingest killed before its first manifest leaves no manifest: Ingest() refuses
        // to delete such a directory, but it is ours.
        if (!to_stdout && fs::exists(dir) && !stream::IsBakeDirectory(dir))
            fs::remove_all(dir);
        RunIngest(ing);
    }

    SolveCommand sol;
    sol.dir = ing.output;
    sol.scene_file = c.scene_file;
    sol.order = c.order;
    sol.tolerance = c.tolerance;
    sol.max_bounces = c.max_bounces;
    sol.threads = c.threads;
    sol.memory = c.memory;
    sol.checkpoint_interval = c.checkpoint_interval;
    sol.resume = true;
    sol.force = c.force;
    RunSolve(sol);

    ExportCommand exp;
    exp.dir = ing.output;
    exp.threads = c.threads;
    exp.force = true;
    if (to_stdout) {
        exp.vertex_colors = "-";
        RunExport(exp);
        fs::remove_all(out_dir);
        return 0;
    }
    exp.lightmap = out_dir + "/lightmap.exr";
    exp.mesh = out_dir + "/baked.glb";
    exp.vertex_colors = out_dir + "/vertex_colors.ply";
    exp.stats = out_dir + "/stats.json";
    RunExport(exp);
    ExportCommand png = exp;
    png.lightmap = out_dir + "/lightmap.png";
    png.mesh = png.vertex_colors = png.stats = png.irradiance = "";
    RunExport(png);

    RenderCommand ren;
    ren.dir = ing.output;
    ren.output = out_dir + "/render.png";
    ren.threads = c.threads;
    ren.force = true;
    RunRender(ren);
    spdlog::info("baked: {0}/lightmap.exr (and .png), {0}/baked.glb, {0}/vertex_colors.ply, "
                 "{0}/render.png",
                 out_dir);
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
