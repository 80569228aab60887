#include "output/bake_job.h"

#include "core/error.h"
#include "core/log.h"
#include "core/parallel.h"
#include "core/units.h"
#include "io/byte_stream.h"
#include "output/export_job.h"
#include "solve/solve_job.h"
#include "stream/bake_dir.h"
#include "stream/ingest_job.h"

#include <filesystem>
#include <stdlib.h>

namespace mebake::output {

namespace {

namespace fs = std::filesystem;

// Prepares the output directory; true when it holds an earlier bake to resume.
bool PrepareOutputDir(const std::string& out_dir, bool force) {
    const std::string marker = out_dir + "/.mebake-bake";
    bool resuming = false;
    if (fs::exists(out_dir) && !fs::is_empty(out_dir) && !force) {
        if (!fs::exists(marker) && !stream::IsBakeDirectory(out_dir + "/scene.mebake"))
            UsageError("{} exists, is not empty and is not the output of `mebake bake`; pass "
                       "--force to replace its outputs",
                       out_dir);
        resuming = true;
    }
    fs::create_directories(out_dir);
    if (!fs::exists(marker)) {
        auto out = io::OutputStream::Open(marker);
        out->Write("mebake bake output directory: rerunning the same command resumes here\n");
        out->Commit();
    }
    return resuming;
}

// Ingests unless a finished ingest in ing.out_dir can be reused.
void IngestOrReuse(const stream::IngestOptions& ing, bool resuming, const std::string& out_dir,
                   bool temporary) {
    const std::string reason = resuming ? stream::CheckIngestReusable(ing) : "new";
    if (reason.empty()) {
        spdlog::info("resuming in {}: ingest is done, inputs and options unchanged", out_dir);
        return;
    }
    if (resuming)
        spdlog::info("resuming in {}: {}; ingest starts over", out_dir, reason);
    // An ingest killed before its first manifest leaves no manifest: Ingest() refuses
    // to delete such a directory, but it is ours.
    if (!temporary && fs::exists(ing.out_dir) && !stream::IsBakeDirectory(ing.out_dir))
        fs::remove_all(ing.out_dir);
    const stream::Manifest m = stream::RunIngestJob(ing);
    spdlog::info("wrote {} ({} charts); peak memory {}", ing.out_dir, m.charts.size(),
                 FormatBytes(PeakRssBytes()));
}

void Solve(const BakeJobOptions& c, const std::string& dir) {
    solve::SolveJobOptions sol;
    sol.dir = dir;
    sol.scene_file = c.scene_file;
    sol.order = c.order;
    sol.tolerance = c.tolerance;
    sol.max_bounces = c.max_bounces;
    sol.threads = c.threads;
    sol.memory = c.memory;
    sol.checkpoint_interval = c.checkpoint_interval;
    sol.resume = true;
    sol.force = c.force;
    const solve::SolveStats st = solve::RunSolveJob(sol);
    if (st.stop_reason != "already solved")
        spdlog::info("wrote {}/solve/solution.bin; peak memory {}", dir,
                     FormatBytes(PeakRssBytes()));
}

// The light map (EXR and PNG), the lit glTF, vertex colours, statistics and a render.
void WriteOutputs(const std::string& dir, const std::string& out_dir, uint64_t memory) {
    ExportJobOptions exp;
    exp.dir = dir;
    exp.memory = memory;
    exp.force = true;
    exp.tone_curve = "filmic";
    exp.lightmap = out_dir + "/lightmap.exr";
    exp.lightmap_png = out_dir + "/lightmap.png";  // and in the .glb: shaded once for all
    exp.mesh = out_dir + "/baked.glb";
    exp.vertex_colors = out_dir + "/vertex_colors.ply";
    exp.stats = out_dir + "/stats.json";
    RenderJobOptions ren;
    ren.dir = dir;
    ren.output = out_dir + "/render.png";
    ren.force = true;
    // The render reads what the export reads and writes a file the export does not read:
    // beside it, its rows fill the cores the export's single streams leave idle (the EXR's
    // ZIP, the .glb).
    TaskGroup beside;
    beside.Run([&] { RunRenderJob(ren); });
    RunExportJob(exp);
    beside.Wait();
}

}  // namespace

void RunBakeJob(const BakeJobOptions& c) {
    const bool to_stdout = c.output == "-";
    std::string out_dir = c.output;
    bool resuming = false;
    if (to_stdout) {
        char tmpl[] = "/tmp/mebake-bake-XXXXXX";
        if (!::mkdtemp(tmpl))
            IoError({"/tmp"}, "cannot create a temporary directory");
        out_dir = tmpl;
    } else {
        resuming = PrepareOutputDir(out_dir, c.force);
    }
    stream::IngestOptions ing;
    ing.inputs = c.inputs;
    ing.format = c.format;
    ing.out_dir = out_dir + "/scene.mebake";
    ing.memory = c.memory;
    ing.threads = c.threads;
    ing.lightmap_resolution = c.lightmap_resolution;
    ing.ground = c.ground;
    ing.up = c.up;
    ing.force = true;
    IngestOrReuse(ing, resuming, out_dir, to_stdout);
    Solve(c, ing.out_dir);
    if (to_stdout) {
        ExportJobOptions exp;
        exp.dir = ing.out_dir;
        exp.force = true;
        exp.tone_curve = "filmic";
        exp.vertex_colors = "-";
        exp.memory = c.memory;
        RunExportJob(exp);
        fs::remove_all(out_dir);
        return;
    }
    WriteOutputs(ing.out_dir, out_dir, c.memory);
    spdlog::info("baked: {0}/lightmap.exr (and .png), {0}/baked.glb, {0}/vertex_colors.ply, "
                 "{0}/render.png",
                 out_dir);
}

}  // namespace mebake::output
