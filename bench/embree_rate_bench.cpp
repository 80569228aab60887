// The raw Embree ray rate on this machine: occlusion queries through solve/visibility.h on a
// ~1M-triangle bumpy height field, per trace method, one thread and all threads. Other
// benchmarks compare the solver's visibility cost against these numbers.
//
//   build/bench/embree_rate_bench --benchmark_counters_tabular=true
//
// Recorded 2026-11-22 on the 2-core AMD EPYC VM (AVX-512, Embree 3.13.5, TBB tasking), load
// average ~5-7 from other builds, so rates are per CPU-second; 1.0M triangles, robust +
// compact, medium quality (55 MB, ~0.16 CPU-s build). Occlusion rays per CPU-second:
//   kind 0 long grazing pairs:  stream 0.58-0.66M, packet16 0.65M, packet8 0.62M, single 0.69M
//   kind 1 short hemisphere:    stream 1.27M, packet16 1.07-1.35M, packet8 1.19M, single 1.2M
//   kind 2 node-to-node bundle: stream 3.3M,  packet16 2.2-2.4M,  packet8 2.4M,  single 2.1M
//   2 threads (OccludedParallel): the same per CPU-second (3.2M/cpu-s on bundles); wall-clock
//   rates only reflect the share of the cores the machine gave us.
// The per-ray cost is dominated by cache misses in the 55 MB BVH: the same rays on a
// 1800-triangle field run ~5-10x faster.
#include "core/parallel.h"
#include "solve/visibility.h"

#include <benchmark/benchmark.h>

#include <cmath>
#include <ctime>
#include <memory>
#include <random>
#include <vector>

