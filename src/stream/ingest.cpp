#include "stream/ingest.h"

#include "core/error.h"
#include "core/log.h"
#include "core/memory_budget.h"
#include "core/parallel.h"
#include "core/progress.h"
#include "core/units.h"
#include "io/byte_stream.h"
#include "io/chunk_file.h"
#include "io/mesh_format.h"
#include "stream/bricks.h"
#include "stream/chart_builder.h"
#include "stream/ground.h"
#include "stream/orient.h"
#include "stream/proxy_cluster.h"
#include "stream/spill.h"
#include "stream/up_axis.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>

namespace mebake::stream {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

namespace {

double Since(Clock::time_point t) {
    return std::chrono::duration<double>(Clock::now() - t).count();
}

// In-core cost of one brick triangle through repair, charting and parameterization
// (OpenMesh, Eigen factorizations), measured with /usr/bin/time: igea as one brick of 269K
// faces peaks at 94 MiB for the whole process (366 B per face), so 400 B. The budget
// decides from it how many bricks are in core at once, never their size.
constexpr uint64_t kBytesPerBrickTriangle = 400;
// Bricks processed at once (each also runs parallel loops inside): two when two fit the
// budget, else one. Which worker builds a brick changes no byte (each writes only its own
// files), so neither --threads nor --memory changes the tiles.
int BricksInFlight(const MemoryBudget& budget, uint64_t brick_faces) {
    return budget.Bricks() >= 2 * brick_faces * kBytesPerBrickTriangle ? 2 : 1;
}

void PrepareDirectory(const IngestOptions& opt) {
    const std::string& dir = opt.out_dir;
    if (fs::exists(dir)) {
        if (!fs::is_directory(dir))
            UsageError("{} exists and is not a directory", dir);
        if (!fs::is_empty(dir)) {
            if (!opt.force)
                UsageError("{} exists and is not empty; pass --force to replace it", dir);
            if (!IsBakeDirectory(dir))
                UsageError("{} is not a bake directory; refusing to delete it even with --force",
                           dir);
            fs::remove_all(dir);
        }
    }
    fs::create_directories(dir + "/tiles");
    fs::create_directories(dir + "/bricks");
}

std::string BrickProxyPath(const std::string& dir, uint32_t brick) {
    char name[48];
    std::snprintf(name, sizeof(name), "/bricks/b%05u.proxy", brick);
    return dir + name;
}

// Pass 4: the full repaired mesh, one chunk per brick, when its Embree scene fits
// `visibility` bytes (the solve's visibility share, the same for every budget); else a
// vertex-clustered proxy that fits it (proxy_cluster.h), one chunk.
void WriteProxy(const std::string& dir, const std::vector<uint64_t>& brick_triangles,
                uint64_t visibility, Manifest* m) {
    const uint32_t bricks = uint32_t(brick_triangles.size());
    uint64_t total = 0;
    for (uint64_t n : brick_triangles)
        total += n;
    const uint64_t full_budget = FullMeshTriangleBudget(visibility);
    const uint64_t budget = std::max<uint64_t>(ProxyTriangleBudget(visibility), 1);
    const double diag = Length(m->bbox_max - m->bbox_min);
    // Brick parts read: once each for the full mesh, twice per clustering round (ETA for
    // one round; the total grows if another round is needed).
    ProgressStage progress("proxy", total <= full_budget ? bricks : 2 * uint64_t(bricks),
                           "parts");
    std::atomic<uint64_t> reads{0};  // parts may be read ahead on another thread
    // One brick's part of the full repaired mesh, as pass 3 spilled it (empty if none).
    auto source = [&](uint32_t b) {
        if (const uint64_t n = ++reads; n > 2 * uint64_t(bricks))
            progress.SetTotal(n + 2 * uint64_t(bricks) - 1);
        progress.Add();
        ProxyMesh part;
        if (!fs::exists(BrickProxyPath(dir, b)))
            return part;
        io::ChunkReader r(BrickProxyPath(dir, b), io::Tag("PRXP"), 1, 1);
        part.positions = r.ReadArray<Vec3f>(io::Tag("PPOS"));
        part.triangles = r.ReadArray<uint32_t>(io::Tag("PTRI"));
        return part;
    };
    io::ChunkWriter w(ProxyPath(dir), io::Tag("PRXY"), 1);
    if (total <= full_budget) {
        uint64_t tris = 0;
        for (uint32_t b = 0; b < bricks; ++b) {
            const ProxyMesh part = source(b);
            if (part.triangles.empty())
                continue;
            tris += part.triangles.size() / 3;
            w.AddArray(io::Tag("PPOS"), b, part.positions);
            w.AddArray(io::Tag("PTRI"), b, part.triangles);
        }
        w.Finish();
        m->proxy_triangles = tris;
        m->proxy_deviation = 0;
        m->proxy_cell_size = 0;
        spdlog::info("proxy: the full mesh, {} triangles (budget {})", FormatCount(double(tris)),
                     FormatCount(double(full_budget)));
        return;
    }
    ClusterOptions co;
    co.max_triangles = budget;
    co.surface_area = m->surface_area;
    co.bbox_min = m->bbox_min;
    co.bbox_max = m->bbox_max;
    ClusterResult cr = ClusterProxy(bricks, source, co);
    w.AddArray(io::Tag("PPOS"), 0, cr.mesh.positions);
    w.AddArray(io::Tag("PTRI"), 0, cr.mesh.triangles);
    w.Finish();
    m->proxy_triangles = cr.mesh.triangles.size() / 3;
    m->proxy_deviation = cr.deviation;
    m->proxy_cell_size = cr.cell_size;
    spdlog::info(
        "proxy: {} -> {} triangles (budget {}), cell {:.3g}, deviation {:.3g} = {:.3f}% of the "
        "diagonal, {} round(s){}",
        FormatCount(double(cr.input_triangles)), FormatCount(double(m->proxy_triangles)),
        FormatCount(double(budget)), cr.cell_size, cr.deviation,
        diag > 0 ? 100 * cr.deviation / diag : 0.0, cr.rounds,
        cr.uncovered_vertices
            ? fmt::format(", {} vertices in collapsed pieces", cr.uncovered_vertices)
            : std::string());
}

// Passes the reader's batches on to the spill and reports the bytes read so far.
class ProgressSink : public io::MeshSink {
public:
    ProgressSink(io::MeshSink& inner, const io::InputStream& in, ProgressStage& stage,
                 uint64_t before)
        : inner_(inner), in_(in), stage_(stage), before_(before) {}
    void Begin(const io::MeshHeader& header) override { inner_.Begin(header); }
    void Vertices(const io::VertexBatch& b) override {
        inner_.Vertices(b);
        stage_.Set(before_ + in_.offset());
    }
    void Faces(const io::FaceBatch& b) override {
        inner_.Faces(b);
        stage_.Set(before_ + in_.offset());
    }
    void End(const io::MeshSummary& summary) override { inner_.End(summary); }

private:
    io::MeshSink& inner_;
    const io::InputStream& in_;
    ProgressStage& stage_;
    const uint64_t before_;
};

// Bytes of all inputs, or 0 when one of them (stdin) has no known size.
uint64_t InputBytes(const std::vector<std::string>& inputs) {
    uint64_t total = 0;
    for (const auto& path : inputs) {
        std::error_code ec;
        const uint64_t size = path == "-" ? 0 : uint64_t(fs::file_size(path, ec));
        if (path == "-" || ec || size == 0)
            return 0;
        total += size;
    }
    return total;
}

// The scans' up direction (up_axis.h): --up, else detected from the vertices spilled so far.
Vec3d ChooseUp(const IngestOptions& opt, Spill& spill, const std::string& dir) {
    if (opt.up) {
        spdlog::info("up: {} (--up)", AxisName(*opt.up));
        return *opt.up;
    }
    const SpillResult& sr = spill.Finish();  // flushed, so the vertices can be read back
    if (sr.vertex_count == 0)
        return Vec3d(0, 1, 0);
    const UpAxis up = DetectUpAxis(dir, sr.vertex_count, sr.bbox_min, sr.bbox_max,
                                   size_t(4) << 20);
    if (up.detected)
        spdlog::info("up: {} detected (support {:.2f}, next {:.2f}; --up overrides)",
                     AxisName(up.up), up.support, up.runner_up);
    else
        spdlog::info("up: +y, the default (no clear support: best {:.2f}; --up overrides)",
                     up.support);
    return up.up;
}

}  // namespace

Manifest Ingest(const IngestOptions& opt) {
    if (opt.inputs.empty())
        UsageError("no input mesh");
    if (std::count(opt.inputs.begin(), opt.inputs.end(), "-") > 1)
        UsageError("stdin ('-') can be read only once");
    PrepareDirectory(opt);
    const std::string& dir = opt.out_dir;
    ThreadLimit limit(opt.threads);
    Manifest m;
    m.memory_budget = opt.memory;
    const MemoryBudget budget(opt.memory);
    KeepLargeBlocksOutOfTheHeap();
    m.max_distortion = opt.max_distortion;

    // Pass 1: spill.
    auto t0 = Clock::now();
    SpillResult sr;
    double up_seconds = 0;
    {
        // Scoped: the spill's page caches are freed before the passes that follow.
        // Appends only: a few pages per file are enough to write in large blocks.
        Spill spill(dir, budget.SpillCache());
        ProgressStage progress("spill", InputBytes(opt.inputs), "B");
        uint64_t before = 0;
        for (const auto& path : opt.inputs) {
            auto in = io::InputStream::Open(path);
            io::MeshFormat format = io::DetectFormat(*in, path, opt.format);
            spdlog::info("reading {} ({})", in->name(), io::FormatName(format));
            ProgressSink sink(spill.BeginInput(path), *in, progress, before);
            io::ReadMesh(*in, format, sink);
            before += in->offset();
        }
        progress.Finish();
        m.object_bbox_min = spill.result().bbox_min;
        m.object_bbox_max = spill.result().bbox_max;
        const auto t_up = Clock::now();
        m.up = ChooseUp(opt, spill, dir);
        up_seconds = Since(t_up);
        if (opt.ground && spill.result().face_count > 0) {
            WriteGroundPlane(m.object_bbox_min, m.object_bbox_max, m.up,
                             spill.BeginInput(kGroundSource));
            m.ground = true;
        }
        sr = spill.Finish();
    }
    for (const auto& in : sr.inputs) {
        InputRecord r;
        r.path = in.source;
        r.bytes = in.bytes_read;
        r.vertices = in.vertex_count;
        r.triangles = in.face_count;
        r.first_vertex = in.first_vertex;
        r.first_face = in.first_face;
        r.has_colors = in.has_colors;
        r.materials = in.materials;
        r.mtllibs = in.mtllibs;
        m.inputs.push_back(r);
    }
    m.vertex_count = sr.vertex_count;
    m.face_count = sr.face_count;
    m.bbox_min = sr.bbox_min;
    m.bbox_max = sr.bbox_max;
    m.timings.emplace_back("spill", Since(t0));
    m.timings.emplace_back("spill.up", up_seconds);  // of which the up axis (up_axis.h)
    if (sr.face_count == 0)
        InputError({opt.inputs[0]}, "the input has no faces to bake onto");
    spdlog::info("spilled {} vertices, {} triangles in {} (peak memory {})",
                 FormatCount(double(sr.vertex_count)), FormatCount(double(sr.face_count)),
                 FormatSeconds(Since(t0)), FormatBytes(PeakRssBytes()));
    m.state = "spilled";

    // Pass 2: bricks.
    auto t1 = Clock::now();
    BinOptions bopt;
    bopt.max_faces = std::max<uint64_t>(opt.brick_faces, 1);
    // Caches no larger than the files they cache (small meshes need little memory).
    const uint64_t spilled_bytes = sr.vertex_count * 16 + sr.face_count * 16;
    bopt.cache_bytes = std::min<uint64_t>(
        budget.BinningCache(), 4 * spilled_bytes + (uint64_t(4) << 20));
    BrickPlan plan;
    {
        ProgressStage progress("bricks", 2 * sr.face_count, "faces");
        bopt.progress = &progress;
        plan = BinFaces(dir, sr, bopt);
    }
    m.brick_faces = bopt.max_faces;
    m.brick_count = uint32_t(plan.bricks.size());
    m.surface_area = plan.surface_area;
    // The ground takes no light-map resolution from the scans: the texel size follows from
    // their area alone (the atlas grows by the ground's share).
    const double ground_area =
        m.ground ? GroundPlaneArea(m.object_bbox_min, m.object_bbox_max, m.up) : 0.0;
    const double texel_area =
        std::max(plan.surface_area - ground_area, 1e-3 * plan.surface_area);
    m.texel_size = opt.texel_size > 0
                       ? opt.texel_size
                       : std::sqrt(texel_area / (0.5 * double(opt.lightmap_resolution) *
                                                 opt.lightmap_resolution));
    m.timings.emplace_back("bricks", Since(t1));
    uint64_t largest = 0;
    for (const BrickInfo& b : plan.bricks)
        largest = std::max(largest, b.face_count);
    spdlog::info(
        "{} bricks of up to {} triangles (largest {}, mean {}), texel size {:.4g}, in {} (peak "
        "memory {})",
        plan.bricks.size(), FormatCount(double(bopt.max_faces)), FormatCount(double(largest)),
        FormatCount(double(sr.face_count) / double(std::max<size_t>(plan.bricks.size(), 1))),
        m.texel_size, FormatSeconds(Since(t1)), FormatBytes(PeakRssBytes()));

    // Pass 2b: components wound inwards turned outwards (orient.h).
    if (opt.orient) {
        auto t = Clock::now();
        ProgressStage progress("orient", sr.face_count, "faces");
        const OrientReport r = OrientOutwards(dir, plan, sr.bbox_min, sr.bbox_max, &progress);
        progress.Finish();
        m.orientation = {r.components, r.flipped_components, r.flipped_triangles,
                         r.nested_kept};
        m.timings.emplace_back("orient", Since(t));
    }

    // Pass 3: charts, bricks in parallel (each writes only its own files).
    auto t2 = Clock::now();
    ChartBuildOptions copt;
    copt.texel_size = m.texel_size;
    copt.max_distortion = opt.max_distortion;
    copt.merge_horizon_cells = opt.merge_horizon_cells;
    // A brick reads its vertices in ascending id order, each page once: a few pages per
    // file are enough, and a fixed size keeps peak memory independent of the mesh.
    copt.cache_bytes = uint64_t(3) << 20;
    std::vector<BrickResult> results(plan.bricks.size());
    std::vector<uint64_t> proxy_triangles(plan.bricks.size(), 0);
    ProgressStage chart_progress("charts", sr.face_count, "faces");
    // The workers take bricks in turn; each brick writes only its own files and result
    // slot, so which worker runs it does not matter.
    std::atomic<uint32_t> next{0};
    std::atomic<bool> failed{false};
    const uint32_t brick_count = uint32_t(plan.bricks.size());
    const int in_flight = BricksInFlight(budget, bopt.max_faces);
    spdlog::info("{} brick(s) in core at a time", in_flight);
    ParallelFor(0, in_flight, [&](int64_t) {
        for (uint32_t b = next++; b < brick_count && !failed; b = next++) {
            try {
                BrickResult r = BuildBrickCharts(dir, b, copt);
                // The brick's visibility part goes to disk now, so memory does not accumulate.
                io::ChunkWriter w(BrickProxyPath(dir, b), io::Tag("PRXP"), 1);
                w.AddArray(io::Tag("PPOS"), 0, r.proxy_positions);
                w.AddArray(io::Tag("PTRI"), 0, r.proxy_triangles);
                w.Finish();
                proxy_triangles[b] = r.proxy_triangles.size() / 3;
                std::vector<Vec3f>().swap(r.proxy_positions);
                std::vector<uint32_t>().swap(r.proxy_triangles);
                results[b] = std::move(r);
                // The brick's memory back to the system: glibc keeps the freed pages of
                // blocks under the mmap threshold (KeepLargeBlocksOutOfTheHeap, above), and
                // bricks in turn would leave the pages of every earlier brick's holes
                // resident.
                ReturnFreedHeap();
            } catch (...) {
                failed = true;
                throw;
            }
            chart_progress.Add(plan.bricks[b].face_count);
        }
    });
    chart_progress.Finish();
    uint64_t splits = 0, holes = 0;
    std::array<double, kChartStageNames.size()> stage_seconds{};
    for (auto& r : results) {
        for (size_t k = 0; k < stage_seconds.size(); ++k)
            stage_seconds[k] += r.stage_seconds[k];
        for (size_t k = 0; k < r.charts.size(); ++k) {
            uint32_t id = uint32_t(m.charts.size());
            fs::rename(r.tile_files[k], TilePath(dir, id));
            m.charts.push_back(r.charts[k]);
        }
        splits += r.splits;
        holes += r.repair.holes_filled;
    }
    m.timings.emplace_back("charts", Since(t2));
    // Per-stage thread-seconds summed over the bricks (they overlap when threads > 1).
    for (size_t k = 0; k < stage_seconds.size(); ++k)
        m.timings.emplace_back(std::string("charts.") + kChartStageNames[k], stage_seconds[k]);
    spdlog::info("{} charts ({} splits, {} holes filled) in {} (peak memory {})", m.charts.size(),
                 splits, holes, FormatSeconds(Since(t2)), FormatBytes(PeakRssBytes()));

    // Pass 4: the visibility mesh.
    auto t3 = Clock::now();
    WriteProxy(dir, proxy_triangles, opt.visibility_bytes, &m);
    m.timings.emplace_back("proxy", Since(t3));

    // The spill's face list and brick files are not needed any more.
    fs::remove_all(dir + "/bricks");
    fs::remove(Spill::FacesPath(dir));
    fs::remove(OwnersPath(dir));
    m.state = "ingested";
    m.timings.emplace_back("total", Since(t0));
    WriteManifest(dir, m);
    return m;
}

}  // namespace mebake::stream
