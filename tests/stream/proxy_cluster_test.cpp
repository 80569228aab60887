// The clustered visibility proxy (stream/proxy_cluster.h): it stays under the budget, a
// closed sphere split into parts gives a closed proxy (no cracks at the part borders),
// the recorded deviation bounds the distance both ways on a brute-force check, the result
// does not depend on the order of the parts or the thread count, and through ingest: a small budget
// simplifies with the same bytes for 1 and 2 threads, a large one keeps the full mesh.
#include "stream/proxy_cluster.h"

#include "core/parallel.h"
#include "io/chunk_file.h"
#include "stream/ingest.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <string>
#include <tuple>
#include <vector>

namespace mebake::stream {
namespace {

namespace fs = std::filesystem;

// A subdivided icosahedron on the unit sphere: closed, manifold, 20 * 4^level triangles.
ProxyMesh Icosphere(int level) {
    const float t = (1.0f + std::sqrt(5.0f)) / 2;
    ProxyMesh m;
    m.positions = {{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                   {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
    m.triangles = {0, 11, 5,  0, 5,  1, 0, 1, 7, 0, 7,  10, 0, 10, 11, 1, 5, 9, 5, 11,
                   4, 11, 10, 2, 10, 7, 6, 7, 1, 8, 3,  9,  4, 3,  4,  2, 3, 2, 6, 3,
                   6, 8,  3,  8, 9,  4, 9, 5, 2, 4, 11, 6,  2, 10, 8,  6, 7, 9, 8, 1};
    for (auto& p : m.positions)
        p = Normalize(p);
    for (int l = 0; l < level; ++l) {
        std::map<std::pair<uint32_t, uint32_t>, uint32_t> mid;
        auto midpoint = [&](uint32_t a, uint32_t b) {
            auto key = std::minmax(a, b);
            auto it = mid.find(key);
            if (it != mid.end())
                return it->second;
            m.positions.push_back(Normalize(m.positions[a] + m.positions[b]));
            uint32_t v = uint32_t(m.positions.size() - 1);
            mid[key] = v;
            return v;
        };
        std::vector<uint32_t> next;
        for (size_t i = 0; i < m.triangles.size(); i += 3) {
            uint32_t a = m.triangles[i], b = m.triangles[i + 1], c = m.triangles[i + 2];
            uint32_t ab = midpoint(a, b), bc = midpoint(b, c), ca = midpoint(c, a);
            next.insert(next.end(), {a, ab, ca, b, bc, ab, c, ca, bc, ab, bc, ca});
        }
        m.triangles.swap(next);
    }
    return m;
}

// Splits the triangles into slabs along x by centroid, each with its own vertex list (a
// vertex on a slab border is copied into both, as bricks do).
std::vector<ProxyMesh> Split(const ProxyMesh& m, int parts) {
    std::vector<ProxyMesh> out(parts);
    std::vector<std::map<uint32_t, uint32_t>> local(parts);
    for (size_t i = 0; i < m.triangles.size(); i += 3) {
        float x = 0;
        for (int k = 0; k < 3; ++k)
            x += m.positions[m.triangles[i + k]].x / 3;
        int p = std::clamp(int((x + 1) / 2 * parts), 0, parts - 1);
        for (int k = 0; k < 3; ++k) {
            uint32_t v = m.triangles[i + k];
            auto [it, added] = local[p].emplace(v, uint32_t(out[p].positions.size()));
            if (added)
                out[p].positions.push_back(m.positions[v]);
            out[p].triangles.push_back(it->second);
        }
    }
    return out;
}

ClusterResult Cluster(const std::vector<ProxyMesh>& parts, uint64_t budget) {
    ClusterOptions o;
    o.max_triangles = budget;
    o.surface_area = 4 * 3.14159265;
    o.bbox_min = {-1, -1, -1};
    o.bbox_max = {1, 1, 1};
    return ClusterProxy(
        uint32_t(parts.size()), [&](uint32_t k) { return parts[k]; }, o);
}

// Distance from p to triangle abc (Ericson, Real-Time Collision Detection 5.1.5).
double PointTriangle(Vec3d p, Vec3d a, Vec3d b, Vec3d c) {
    Vec3d ab = b - a, ac = c - a, ap = p - a;
    double d1 = Dot(ab, ap), d2 = Dot(ac, ap);
    if (d1 <= 0 && d2 <= 0)
        return Length(p - a);
    Vec3d bp = p - b;
    double d3 = Dot(ab, bp), d4 = Dot(ac, bp);
    if (d3 >= 0 && d4 <= d3)
        return Length(p - b);
    double vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0)
        return Length(p - (a + ab * (d1 / (d1 - d3))));
    Vec3d cp = p - c;
    double d5 = Dot(ab, cp), d6 = Dot(ac, cp);
    if (d6 >= 0 && d5 <= d6)
        return Length(p - c);
    double vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0)
        return Length(p - (a + ac * (d2 / (d2 - d6))));
    double va = d3 * d6 - d5 * d4;
    if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
        return Length(p - (b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)))));
    double denom = 1 / (va + vb + vc);
    return Length(p - (a + ab * (vb * denom) + ac * (vc * denom)));
}