namespace {

using mebake::solve::BuildQuality;
using mebake::solve::Segment;
using mebake::solve::TraceMethod;
using mebake::solve::VisibilityOptions;
using mebake::solve::VisibilityScene;

constexpr int kGrid = 708;  // 708^2 * 2 = 1.0M triangles

float Height(float x, float y) {
    return 0.05f * std::sin(40 * x) * std::cos(37 * y) + 0.1f * std::sin(7 * x + 3 * y) +
           0.01f * std::sin(300 * x + 200 * y);
}

struct Field {
    std::vector<float> p;
    std::vector<uint32_t> t;
    Field() {
        for (int j = 0; j <= kGrid; ++j) {
            for (int i = 0; i <= kGrid; ++i) {
                const float x = float(i) / kGrid, y = float(j) / kGrid;
                p.insert(p.end(), {x, y, Height(x, y)});
            }
        }
        for (int j = 0; j < kGrid; ++j) {
            for (int i = 0; i < kGrid; ++i) {
                const uint32_t a = uint32_t(j * (kGrid + 1) + i), b = a + 1,
                               c = a + uint32_t(kGrid + 1), d = c + 1;
                t.insert(t.end(), {a, b, d, a, d, c});
            }
        }
    }
};

const Field& GetField() {
    static const Field field;
    return field;
}

// kind 0: surface to surface (random pairs of points 1 cm above the field: long, grazing,
//         incoherent); kind 1: short segments (length 0.05, random upper-hemisphere
//         directions: near-field transfers); kind 2: node-to-node bundles (256 segments
//         between two random 0.02-wide patches, the solver's shooter-to-receiver pattern).
const std::vector<Segment>& Segments(int kind) {
    static std::vector<Segment> segs[3];
    if (segs[kind].empty()) {
        std::mt19937 rng(7 + kind);
        std::uniform_real_distribution<float> u(0, 1);
        segs[kind].resize(1 << 16);
        float px = 0, py = 0, qx = 0, qy = 0;
        for (size_t i = 0; i < segs[kind].size(); ++i) {
            Segment& s = segs[kind][i];
            if (kind == 2 && i % 256 == 0) {
                px = 0.98f * u(rng);
                py = 0.98f * u(rng);
                qx = 0.98f * u(rng);
                qy = 0.98f * u(rng);
            }
            float x0 = u(rng), y0 = u(rng);
            if (kind == 2) {
                x0 = px + 0.02f * x0;
                y0 = py + 0.02f * y0;
            }
            const float z0 = Height(x0, y0) + 0.01f;
            float x1, y1, z1;
            if (kind == 0) {
                x1 = u(rng);
                y1 = u(rng);
                z1 = Height(x1, y1) + 0.01f;
            } else if (kind == 1) {
                const float phi = 6.2831853f * u(rng), ct = u(rng), st = std::sqrt(1 - ct * ct);
                x1 = x0 + 0.05f * st * std::cos(phi);
                y1 = y0 + 0.05f * st * std::sin(phi);
                z1 = z0 + 0.05f * ct;
            } else {
                x1 = qx + 0.02f * u(rng);
                y1 = qy + 0.02f * u(rng);
                z1 = Height(x1, y1) + 0.01f;
            }
            s = {x0, y0, z0, 0, x1 - x0, y1 - y0, z1 - z0, 1};
        }
    }
    return segs[kind];
}

double ProcessCpuSeconds() {
    timespec t;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}

VisibilityScene& Scene(TraceMethod method, bool coherent) {
    static std::unique_ptr<VisibilityScene> scenes[4][2];  // per method and coherent flag
    auto& s = scenes[int(method)][coherent];
    if (!s) {
        VisibilityOptions opt;
        opt.method = method;
        opt.coherent = coherent;
        s = std::make_unique<VisibilityScene>(opt);
        s->AddTriangles(GetField().p, GetField().t);
        s->Commit();
    }
    return *s;
}

// Args: method, segment kind, coherent flag.
void BM_Occluded(benchmark::State& state) {
    const auto method = TraceMethod(state.range(0));
    const auto& segs = Segments(int(state.range(1)));
    VisibilityScene& scene = Scene(method, state.range(2) != 0);
    std::vector<uint8_t> occ(segs.size());
    for (auto _ : state) {
        scene.Occluded(segs, occ);
        benchmark::DoNotOptimize(occ.data());
    }
    int64_t blocked = 0;
    for (uint8_t o : occ)
        blocked += o;
    state.counters["occluded%"] = 100.0 * double(blocked) / double(segs.size());
    state.SetItemsProcessed(int64_t(state.iterations()) * int64_t(segs.size()));
}
BENCHMARK(BM_Occluded)
    ->ArgNames({"method", "kind", "coherent"})
    ->ArgsProduct({{0, 1, 2, 3}, {0, 1, 2}, {0}})
    ->ArgsProduct({{0, 1}, {2}, {1}})
    ->Unit(benchmark::kMillisecond);

// All threads through OccludedParallel (ParallelFor over blocks of 1024 segments); real time.
void BM_OccludedParallel(benchmark::State& state) {
    const auto method = TraceMethod(state.range(0));
    const auto& segs = Segments(int(state.range(1)));
    VisibilityScene& scene = Scene(method, false);
    std::vector<uint8_t> occ(segs.size());
    const double cpu0 = ProcessCpuSeconds();
    for (auto _ : state) {
        scene.OccludedParallel(segs, occ);
        benchmark::DoNotOptimize(occ.data());
    }
    const double cpu = ProcessCpuSeconds() - cpu0;
    state.counters["threads"] = mebake::MaxThreads();
    // Rays per CPU-second over all threads: on a shared machine the wall-clock rate says
    // how many cores we actually got, this says what each core does.
    state.counters["rays/cpu-s"] = double(state.iterations()) * double(segs.size()) / cpu;
    state.SetItemsProcessed(int64_t(state.iterations()) * int64_t(segs.size()));
}
BENCHMARK(BM_OccludedParallel)
    ->ArgNames({"method", "kind"})
    ->ArgsProduct({{0, 1}, {0, 1, 2}})
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

void BM_Build(benchmark::State& state) {
    VisibilityOptions opt;
    opt.quality = BuildQuality(state.range(0));
    opt.compact = state.range(1) != 0;
    int64_t bytes = 0;
    for (auto _ : state) {
        const int64_t before = mebake::solve::EmbreeMemoryBytes();
        VisibilityScene scene(opt);
        scene.AddTriangles(GetField().p, GetField().t);
        scene.Commit();
        bytes = mebake::solve::EmbreeMemoryBytes() - before;
    }
    state.counters["MB"] = double(bytes) / 1e6;
    state.counters["Mtri/s"] =
        benchmark::Counter(double(GetField().t.size() / 3) * double(state.iterations()) * 1e-6,
                           benchmark::Counter::kIsRate);
}
BENCHMARK(BM_Build)
    ->ArgNames({"quality", "compact"})
    ->ArgsProduct({{0, 1, 2}, {0, 1}})
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
