#include "solve/checkpoint.h"

#include "core/checksum.h"
#include "core/error.h"
#include "core/log.h"
#include "io/chunk_file.h"
#include "solve/solution.h"
#include "stream/bake_dir.h"

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fcntl.h>
#include <filesystem>
#include <signal.h>
#include <unistd.h>

namespace mebake::solve {

namespace fs = std::filesystem;
using io::Tag;

namespace {

constexpr uint32_t kKind = Tag("CKPT");

struct Header {
    uint64_t key;
    double reference;
    int32_t next_batch;
    uint32_t order, blocks, charts;
};

// SolveStats' counters, without padding.
struct Counters {
    uint64_t shots, rays;
    double seconds_direct, seconds_indirect, emitted_power, unshot_power;
    int32_t batches, reserved;
    double shot_power;
};

template <typename T>
std::span<const uint8_t> Bytes(const T& t) {
    return {reinterpret_cast<const uint8_t*>(&t), sizeof(T)};
}

template <typename T>
T ReadPod(const io::ChunkReader& r, uint32_t tag) {
    auto b = r.Read(tag);
    T t{};
    if (b.size() != sizeof(T))
        CorruptError({r.path()}, "chunk {} has {} bytes, expected {}", io::TagName(tag), b.size(),
                     sizeof(T));
    std::memcpy(&t, b.data(), sizeof(T));
    return t;
}

// MEBAKE_TEST_KILL_IN_CHECKPOINT=N[,rotate]: which write kills itself, and where.
struct KillHook {
    int write = 0;
    bool rotate = false;
};
KillHook ParseKillHook() {
    KillHook h;
    if (const char* s = std::getenv("MEBAKE_TEST_KILL_IN_CHECKPOINT")) {
        h.write = std::atoi(s);
        h.rotate = std::strstr(s, "rotate") != nullptr;
    }
    return h;
}

void RenameOrThrow(const std::string& from, const std::string& to) {
    if (::rename(from.c_str(), to.c_str()) != 0)
        IoError({to}, "cannot rename {} into place: {}", from, ErrnoString(errno));
}

}  // namespace

std::string CheckpointPath(const std::string& dir) {
    return dir + "/solve/checkpoint.bin";
}
std::string PrevCheckpointPath(const std::string& dir) {
    return dir + "/solve/checkpoint.prev.bin";
}
std::string NextCheckpointPath(const std::string& dir) {
    return dir + "/solve/checkpoint.next.bin";
}

uint64_t SolveKey(const std::string& dir, size_t charts, const std::string& settings) {
    uint64_t h = Fnv1a64(settings.data(), settings.size());
    auto add_header = [&](const std::string& path) {
        int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
        if (fd < 0)
            IoError({path}, "cannot open: {}", ErrnoString(errno));
        uint8_t head[64];
        ssize_t n = ::pread(fd, head, sizeof(head), 0);
        ::close(fd);
        if (n != ssize_t(sizeof(head)))
            CorruptError({path, 0}, "truncated: shorter than its header");
        h = Fnv1a64(head, sizeof(head), h);
    };
    for (size_t c = 0; c < charts; ++c)
        add_header(stream::TilePath(dir, uint32_t(c)));
    add_header(stream::ProxyPath(dir));
    return h == 0 ? 1 : h;  // 0 means "no key" in solution files
}

uint64_t WriteCheckpoint(const std::string& dir, const Solver& solver, uint64_t key) {
    static const KillHook hook = ParseKillHook();
    static int writes = 0;
    const bool kill_here = ++writes == hook.write;

    const auto& fields = solver.fields();
    const std::string next = NextCheckpointPath(dir);
    uint64_t size = 0;
    {
        io::ChunkWriter w(next, kKind, kCheckpointVersion);
        Header h{key,
                 solver.reference(),
                 solver.next_batch(),
                 uint32_t(fields.empty() ? 0 : fields[0].order()),
                 uint32_t(fields.empty() ? 0 : fields[0].blocks()),
                 uint32_t(fields.size())};
        w.Add(Tag("HEAD"), 0, Bytes(h), false);
        const SolveStats& st = solver.stats();
        Counters k{st.shots,         st.rays,         st.seconds_direct, st.seconds_indirect,
                   st.emitted_power, st.unshot_power, st.batches,        0,
                   st.shot_power};
        w.Add(Tag("STAT"), 0, Bytes(k), false);
        w.AddArray(Tag("KEPT"), 0, st.chart_kept);
        w.AddArray(Tag("RECV"), 0, st.chart_received);
        for (uint32_t c = 0; c < fields.size(); ++c) {
            if (kill_here && !hook.rotate && c == fields.size() / 2)
                ::raise(SIGKILL);
            const RegionPin pin = fields[c].Pin();
            w.AddArray(Tag("NODE"), c, PackNodes(fields[c].nodes()));
            w.AddArray(Tag("VALU"), c, fields[c].values());
            w.AddArray(Tag("UNSH"), c, fields[c].unshots());
        }
        w.Finish(true);  // durable under its name before the rotation below
        size = w.bytes_written();
    }
    const std::string cur = CheckpointPath(dir);
    if (fs::exists(cur))
        RenameOrThrow(cur, PrevCheckpointPath(dir));
    if (kill_here && hook.rotate)
        ::raise(SIGKILL);
    RenameOrThrow(next, cur);
    io::SyncDirectory(dir + "/solve");
    return size;
}

Checkpoint ReadCheckpoint(const std::string& path, uint64_t key, int order, int blocks,
                          size_t charts, const FieldSink& sink) {
    io::ChunkReader r(path, kKind, kCheckpointVersion, kCheckpointVersion);
    const auto h = ReadPod<Header>(r, Tag("HEAD"));
    if (h.key != key)
        UsageError("{} was made from other tiles or solver settings than this solve's; rerun "
                   "with the same settings, or pass --force to start the solve over",
                   path);
    const auto k = ReadPod<Counters>(r, Tag("STAT"));
    if (int(h.order) != order || int(h.blocks) != blocks || h.charts != charts)
        CorruptError({path}, "made for order {}, {} blocks, {} charts; this solve has {}, {}, {}",
                     h.order, h.blocks, h.charts, order, blocks, charts);
    if (h.next_batch < 0 || h.next_batch > (1 << 24) || !std::isfinite(h.reference))
        CorruptError({path}, "HEAD chunk is inconsistent");
    Checkpoint cp;
    cp.path = path;
    cp.key = h.key;
    cp.next_batch = h.next_batch;
    cp.reference = h.reference;
    cp.stats.batches = k.batches;
    cp.stats.shots = k.shots;
    cp.stats.rays = k.rays;
    cp.stats.seconds_direct = k.seconds_direct;
    cp.stats.seconds_indirect = k.seconds_indirect;
    cp.stats.emitted_power = k.emitted_power;
    cp.stats.unshot_power = k.unshot_power;
    cp.stats.shot_power = k.shot_power;
    cp.stats.chart_kept = r.ReadArray<double>(Tag("KEPT"));
    cp.stats.chart_received = r.ReadArray<double>(Tag("RECV"));
    for (const auto* v : {&cp.stats.chart_kept, &cp.stats.chart_received})
        if (!v->empty() && v->size() != charts)
            CorruptError({path}, "{} per-chart powers for {} charts", v->size(), charts);
    if (!sink)
        cp.fields.reserve(charts);
    for (uint32_t c = 0; c < charts; ++c) {
        auto nodes = UnpackNodes(r.ReadArray<PackedNode>(Tag("NODE"), c), path, c);
        auto value = r.ReadArray<float>(Tag("VALU"), c);
        auto unshot = r.ReadArray<float>(Tag("UNSH"), c);
        ChartField f(order, blocks);
        const size_t want = nodes.size() * size_t(f.stride());
        if (nodes.empty() || value.size() != want || unshot.size() != want)
            CorruptError({path}, "chart {}: {} / {} coefficients for {} nodes", c, value.size(),
                         unshot.size(), nodes.size());
        for (const auto* v : {&value, &unshot})
            for (float x : *v)
                if (!std::isfinite(x))
                    CorruptError({path}, "chart {}: non-finite coefficient", c);
        f.Assign(std::move(nodes), std::move(value), std::move(unshot));
        if (sink)
            sink(c, std::move(f));
        else
            cp.fields.push_back(std::move(f));
    }
    return cp;
}

std::optional<Checkpoint> LoadCheckpoint(const std::string& dir, uint64_t key, int order,
                                         int blocks, size_t charts, const FieldSink& sink) {
    // With a sink, candidates are only validated (their fields dropped as read).
    const FieldSink validate = [](uint32_t, ChartField&&) {};
    const std::string solve_dir = dir + "/solve";
    if (fs::is_directory(solve_dir)) {
        for (const auto& e : fs::directory_iterator(solve_dir)) {
            const std::string name = e.path().filename().string();
            if (name.rfind(".checkpoint", 0) == 0 && name.find(".tmp-") != std::string::npos)
                fs::remove(e.path());
        }
    }
    std::optional<Checkpoint> best;
    bool damaged = false;
    for (const auto& path :
         {NextCheckpointPath(dir), CheckpointPath(dir), PrevCheckpointPath(dir)}) {
        if (!fs::exists(path))
            continue;
        try {
            Checkpoint cp =
                ReadCheckpoint(path, key, order, blocks, charts, sink ? validate : FieldSink());
            if (!best || cp.next_batch > best->next_batch)
                best = std::move(cp);
        } catch (const Error& e) {
            if (e.kind() == ErrorKind::Usage)
                throw;
            spdlog::warn("checkpoint damaged, skipped: {}", e.what());
            damaged = true;
        }
    }
    if (best && damaged)
        spdlog::warn("falling back to {} (batch {})", best->path, best->next_batch);
    if (!best && damaged)
        spdlog::warn("no usable checkpoint is left: the solve starts over");
    if (best && sink)
        best = ReadCheckpoint(best->path, key, order, blocks, charts, sink);
    return best;
}

bool HasCheckpoint(const std::string& dir) {
    for (const auto& path : {NextCheckpointPath(dir), CheckpointPath(dir), PrevCheckpointPath(dir)})
        if (fs::exists(path))
            return true;
    return false;
}

void RemoveCheckpoints(const std::string& dir) {
    for (const auto& path : {NextCheckpointPath(dir), CheckpointPath(dir), PrevCheckpointPath(dir)})
        fs::remove(path);
}

}  // namespace mebake::solve