double DistanceToMesh(const Vec3f& p, const ProxyMesh& m) {
    double best = 1e30;
    for (size_t i = 0; i < m.triangles.size(); i += 3)
        best = std::min(best, PointTriangle(Vec3d(p), Vec3d(m.positions[m.triangles[i]]),
                                            Vec3d(m.positions[m.triangles[i + 1]]),
                                            Vec3d(m.positions[m.triangles[i + 2]])));
    return best;
}

TEST(ProxyCluster, StaysUnderTheBudgetWithoutCollapsing) {
    const ProxyMesh sphere = Icosphere(6);  // 81920 triangles
    for (uint64_t budget : {500u, 3000u, 20000u}) {
        ClusterResult r = Cluster(Split(sphere, 4), budget);
        const uint64_t n = r.mesh.triangles.size() / 3;
        EXPECT_LE(n, budget);
        EXPECT_GE(n, budget / 4) << "budget " << budget << ": far coarser than needed";
        EXPECT_EQ(r.input_triangles, 81920u);
        EXPECT_GT(r.cell_size, 0);
        for (uint32_t v : r.mesh.triangles)
            ASSERT_LT(v, r.mesh.positions.size());
    }
}

// Rays from the centre of the unit sphere that miss every proxy triangle: light leaking
// through a crack. Moller-Trumbore with a small tolerance, so a ray through an edge shared
// by two triangles counts as a hit.
size_t LeakingRays(const ProxyMesh& m, int rays) {
    size_t leaks = 0;
    for (int i = 0; i < rays; ++i) {
        // Fibonacci directions over the sphere.
        double z = 1 - (2 * i + 1) / double(rays), r = std::sqrt(1 - z * z);
        double phi = i * 2.399963229728653;
        Vec3d d{r * std::cos(phi), r * std::sin(phi), z};
        bool hit = false;
        for (size_t t = 0; t < m.triangles.size() && !hit; t += 3) {
            Vec3d a(m.positions[m.triangles[t]]), b(m.positions[m.triangles[t + 1]]),
                c(m.positions[m.triangles[t + 2]]);
            Vec3d e1 = b - a, e2 = c - a, p = Cross(d, e2);
            double det = Dot(e1, p);
            if (std::abs(det) < 1e-18)
                continue;
            Vec3d s = -a;  // the origin is the centre
            double u = Dot(s, p) / det, v = Dot(d, Cross(s, e1)) / det;
            double dist = Dot(e2, Cross(s, e1)) / det;
            const double eps = 1e-9;
            hit = u >= -eps && v >= -eps && u + v <= 1 + eps && dist > 0;
        }
        leaks += !hit;
    }
    return leaks;
}

TEST(ProxyCluster, AWrongAreaGuessCostsRoundsNotTheBudget) {
    const std::vector<ProxyMesh> parts = Split(Icosphere(6), 4);
    for (double area : {0.05, 4.0, 400.0}) {  // the true area is 12.6
        ClusterOptions o;
        o.max_triangles = 3000;
        o.surface_area = area;
        o.bbox_min = {-1, -1, -1};
        o.bbox_max = {1, 1, 1};
        ClusterResult r = ClusterProxy(
            4, [&](uint32_t k) { return parts[k]; }, o);
        EXPECT_LE(r.mesh.triangles.size() / 3, 3000u) << "area " << area;
        EXPECT_GT(r.mesh.triangles.size() / 3, 0u) << "area " << area;
        if (area < 1) {
            EXPECT_GT(r.rounds, 1) << "a far too fine first cell must be redone";
        }
    }
}

