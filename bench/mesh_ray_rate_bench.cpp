// The raw Embree occlusion-ray rate on a bake directory's own visibility mesh (proxy.bin,
// the geometry `mebake solve` traces against), for the solver tables' "rays per CPU-s"
// column to be read against the limit on the same geometry:
//
//   build/bench/mesh_ray_rate_bench DIR [rays]
//
// Rays start at random area-weighted points of the mesh, 1e-4 of the bounding diagonal
// above their triangle: "sky" rays go a whole diagonal in uniform directions of the
// triangle's upper hemisphere (long, mostly unoccluded on convex parts), "pairs" join two
// such points (the solver's link and penumbra pattern: many are occluded). Reports rays
// per CPU-second on one thread (Occluded) and on all threads (OccludedParallel).
#include "io/chunk_file.h"
#include "solve/visibility.h"
#include "stream/bake_dir.h"

#include <cmath>
#include <cstdio>
#include <ctime>
#include <random>
#include <string>
#include <vector>

namespace {

using mebake::Vec3f;
using mebake::solve::Segment;
using mebake::solve::VisibilityScene;

double CpuSeconds() {
    timespec t;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}

double WallSeconds() {
    timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}

struct Mesh {
    std::vector<float> p;
    std::vector<uint32_t> t;
};

Vec3f At(const Mesh& m, uint32_t v) {
    return Vec3f(m.p[3 * size_t(v)], m.p[3 * size_t(v) + 1], m.p[3 * size_t(v) + 2]);
}

}  // namespace

int main(int argc, char** argv) {
    if (argc < 2) {
        std::fprintf(stderr, "usage: %s BAKE_DIR [rays]\n", argv[0]);
        return 2;
    }
    const std::string dir = argv[1];
    const size_t n = argc > 2 ? size_t(std::stoull(argv[2])) : size_t(1) << 20;

    // The proxy, as solve_job.cpp loads it (one Embree geometry per brick).
    VisibilityScene scene;
    Mesh all;
    {
        mebake::io::ChunkReader r(mebake::stream::ProxyPath(dir), mebake::io::Tag("PRXY"), 1, 1);
        for (auto [tag, index] : r.List()) {
            if (tag != mebake::io::Tag("PPOS"))
                continue;
            auto pos = r.ReadArray<float>(mebake::io::Tag("PPOS"), index);
            auto tri = r.ReadArray<uint32_t>(mebake::io::Tag("PTRI"), index);
            if (tri.empty())
                continue;
            scene.AddTriangles(pos, tri, "proxy");
            const uint32_t base = uint32_t(all.p.size() / 3);
            all.p.insert(all.p.end(), pos.begin(), pos.end());
            for (uint32_t v : tri)
                all.t.push_back(base + v);
        }
    }
    const double b0 = WallSeconds();
    scene.Commit();
    const double build = WallSeconds() - b0;
    const size_t tris = all.t.size() / 3;
    if (tris == 0) {
        std::fprintf(stderr, "%s: the proxy has no triangles\n", dir.c_str());
        return 1;
    }

    // Area-weighted triangle picks.
    std::vector<double> cdf(tris);
    Vec3f lo = At(all, 0), hi = lo;
    double total = 0;
    for (size_t t = 0; t < tris; ++t) {
        const Vec3f a = At(all, all.t[3 * t]), b = At(all, all.t[3 * t + 1]),
                    c = At(all, all.t[3 * t + 2]);
        total += 0.5 * double(mebake::Length(mebake::Cross(b - a, c - a)));
        cdf[t] = total;
        for (const Vec3f& q : {a, b, c}) {
            lo = Vec3f(std::min(lo.x, q.x), std::min(lo.y, q.y), std::min(lo.z, q.z));
            hi = Vec3f(std::max(hi.x, q.x), std::max(hi.y, q.y), std::max(hi.z, q.z));
        }
    }
    const float diag = mebake::Length(hi - lo);
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> u01(0, 1);
    auto surface_point = [&](Vec3f* p, Vec3f* nrm) {
        const size_t t =
            size_t(std::lower_bound(cdf.begin(), cdf.end(), u01(rng) * total) - cdf.begin());
        const size_t k = std::min(t, tris - 1);
        const Vec3f a = At(all, all.t[3 * k]), b = At(all, all.t[3 * k + 1]),
                    c = At(all, all.t[3 * k + 2]);
        double s = u01(rng), r = u01(rng);
        if (s + r > 1) {
            s = 1 - s;
            r = 1 - r;
        }
        *nrm = mebake::Normalize(mebake::Cross(b - a, c - a));
        *p = a + (b - a) * float(s) + (c - a) * float(r) + *nrm * (1e-4f * diag);
    };

    std::vector<Segment> sky(n), pairs(n);
    for (size_t i = 0; i < n; ++i) {
        Vec3f p, nrm;
        surface_point(&p, &nrm);
        Vec3f d;
        do {
            d = Vec3f(float(2 * u01(rng) - 1), float(2 * u01(rng) - 1), float(2 * u01(rng) - 1));
        } while (mebake::Dot(d, d) > 1 || mebake::Dot(d, d) < 1e-6f);
        d = mebake::Normalize(d);
        if (mebake::Dot(d, nrm) < 0)
            d = d * -1.f;
        sky[i] = {p.x, p.y, p.z, 0, d.x * diag, d.y * diag, d.z * diag, 1};
        Vec3f q, qn;
        surface_point(&q, &qn);
        pairs[i] = {p.x, p.y, p.z, 0, q.x - p.x, q.y - p.y, q.z - p.z, 1};
    }

    std::printf("%s: %zu triangles, BVH build %.2f s wall, %zu rays per set\n", dir.c_str(), tris,
                build, n);
    std::printf("| rays | occluded | 1 thread: rays per CPU-s | all threads: rays per CPU-s | all "
                "threads: rays per wall-s |\n|---|---:|---:|---:|---:|\n");
    std::vector<uint8_t> occ(n);
    for (int set = 0; set < 2; ++set) {
        const auto& segs = set == 0 ? sky : pairs;
        double c0 = CpuSeconds();
        scene.Occluded(segs, occ);
        const double one = double(n) / (CpuSeconds() - c0);
        size_t blocked = 0;
        for (uint8_t o : occ)
            blocked += o;
        c0 = CpuSeconds();
        const double w0 = WallSeconds();
        scene.OccludedParallel(segs, occ);
        const double cpu = CpuSeconds() - c0, wall = WallSeconds() - w0;
        std::printf("| %s | %.0f %% | %.2fM | %.2fM | %.2fM |\n", set == 0 ? "sky" : "pairs",
                    100.0 * double(blocked) / double(n), one * 1e-6, double(n) / cpu * 1e-6,
                    double(n) / wall * 1e-6);
    }
    return 0;
}