TEST(ProxyCluster, SplittingIntoPartsLeavesNoCracks) {
    const ProxyMesh sphere = Icosphere(6);
    const ClusterResult whole = Cluster(Split(sphere, 1), 5000);
    EXPECT_EQ(LeakingRays(whole.mesh, 2000), 0u);
    for (int parts : {3, 7}) {
        ClusterResult r = Cluster(Split(sphere, parts), 5000);
        // The same cells and triangles as the undivided sphere: a part border changes
        // nothing but the representatives of the cells it crosses (a border vertex counts
        // once per part), by far less than a cell.
        EXPECT_EQ(r.mesh.triangles, whole.mesh.triangles) << parts << " parts";
        ASSERT_EQ(r.mesh.positions.size(), whole.mesh.positions.size());
        for (size_t v = 0; v < r.mesh.positions.size(); ++v)
            ASSERT_LT(Length(r.mesh.positions[v] - whole.mesh.positions[v]), 0.5 * r.cell_size);
        EXPECT_EQ(r.uncovered_vertices, 0u);
        EXPECT_EQ(LeakingRays(r.mesh, 2000), 0u) << parts << " parts";
    }
}

TEST(ProxyCluster, DeviationBoundsTheDistanceBothWays) {
    const ProxyMesh sphere = Icosphere(5);  // 20480 triangles, 10242 vertices
    ClusterResult r = Cluster(Split(sphere, 3), 1500);
    ASSERT_GT(r.deviation, 0);
    EXPECT_LE(r.deviation, r.cell_size * std::sqrt(3.0) * 1.0001);
    const double slack = 1e-6;
    double worst_in = 0, worst_out = 0;
    for (const Vec3f& v : sphere.positions)
        worst_in = std::max(worst_in, DistanceToMesh(v, r.mesh));
    // Proxy points: vertices and triangle centroids.
    for (size_t i = 0; i < r.mesh.triangles.size(); i += 3) {
        Vec3f c{};
        for (int k = 0; k < 3; ++k) {
            const Vec3f& p = r.mesh.positions[r.mesh.triangles[i + k]];
            worst_out = std::max(worst_out, DistanceToMesh(p, sphere));
            c += p * (1.0f / 3);
        }
        worst_out = std::max(worst_out, DistanceToMesh(c, sphere));
    }
    EXPECT_LE(worst_in, r.deviation + slack);
    EXPECT_LE(worst_out, r.deviation + slack);
}

TEST(ProxyCluster, SameBytesForAnyThreadsAndPartOrder) {
    const std::vector<ProxyMesh> parts = Split(Icosphere(5), 5);
    const std::vector<ProxyMesh> reversed(parts.rbegin(), parts.rend());
    ClusterResult a, b, c;
    {
        ThreadLimit one(1);
        a = Cluster(parts, 2000);
    }
    {
        ThreadLimit two(2);
        b = Cluster(parts, 2000);
        c = Cluster(reversed, 2000);
    }
    EXPECT_EQ(a.mesh.positions, b.mesh.positions);
    EXPECT_EQ(a.mesh.triangles, b.mesh.triangles);
    EXPECT_EQ(a.mesh.positions, c.mesh.positions);
    EXPECT_EQ(a.mesh.triangles, c.mesh.triangles);
    EXPECT_EQ(a.deviation, c.deviation);
}

// Through ingest -------------------------------------------------------------------------

std::string WriteObj(const ProxyMesh& m, const std::string& name) {
    std::string path = (fs::temp_directory_path() / name).string();
    std::FILE* f = std::fopen(path.c_str(), "w");
    for (const Vec3f& p : m.positions)
        std::fprintf(f, "v %.9g %.9g %.9g\n", p.x, p.y, p.z);
    for (size_t i = 0; i < m.triangles.size(); i += 3)
        std::fprintf(f, "f %u %u %u\n", m.triangles[i] + 1, m.triangles[i + 1] + 1,
                     m.triangles[i + 2] + 1);
    std::fclose(f);
    return path;
}

Manifest IngestSphere(const std::string& obj, const std::string& dir, int threads,
                      uint64_t visibility_bytes) {
    fs::remove_all(dir);  // a failed earlier run leaves a directory ingest refuses to touch
    IngestOptions o;
    o.inputs = {obj};
    o.out_dir = dir;
    o.threads = threads;
    o.visibility_bytes = visibility_bytes;
    o.brick_faces = 20000;
    o.force = true;
    return Ingest(o);
}

std::string Bytes(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), {}};
}

ProxyMesh ReadProxy(const std::string& dir, size_t* chunks) {
    io::ChunkReader r(ProxyPath(dir), io::Tag("PRXY"), 1, 1);
    ProxyMesh all;
    *chunks = 0;
    for (auto [tag, index] : r.List()) {
        if (tag != io::Tag("PPOS"))
            continue;
        ++*chunks;
        auto pos = r.ReadArray<Vec3f>(tag, index);
        auto tri = r.ReadArray<uint32_t>(io::Tag("PTRI"), index);
        for (uint32_t& v : tri)
            v += uint32_t(all.positions.size());
        all.positions.insert(all.positions.end(), pos.begin(), pos.end());
        all.triangles.insert(all.triangles.end(), tri.begin(), tri.end());
    }
    return all;
}

TEST(ProxyIngest, SmallBudgetSimplifiesCrackFreeAndDeterministic) {
    const std::string obj = WriteObj(Icosphere(6), "mebake_proxy_sphere.obj");
    const std::string a = (fs::temp_directory_path() / "mebake_proxy_a").string();
    const std::string b = (fs::temp_directory_path() / "mebake_proxy_b").string();
    const uint64_t visibility = uint64_t(1) << 20;  // full 18724 triangles, proxy 10485; 8 bricks
    const uint64_t budget = ProxyTriangleBudget(visibility);
    const Manifest ma = IngestSphere(obj, a, 2, visibility);
    IngestSphere(obj, b, 1, visibility);
    ASSERT_GT(ma.brick_count, 2u) << "the test needs brick borders";
    EXPECT_LE(ma.proxy_triangles, budget);
    EXPECT_GE(ma.proxy_triangles, budget / 4);
    EXPECT_GT(ma.proxy_deviation, 0);
    EXPECT_LT(ma.proxy_deviation, 0.1);  // of a unit sphere
    EXPECT_GT(ma.proxy_cell_size, 0);
    EXPECT_EQ(ReadManifest(a).proxy_deviation, ma.proxy_deviation);
    EXPECT_EQ(Bytes(ProxyPath(a)), Bytes(ProxyPath(b)));
    size_t chunks = 0;
    const ProxyMesh proxy = ReadProxy(a, &chunks);
    EXPECT_EQ(chunks, 1u);
    EXPECT_EQ(proxy.triangles.size() / 3, ma.proxy_triangles);
    // The same triangles as the unsplit sphere clustered in one part on the same grid,
    // and closed: no ray from the centre gets out.
    ClusterOptions co;
    co.max_triangles = budget;
    co.surface_area = ma.surface_area;
    co.bbox_min = ma.bbox_min;
    co.bbox_max = ma.bbox_max;
    const ProxyMesh sphere = Icosphere(6);
    const ClusterResult whole = ClusterProxy(
        1, [&](uint32_t) { return sphere; }, co);
    EXPECT_EQ(proxy.triangles, whole.mesh.triangles) << "cracks at brick borders";
    EXPECT_EQ(whole.cell_size, ma.proxy_cell_size);
    EXPECT_EQ(LeakingRays(proxy, 2000), 0u) << "cracks at brick borders";
    fs::remove_all(a);
    fs::remove_all(b);
    fs::remove(obj);
}

TEST(ProxyIngest, FullMeshWhenItFits) {
    const ProxyMesh sphere = Icosphere(5);
    const std::string obj = WriteObj(sphere, "mebake_proxy_sphere5.obj");
    const std::string a = (fs::temp_directory_path() / "mebake_proxy_full").string();
    const Manifest m = IngestSphere(obj, a, 2, uint64_t(4) << 20);  // full mesh budget 74898
    EXPECT_EQ(m.proxy_triangles, 20480u);
    EXPECT_EQ(m.proxy_deviation, 0);
    EXPECT_EQ(m.proxy_cell_size, 0);
    size_t chunks = 0;
    const ProxyMesh proxy = ReadProxy(a, &chunks);
    EXPECT_EQ(chunks, m.brick_count);
    EXPECT_EQ(proxy.triangles.size(), sphere.triangles.size());
    // The input's own vertices, unmoved.
    std::vector<Vec3f> in = sphere.positions, out = proxy.positions;
    auto less = [](const Vec3f& p, const Vec3f& q) {
        return std::tie(p.x, p.y, p.z) < std::tie(q.x, q.y, q.z);
    };
    std::sort(in.begin(), in.end(), less);
    std::sort(out.begin(), out.end(), less);
    out.erase(std::unique(out.begin(), out.end()), out.end());
    EXPECT_EQ(in, out);
    fs::remove_all(a);
    fs::remove(obj);
}

}  // namespace
}  // namespace mebake::stream
