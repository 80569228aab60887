// Chart segmentation (Master-Element paper, seeds/000, section 3.1 step 2: "an approach
// inspired by [Sander et al. 2003] ... a discrete version of Centroidal Voronoi Diagrams
// [Lloyd 1982] ... driven by a curvature estimator").
//
// Discrete Lloyd iterations over the faces, as in variational shape approximation
// (Cohen-Steiner, Alliez, Desbrun 2004): each chart has a proxy (unit normal N, centre C);
// a face f joins the chart that minimises
//     e(f, P) = |n_f - N|^2 + compactness * |c_f - C|^2 / R^2,
// the L2,1 normal term plus a centroidal-Voronoi term (R^2 = mean chart area / pi) that
// keeps charts compact, grown from one seed face per proxy by a priority queue (cheapest
// face first). Proxies are refit (area-weighted mean normal and centroid) and reseeded at
// their best face after each pass. Normals are lightly smoothed first (scan noise is not
// curvature; the paper uses the Cohen-Steiner-Morvan estimator, which also integrates over
// a neighbourhood). Curvature drives the segmentation through the normal term and through
// the bound on normal deviation: where 5% or more of a chart's area deviates too far from
// its proxy, a seed is inserted at its worst face, so curved parts get more, smaller
// charts. The vertex bound inserts seeds the same way (at the farthest face).
//
// Discs. Lloyd regions are edge-connected but may be annuli (around a bump), pinched at a
// vertex, or a whole closed part. Every chart is checked (CheckDisc) and, if it is not a
// disc or exceeds the vertex bound, split by SplitChart, whose growth is constrained: a
// face joins a growing chart only if it shares exactly one edge with it and brings a new
// vertex, or shares two edges (filling a notch); anything else would change the chart's
// Euler characteristic (a handle, a pinch or a closed surface). Faces no seed can take
// start charts of their own. Small charts are then merged into a neighbour when they share
// exactly one boundary arc (V - E = 1 on the common boundary keeps the union a disc).
//
// Determinism: the queue orders by (cost, face, proxy), every loop runs in index order
// (faces are first put in Morton order of their centroids, for cache locality).
#include "stream/segment.h"

#include "core/check.h"
#include "core/error.h"
#include "core/parallel.h"
#include "stream/flood_queue.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <queue>

namespace mebake::stream {
namespace {

using Tri = std::array<uint32_t, 3>;
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kPi = 3.14159265358979323846;
constexpr int kSmoothingPasses = 3;
// The share of a chart's area whose normal must lie within the deviation bound: the rest
// is left to noise and small bumps.
constexpr double kDeviationQuantile = 0.95;
// Charts never grow across an edge whose faces fold by more than this (a box's or a
// wall's edge): E jumps there, and one polynomial over both sides would ring. Scans rarely
// fold this sharply between neighbouring faces; the few noise spikes that do make charts
// under min_chart_faces, which are merged back.
constexpr double kCreaseDeg = 70;
// Lloyd iterations stop early once at most 1 / kSettledFraction of the faces change chart
// (late iterations on scans move 2-7% of the faces back and forth along the borders).
constexpr size_t kSettledFraction = 64;

struct Surface {
    const std::vector<Tri>& tris;
    size_t vertex_count;
    std::vector<Vec3d> normal;
    std::vector<Vec3d> centroid;
    std::vector<double> area;
    std::vector<uint32_t> twin;
    VertexFaces vf;
    std::vector<uint8_t> degenerate;  // repeated index: a chart of its own
    double total_area = 0;
    // What the partition's hot loop reads of a face, in one cache line's reach (it visits
    // faces in heap order, so each face costs a cache miss per array it reads): normal,
    // centroid, and the neighbour across each edge a chart may grow to (kNoIndex at a
    // boundary, a crease or a degenerate neighbour).
    struct Packed {
        Vec3f normal, centroid;
        uint32_t grow[3];
    };
    std::vector<Packed> packed;

    explicit Surface(const TriMesh& m) : tris(m.triangles), vertex_count(m.vertex_count()) {
        const size_t nf = tris.size();
        CHECK_LT(nf, size_t(kNoIndex) / 3);
        normal.resize(nf);
        centroid.resize(nf);
        area.resize(nf);
        degenerate.resize(nf);
        for (const Tri& t : tris)
            for (uint32_t v : t)
                CHECK_LT(v, vertex_count);
        ParallelFor(
            0, int64_t(nf),
            [&](int64_t f) {
                const Tri& t = tris[size_t(f)];
                const Vec3d a(m.position[t[0]]), b(m.position[t[1]]), c(m.position[t[2]]);
                const Vec3d n = Cross(b - a, c - a);
                area[size_t(f)] = 0.5 * Length(n);
                normal[size_t(f)] = Normalize(n);
                centroid[size_t(f)] = (a + b + c) / 3.0;
                degenerate[size_t(f)] = t[0] == t[1] || t[1] == t[2] || t[2] == t[0];
            },
            4096);
        for (double a : area)
            total_area += a;
        twin = BuildTwins(tris, BuildEdgeGroups(tris));
        vf = BuildVertexFaces(tris, vertex_count);
        // Folds are read off the raw normals, before smoothing blurs a box's edges away.
        const double crease_cos = std::cos(kCreaseDeg * kPi / 180);
        packed.resize(nf);
        for (size_t f = 0; f < nf; ++f) {
            for (uint32_t k = 0; k < 3; ++k) {
                const uint32_t g = Neighbour(uint32_t(f), k);
                const bool crease = g != kNoIndex && Dot(normal[f], normal[g]) < crease_cos;
                packed[f].grow[k] = g != kNoIndex && !degenerate[g] && !crease ? g : kNoIndex;
            }
        }
        SmoothNormals();
        for (size_t f = 0; f < nf; ++f) {
            packed[f].normal = Vec3f(normal[f]);
            packed[f].centroid = Vec3f(centroid[f]);
        }
    }

    // Scanned surfaces carry noise at the scale of a face, which would read as curvature.
    // Like a curvature estimator integrated over a small neighbourhood (Cohen-Steiner and
    // Morvan 2003 average over a ball), normals are averaged: face -> vertex (area-weighted)
    // -> face, kSmoothingPasses times, which covers a ring of about that many faces.
    void SmoothNormals() {
        const size_t nf = tris.size();
        std::vector<Vec3d> vertex_normal(vertex_count);
        for (int pass = 0; pass < kSmoothingPasses; ++pass) {
            ParallelFor(
                0, int64_t(vertex_count),
                [&](int64_t v) {
                    Vec3d sum;
                    for (uint32_t i = vf.offset[size_t(v)]; i < vf.offset[size_t(v) + 1]; ++i)
                        sum += normal[vf.face[i]] * area[vf.face[i]];
                    vertex_normal[size_t(v)] = sum;
                },
                4096);
            ParallelFor(
                0, int64_t(nf),
                [&](int64_t f) {
                    const Tri& t = tris[size_t(f)];
                    const Vec3d n =
                        Normalize(vertex_normal[t[0]] + vertex_normal[t[1]] + vertex_normal[t[2]]);
                    if (Dot(n, n) > 0)
                        normal[size_t(f)] = n;
                },
                4096);
        }
    }
    uint32_t face_count() const { return uint32_t(tris.size()); }
    // Neighbour across edge k of f, kNoIndex at a boundary or non-manifold edge.
    uint32_t Neighbour(uint32_t f, uint32_t k) const {
        const uint32_t t = twin[3 * f + k];
        return t == kNoIndex ? kNoIndex : t / 3;
    }
};

struct Proxy {
    Vec3d normal;
    Vec3d center;
    uint32_t seed;
};

class Segmenter {
public:
    Segmenter(const Surface& s, double compactness) : s_(s), compactness_(compactness) {}

    // Grows regions from the proxies' seeds; faces left over start new proxies (appended).
    // chart[f] = proxy index. With discs set, every region is grown as a topological disc.
    void Partition(std::vector<Proxy>& proxies, std::vector<uint32_t>& chart, bool discs) {
        discs_ = discs;
        const uint32_t nf = s_.face_count();
        chart.assign(nf, kNoIndex);
        best_.assign(discs_ ? 0 : nf, std::numeric_limits<float>::infinity());
        weight_ = float(compactness_ * kPi * double(std::max<size_t>(proxies.size(), 1)) /
                        std::max(s_.total_area, 1e-30));
        for (uint32_t p = 0; p < proxies.size(); ++p) {
            const uint32_t f = proxies[p].seed;
            if (chart[f] != kNoIndex)
                continue;  // two proxies on one face: the later starves
            chart[f] = p;
            PushNeighbours(f, p, proxies[p], chart);
        }
        Drain(proxies, chart);
        leftovers_ = 0;
        for (uint32_t f = 0; f < nf; ++f) {
            if (chart[f] != kNoIndex)
                continue;
            ++leftovers_;
            const uint32_t p = uint32_t(proxies.size());
            proxies.push_back({s_.normal[f], s_.centroid[f], f});
            chart[f] = p;
            PushNeighbours(f, p, proxies[p], chart);
            Drain(proxies, chart);
        }
    }

    // Charts the last Partition had to start from faces no seed reached.
    size_t leftovers() const { return leftovers_; }

    float Cost(uint32_t f, const Proxy& p) const {
        return Cost(f, Vec3f(p.normal), Vec3f(p.center));
    }
    float Cost(uint32_t f, const Vec3f& normal, const Vec3f& center) const {
        const Surface::Packed& g = s_.packed[f];
        const Vec3f dn = g.normal - normal;
        const Vec3f dc = g.centroid - center;
        return Dot(dn, dn) + weight_ * Dot(dc, dc);
    }

    // True if adding face f to chart c keeps c a disc.
    bool CanAdd(uint32_t f, uint32_t c, const std::vector<uint32_t>& chart) const {
        if (s_.degenerate[f])
            return false;
        int shared_edges = 0, shared_vertices = 0;
        for (uint32_t k = 0; k < 3; ++k) {
            const uint32_t g = s_.Neighbour(f, k);
            shared_edges += g != kNoIndex && chart[g] == c;
        }
        for (uint32_t v : s_.tris[f]) {
            for (uint32_t i = s_.vf.offset[v]; i < s_.vf.offset[v + 1]; ++i)
                if (chart[s_.vf.face[i]] == c) {
                    ++shared_vertices;
                    break;
                }
        }
        return (shared_edges == 1 && shared_vertices == 2) ||
               (shared_edges == 2 && shared_vertices == 3);
    }

private:
    // Without the disc rule the first entry of a face to leave the heap takes it, so an
    // entry costlier than one already queued for the same face could never take it: it is
    // not pushed (same partition, fewer heap operations).
    void PushNeighbours(uint32_t f, uint32_t p, const Proxy& proxy,
                        const std::vector<uint32_t>& chart) {
        // The proxy in float once, not per neighbour (the pushes may alias it for the compiler).
        const Vec3f normal(proxy.normal), center(proxy.center);
        for (uint32_t g : s_.packed[f].grow) {
            if (g == kNoIndex || chart[g] != kNoIndex)
                continue;
            const float cost = Cost(g, normal, center);
            if (!discs_) {
                if (cost > best_[g])
                    continue;
                if (cost < best_[g])  // a NaN orders nowhere: queued, never a bound
                    best_[g] = cost;
            }
            heap_.push(cost, g, p);
        }
    }

    void Drain(const std::vector<Proxy>& proxies, std::vector<uint32_t>& chart) {
        while (!heap_.empty()) {
            const FloodQueue::Entry e = heap_.top();
            heap_.pop();
            if (!heap_.empty()) {  // the next face's data is on its way while this one is done
                __builtin_prefetch(&s_.packed[heap_.top_face()]);
                __builtin_prefetch(&chart[heap_.top_face()]);
            }
            if (chart[e.face] != kNoIndex)
                continue;
            if (discs_ && !CanAdd(e.face, e.proxy, chart))
                continue;
            chart[e.face] = e.proxy;
            PushNeighbours(e.face, e.proxy, proxies[e.proxy], chart);
        }
    }

    const Surface& s_;
    double compactness_;
    float weight_ = 0;  // compactness / R^2
    size_t leftovers_ = 0;
    bool discs_ = true;
    std::vector<float> best_;  // per face, the least cost queued (without the disc rule)
    FloodQueue heap_;  // pops by (cost, face, proxy)
};

// Refits proxies to their regions, drops the empty ones (renumbering chart) and those under
// min_faces, and moves each seed to the region's best face.
void FitAndReseed(const Surface& s, const Segmenter& seg, uint32_t min_faces,
                  std::vector<Proxy>& proxies, std::vector<uint32_t>& chart) {
    const size_t np = proxies.size();
    std::vector<Vec3d> sum_n(np), sum_c(np);
    std::vector<double> sum_a(np, 0.0);
    std::vector<uint32_t> count(np, 0);
    for (uint32_t f = 0; f < s.face_count(); ++f) {
        const uint32_t p = chart[f];
        sum_n[p] += s.normal[f] * s.area[f];
        sum_c[p] += s.centroid[f] * s.area[f];
        sum_a[p] += s.area[f];
        ++count[p];
    }
    std::vector<uint32_t> remap(np, kNoIndex);
    std::vector<Proxy> kept;
    for (size_t p = 0; p < np; ++p) {
        if (count[p] == 0 || count[p] < min_faces)
            continue;
        remap[p] = uint32_t(kept.size());
        Proxy q = proxies[p];
        const Vec3d n = Normalize(sum_n[p]);
        if (Dot(n, n) > 0)
            q.normal = n;
        if (sum_a[p] > 0)
            q.center = sum_c[p] / sum_a[p];
        q.seed = kNoIndex;
        kept.push_back(q);
    }
    // Each face's cost under its refitted proxy in parallel; the best face per proxy is
    // then found in face order.
    std::vector<float> cost(s.face_count());
    ParallelFor(
        0, int64_t(s.face_count()),
        [&](int64_t f) {
            const uint32_t p = remap[chart[size_t(f)]];
            chart[size_t(f)] = p;
            cost[size_t(f)] = p == kNoIndex ? 0.f : seg.Cost(uint32_t(f), kept[p]);
        },
        4096);
    std::vector<double> best(kept.size(), kInf);
    for (uint32_t f = 0; f < s.face_count(); ++f) {
        const uint32_t p = chart[f];
        if (p == kNoIndex)
            continue;
        const double e = cost[f];
        if (e < best[p]) {
            best[p] = e;
            kept[p].seed = f;
        }
    }
    proxies = std::move(kept);
}

void Lloyd(const Surface& s, Segmenter& seg, int iterations, uint32_t min_faces, bool discs,
           std::vector<Proxy>& proxies, std::vector<uint32_t>& chart, SegmentReport& report) {
    std::vector<uint32_t> previous;
    for (int it = 0; it < iterations; ++it) {
        previous.swap(chart);
        seg.Partition(proxies, chart, discs);
        ++report.lloyd_iterations;
        // Settled: so few faces moved that further passes would only shuffle the borders.
        size_t moved = chart.size();
        if (previous.size() == chart.size()) {
            moved = 0;
            for (size_t f = 0; f < chart.size(); ++f)
                moved += previous[f] != chart[f];
        }
        const bool last = it + 1 == iterations || moved <= chart.size() / kSettledFraction;
        // Small charts are dropped between passes (their faces seed again if nobody takes
        // them), kept after the last.
        FitAndReseed(s, seg, last ? 1 : min_faces, proxies, chart);
        if (last)
            break;
    }
}

// Farthest-point sampling of k seed faces among `faces` (one dual-connected set, or not)
// by Dijkstra over the dual graph with centroid distances. dist must be all +inf on entry
// and is restored on exit.
std::vector<uint32_t> FarthestSeeds(const Surface& s, const std::vector<uint32_t>& faces, size_t k,
                                    std::vector<double>& dist) {
    using Item = std::pair<double, uint32_t>;
    std::priority_queue<Item, std::vector<Item>, std::greater<Item>> heap;
    auto grow = [&](uint32_t source) {
        dist[source] = 0;
        heap.push({0.0, source});
        while (!heap.empty()) {
            const auto [d, f] = heap.top();
            heap.pop();
            if (d > dist[f])
                continue;
            for (uint32_t j = 0; j < 3; ++j) {
                const uint32_t g = s.Neighbour(f, j);
                if (g == kNoIndex)
                    continue;
                const double nd = d + Length(s.centroid[g] - s.centroid[f]);
                if (nd < dist[g]) {
                    dist[g] = nd;
                    heap.push({nd, g});
                }
            }
        }
    };
    auto farthest = [&]() {
        uint32_t best = faces[0];
        for (uint32_t f : faces)
            if (dist[f] > dist[best])
                best = f;
        return best;
    };
    std::vector<uint32_t> seeds;
    // The first seed: the face farthest from faces[0] in a straight line (a full
    // Dijkstra here cost as much as all the later, incremental ones together).
    uint32_t first = faces[0];
    double first_d2 = -1;
    for (uint32_t f : faces) {
        const Vec3d d = s.centroid[f] - s.centroid[faces[0]];
        if (Dot(d, d) > first_d2) {
            first_d2 = Dot(d, d);
            first = f;
        }
    }
    seeds.push_back(first);
    grow(first);
    while (seeds.size() < std::min(k, faces.size())) {
        const uint32_t f = farthest();
        if (!(dist[f] > 0))
            break;
        seeds.push_back(f);
        grow(f);
    }
    for (uint32_t f : faces)
        dist[f] = kInf;
    return seeds;
}

// Per chart: faces, distinct vertices, 95%-area normal deviation (degrees) from its proxy,
// and the faces that deviate the most and lie farthest from the proxy's centre.
struct ChartStats {
    std::vector<uint32_t> faces, vertices;
    std::vector<double> deviation_deg;
    std::vector<uint32_t> worst_normal, farthest;
};

ChartStats Stats(const Surface& s, const std::vector<Proxy>& proxies,
                 const std::vector<uint32_t>& chart) {
    const size_t nc = proxies.size();
    ChartStats st;
    st.faces.assign(nc, 0);
    st.vertices.assign(nc, 0);
    st.deviation_deg.assign(nc, 0);
    st.worst_normal.assign(nc, kNoIndex);
    st.farthest.assign(nc, kNoIndex);
    constexpr int kBins = 180;
    std::vector<double> hist(nc * kBins, 0.0), total(nc, 0.0), worst(nc, -1), far(nc, -1);
    // Each face's angle to its proxy (the acos is most of the cost) in parallel; the sums
    // below stay in face order.
    std::vector<double> angle_of(s.face_count());
    ParallelFor(
        0, int64_t(s.face_count()),
        [&](int64_t f) {
            const Vec3d& n = proxies[chart[size_t(f)]].normal;
            angle_of[size_t(f)] =
                std::acos(std::clamp(Dot(s.normal[size_t(f)], n), -1.0, 1.0)) * 180 / kPi;
        },
        4096);
    for (uint32_t f = 0; f < s.face_count(); ++f) {
        const uint32_t c = chart[f];
        ++st.faces[c];
        const double angle = angle_of[f];
        hist[c * kBins + std::min(kBins - 1, int(angle))] += s.area[f];
        total[c] += s.area[f];
        if (angle > worst[c]) {
            worst[c] = angle;
            st.worst_normal[c] = f;
        }
        const Vec3d d = s.centroid[f] - proxies[c].center;
        if (Dot(d, d) > far[c]) {
            far[c] = Dot(d, d);
            st.farthest[c] = f;
        }
    }
    for (size_t c = 0; c < nc; ++c) {
        double acc = 0;
        int bin = 0;
        for (; bin < kBins; ++bin) {
            acc += hist[c * kBins + bin];
            if (acc >= kDeviationQuantile * total[c])
                break;
        }
        st.deviation_deg[c] = std::min(bin + 1, kBins);
    }
    std::vector<uint32_t> seen;
    for (size_t v = 0; v < s.vertex_count; ++v) {
        seen.clear();
        for (uint32_t i = s.vf.offset[v]; i < s.vf.offset[v + 1]; ++i) {
            const uint32_t c = chart[s.vf.face[i]];
            if (std::find(seen.begin(), seen.end(), c) == seen.end())
                seen.push_back(c);
        }
        for (uint32_t c : seen)
            ++st.vertices[c];
    }
    return st;
}

// Merges charts under min_faces into the neighbour they share the longest boundary arc
// with, when the union stays a disc and under max_vertices.
void MergeSmall(const Surface& s, uint32_t min_faces, uint32_t max_vertices, size_t chart_count,
                std::vector<uint32_t>& chart, size_t* merged) {
    std::vector<std::vector<uint32_t>> faces_of(chart_count);
    for (uint32_t f = 0; f < s.face_count(); ++f)
        faces_of[chart[f]].push_back(f);
    std::vector<uint32_t> vcount(chart_count, 0);
    {
        std::vector<uint32_t> seen;
        for (size_t v = 0; v < s.vertex_count; ++v) {
            seen.clear();
            for (uint32_t i = s.vf.offset[v]; i < s.vf.offset[v + 1]; ++i) {
                const uint32_t c = chart[s.vf.face[i]];
                if (std::find(seen.begin(), seen.end(), c) == seen.end())
                    seen.push_back(c);
            }
            for (uint32_t c : seen)
                ++vcount[c];
        }
    }
    std::vector<uint32_t> order;
    for (uint32_t c = 0; c < chart_count; ++c)
        if (faces_of[c].size() < min_faces)
            order.push_back(c);
    std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
        return faces_of[a].size() != faces_of[b].size() ? faces_of[a].size() < faces_of[b].size()
                                                        : a < b;
    });
    std::vector<std::pair<uint32_t, uint32_t>> edges_with, verts_with;  // (chart, count)
    std::vector<uint32_t> verts, seen;
    auto bump = [](std::vector<std::pair<uint32_t, uint32_t>>& list, uint32_t c) {
        for (auto& [k, n] : list)
            if (k == c) {
                ++n;
                return;
            }
        list.push_back({c, 1});
    };
    for (uint32_t a : order) {
        if (faces_of[a].empty() || faces_of[a].size() >= min_faces)
            continue;
        bool degenerate = false;
        for (uint32_t f : faces_of[a])
            degenerate = degenerate || s.degenerate[f];
        if (degenerate)
            continue;  // a face with a repeated index is no part of any disc
        edges_with.clear();
        verts_with.clear();
        verts.clear();
        for (uint32_t f : faces_of[a]) {
            for (uint32_t k = 0; k < 3; ++k) {
                const uint32_t g = s.Neighbour(f, k);
                if (g != kNoIndex && chart[g] != a)
                    bump(edges_with, chart[g]);
                verts.push_back(s.tris[f][k]);
            }
        }
        std::sort(verts.begin(), verts.end());
        verts.erase(std::unique(verts.begin(), verts.end()), verts.end());
        for (uint32_t v : verts) {
            seen.clear();
            for (uint32_t i = s.vf.offset[v]; i < s.vf.offset[v + 1]; ++i) {
                const uint32_t c = chart[s.vf.face[i]];
                if (c != a && std::find(seen.begin(), seen.end(), c) == seen.end()) {
                    seen.push_back(c);
                    bump(verts_with, c);
                }
            }
        }
        uint32_t target = kNoIndex, target_edges = 0;
        for (const auto& [b, e] : edges_with) {
            uint32_t shared_v = 0;
            for (const auto& [c, n] : verts_with)
                if (c == b)
                    shared_v = n;
            if (shared_v != e + 1)
                continue;  // the common boundary is not one arc
            if (vcount[a] + vcount[b] - shared_v > max_vertices)
                continue;
            if (e > target_edges || (e == target_edges && b < target)) {
                target = b;
                target_edges = e;
            }
        }
        if (target == kNoIndex)
            continue;
        for (uint32_t f : faces_of[a])
            chart[f] = target;
        faces_of[target].insert(faces_of[target].end(), faces_of[a].begin(), faces_of[a].end());
        vcount[target] += vcount[a] - (target_edges + 1);
        faces_of[a].clear();
        vcount[a] = 0;
        ++*merged;
    }
}

// Renumbers chart ids by smallest face index; returns the number of charts.
size_t Renumber(std::vector<uint32_t>& chart) {
    uint32_t max_id = 0;
    for (uint32_t c : chart)
        max_id = std::max(max_id, c);
    std::vector<uint32_t> remap(chart.empty() ? 0 : size_t(max_id) + 1, kNoIndex);
    uint32_t next = 0;
    for (uint32_t& c : chart) {
        if (remap[c] == kNoIndex)
            remap[c] = next++;
        c = remap[c];
    }
    return next;
}

TriMesh ExtractFaces(const TriMesh& mesh, const std::vector<uint32_t>& faces) {
    std::vector<uint32_t> verts;
    verts.reserve(faces.size() * 3);
    for (uint32_t f : faces)
        for (uint32_t v : mesh.triangles[f])
            verts.push_back(v);
    std::sort(verts.begin(), verts.end());
    verts.erase(std::unique(verts.begin(), verts.end()), verts.end());
    // Local index of each used vertex through a per-thread scratch map (reset below),
    // instead of a binary search per corner.
    thread_local std::vector<uint32_t> local_of;
    if (local_of.size() < mesh.vertex_count())
        local_of.assign(mesh.vertex_count(), kNoIndex);
    for (size_t i = 0; i < verts.size(); ++i)
        local_of[verts[i]] = uint32_t(i);
    TriMesh out;
    out.position.reserve(verts.size());
    out.vertex_id.reserve(verts.size());
    for (uint32_t v : verts) {
        out.position.push_back(mesh.position[v]);
        out.vertex_id.push_back(mesh.vertex_id.empty() ? v : mesh.vertex_id[v]);
        if (!mesh.albedo.empty())
            out.albedo.push_back(mesh.albedo[v]);
    }
    out.triangles.reserve(faces.size());
    for (uint32_t f : faces) {
        const Tri& t = mesh.triangles[f];
        out.triangles.push_back({local_of[t[0]], local_of[t[1]], local_of[t[2]]});
        out.face_id.push_back(mesh.face_id.empty() ? f : mesh.face_id[f]);
        if (!mesh.material.empty())
            out.material.push_back(mesh.material[f]);
    }
    for (uint32_t v : verts)
        local_of[v] = kNoIndex;
    return out;
}

void ValidateOptions(const SegmentOptions& o) {
    if (o.target_chart_faces < 1)
        UsageError("segment: target chart faces must be >= 1");
    if (o.max_chart_vertices < 3)
        UsageError("segment: max chart vertices must be >= 3");
    if (!(o.max_normal_deviation_deg > 0) || !(o.max_normal_deviation_deg <= 180))
        UsageError("segment: max normal deviation must be in (0, 180] degrees, got {}",
                   o.max_normal_deviation_deg);
    if (!(o.compactness >= 0) || !std::isfinite(o.compactness))
        UsageError("segment: compactness must be finite and >= 0, got {}", o.compactness);
    if (o.lloyd_iterations < 1 || o.lloyd_iterations > 1000 || o.refinement_rounds < 0 ||
        o.refinement_rounds > 1000)
        UsageError("segment: lloyd iterations must be in [1, 1000], refinement rounds in [0, "
                   "1000]");
}

std::vector<uint32_t> SegmentOrdered(const TriMesh& mesh, const SegmentOptions& options,
                                     SegmentReport* report_out);

constexpr double kSplitCompactness = 1.0;
constexpr int kRefineIterations = 2;
constexpr int kSplitIterations = 4;

}  // namespace

TopologyReport CheckDisc(const TriMesh& m) {
    return AnalyzeTopology(m);
}

std::vector<TriMesh> ExtractCharts(const TriMesh& mesh, const std::vector<uint32_t>& chart_of_tri) {
    CHECK_EQ(chart_of_tri.size(), mesh.triangle_count());
    std::vector<std::vector<uint32_t>> faces_of;
    for (uint32_t f = 0; f < chart_of_tri.size(); ++f) {
        const uint32_t c = chart_of_tri[f];
        CHECK_LT(c, chart_of_tri.size());
        if (c >= faces_of.size())
            faces_of.resize(size_t(c) + 1);
        faces_of[c].push_back(f);
    }
    std::vector<TriMesh> charts(faces_of.size());
    ParallelFor(0, int64_t(faces_of.size()),
                [&](int64_t c) { charts[size_t(c)] = ExtractFaces(mesh, faces_of[size_t(c)]); });
    return charts;
}

TriMesh ExtractChart(const TriMesh& mesh, const std::vector<uint32_t>& chart_of_tri,
                     uint32_t chart) {
    CHECK_EQ(chart_of_tri.size(), mesh.triangle_count());
    std::vector<uint32_t> faces;
    for (uint32_t f = 0; f < chart_of_tri.size(); ++f)
        if (chart_of_tri[f] == chart)
            faces.push_back(f);
    return ExtractFaces(mesh, faces);
}

std::vector<uint32_t> SplitChart(const TriMesh& chart, int parts) {
    const uint32_t nf = uint32_t(chart.triangle_count());
    if (nf == 0)
        return {};
    const Surface s(chart);
    Segmenter seg(s, kSplitCompactness);
    std::vector<uint32_t> all(nf);
    for (uint32_t f = 0; f < nf; ++f)
        all[f] = f;
    std::vector<double> dist(nf, kInf);
    std::vector<Proxy> proxies;
    for (uint32_t f : FarthestSeeds(s, all, size_t(std::max(parts, 1)), dist))
        proxies.push_back({s.normal[f], s.centroid[f], f});
    std::vector<uint32_t> ids;
    SegmentReport scratch;
    Lloyd(s, seg, kSplitIterations, 0, /*discs=*/true, proxies, ids, scratch);
    size_t merged = 0;
    const uint32_t small = std::max<uint32_t>(1, nf / uint32_t(20 * std::max(parts, 1)));
    MergeSmall(s, small, ~0u, proxies.size(), ids, &merged);
    Renumber(ids);
    return ids;
}

namespace {

// The geometry of `mesh` with faces in Morton order of their centroids and vertices in order
// of first use: the partition's random accesses then stay in cache. face_of[i] is the
// original index of face i.
TriMesh SpatialOrder(const TriMesh& mesh, std::vector<uint32_t>* face_of) {
    const size_t nf = mesh.triangle_count();
    Vec3f lo = mesh.position.empty() ? Vec3f() : mesh.position[0], hi = lo;
    for (const Vec3f& p : mesh.position) {
        lo = Min(lo, p);
        hi = Max(hi, p);
    }
    const Vec3f extent = hi - lo;
    const float scale = 1048575.0f / std::max({extent.x, extent.y, extent.z, 1e-30f});
    auto spread = [](uint64_t x) {  // 20 bits -> every third bit
        x &= 0xfffff;
        x = (x | (x << 32)) & 0x1f00000000ffffull;
        x = (x | (x << 16)) & 0x1f0000ff0000ffull;
        x = (x | (x << 8)) & 0x100f00f00f00f00full;
        x = (x | (x << 4)) & 0x10c30c30c30c30c3ull;
        x = (x | (x << 2)) & 0x1249249249249249ull;
        return x;
    };
    std::vector<std::pair<uint64_t, uint32_t>> keys(nf);
    for (uint32_t f = 0; f < nf; ++f) {
        const Tri& t = mesh.triangles[f];
        const Vec3f c = (mesh.position[t[0]] + mesh.position[t[1]] + mesh.position[t[2]]) / 3.0f;
        auto q = [&](float x, float l) {
            const float v = (x - l) * scale;
            return uint64_t(std::clamp(v, 0.0f, 1048575.0f));  // NaN -> 0
        };
        keys[f] = {spread(q(c.x, lo.x)) | (spread(q(c.y, lo.y)) << 1) | (spread(q(c.z, lo.z)) << 2),
                   f};
    }
    std::sort(keys.begin(), keys.end());
    TriMesh out;
    face_of->resize(nf);
    std::vector<uint32_t> vmap(mesh.vertex_count(), kNoIndex);
    out.triangles.resize(nf);
    for (uint32_t i = 0; i < nf; ++i) {
        const uint32_t f = keys[i].second;
        (*face_of)[i] = f;
        for (int k = 0; k < 3; ++k) {
            const uint32_t v = mesh.triangles[f][k];
            CHECK_LT(v, mesh.vertex_count());
            if (vmap[v] == kNoIndex) {
                vmap[v] = uint32_t(out.position.size());
                out.position.push_back(mesh.position[v]);
            }
            out.triangles[i][k] = vmap[v];
        }
    }
    return out;
}

}  // namespace

std::vector<uint32_t> SegmentCharts(const TriMesh& mesh, const SegmentOptions& options,
                                    SegmentReport* report_out) {
    ValidateOptions(options);
    std::vector<uint32_t> face_of;
    const TriMesh ordered = SpatialOrder(mesh, &face_of);
    const std::vector<uint32_t> local = SegmentOrdered(ordered, options, report_out);
    std::vector<uint32_t> chart(mesh.triangle_count());
    for (size_t i = 0; i < local.size(); ++i)
        chart[face_of[i]] = local[i];
    Renumber(chart);
    return chart;
}

namespace {

std::vector<uint32_t> SegmentOrdered(const TriMesh& mesh, const SegmentOptions& options,
                                     SegmentReport* report_out) {
    SegmentReport report;
    const uint32_t nf = uint32_t(mesh.triangle_count());
    if (nf == 0) {
        if (report_out)
            *report_out = report;
        return {};
    }
    const Surface s(mesh);
    Segmenter seg(s, options.compactness);

    // Components of the dual graph, and initial seeds per component.
    std::vector<uint32_t> comp(nf, kNoIndex);
    std::vector<Proxy> proxies;
    {
        std::vector<double> dist(nf, kInf);
        std::vector<uint32_t> faces;
        for (uint32_t root = 0; root < nf; ++root) {
            if (comp[root] != kNoIndex)
                continue;
            const uint32_t id = uint32_t(report.components++);
            faces.assign(1, root);
            comp[root] = id;
            bool closed = true;
            for (size_t head = 0; head < faces.size(); ++head)
                for (uint32_t k = 0; k < 3; ++k) {
                    const uint32_t g = s.Neighbour(faces[head], k);
                    if (g == kNoIndex) {
                        closed = false;
                    } else if (comp[g] == kNoIndex) {
                        comp[g] = id;
                        faces.push_back(g);
                    }
                }
            std::sort(faces.begin(), faces.end());
            size_t k = (faces.size() + options.target_chart_faces - 1) / options.target_chart_faces;
            if (closed)
                k = std::max<size_t>(k, 2);
            for (uint32_t f : FarthestSeeds(s, faces, k, dist))
                proxies.push_back({s.normal[f], s.centroid[f], f});
        }
        report.initial_seeds = proxies.size();
    }

    // Small-chart merging guards scans against noise-sized charts; on a coarse mesh (a
    // Cornell box: a few faces per object) every chart is "small", and merging would fold
    // faces meeting at 90 degrees into one chart, so the bound shrinks with the brick.
    const uint32_t min_faces = std::min(options.min_chart_faces, std::max(1u, nf / 256));
    std::vector<uint32_t> chart;
    Lloyd(s, seg, options.lloyd_iterations, min_faces, /*discs=*/false, proxies, chart, report);
    const double max_dev = options.max_normal_deviation_deg;
    for (int round = 0; round < options.refinement_rounds; ++round) {
        const ChartStats st = Stats(s, proxies, chart);
        size_t inserted = 0;
        const size_t np = proxies.size();
        for (size_t c = 0; c < np; ++c) {
            uint32_t f = kNoIndex;
            if (st.vertices[c] > options.max_chart_vertices)
                f = st.farthest[c];
            else if (st.deviation_deg[c] > max_dev && st.faces[c] >= 2 * min_faces)
                f = st.worst_normal[c];
            if (f == kNoIndex || f == proxies[c].seed)
                continue;
            proxies.push_back({s.normal[f], s.centroid[f], f});
            ++inserted;
        }
        if (inserted == 0)
            break;
        report.inserted_seeds += inserted;
        Lloyd(s, seg, kRefineIterations, min_faces, /*discs=*/false, proxies, chart, report);
    }
    report.leftover_charts = seg.leftovers();
    size_t chart_count = Renumber(chart);

    // Lloyd regions are compact and connected but may be annuli (around a bump), pinched
    // at a vertex, or whole closed parts: split every chart that is not a disc, or is over
    // the vertex bound, with SplitChart, whose parts are discs by construction.
    std::vector<std::vector<uint32_t>> faces_of(chart_count);
    for (uint32_t f = 0; f < nf; ++f)
        faces_of[chart[f]].push_back(f);
    std::vector<uint8_t> ok(chart_count, 0);
    std::vector<uint32_t> work(chart_count);
    for (uint32_t c = 0; c < chart_count; ++c)
        work[c] = c;
    while (!work.empty()) {
        ok.assign(faces_of.size(), 1);
        ParallelFor(0, int64_t(work.size()), [&](int64_t i) {
            const uint32_t c = work[size_t(i)];
            if (faces_of[c].size() < 2)
                return;  // a single face is as good as it gets
            const TriMesh piece = ExtractFaces(mesh, faces_of[c]);
            ok[c] = CheckDisc(piece).IsDisc() && piece.vertex_count() <= options.max_chart_vertices;
        });
        std::vector<uint32_t> next;
        for (uint32_t c : work) {
            if (ok[c])
                continue;
            const TriMesh piece = ExtractFaces(mesh, faces_of[c]);
            const std::vector<uint32_t> part = SplitChart(piece, 2);
            uint32_t parts = 0;
            for (uint32_t p : part)
                parts = std::max(parts, p + 1);
            if (parts < 2)
                continue;  // cannot split further
            ++report.split_charts;
            const std::vector<uint32_t> old = std::move(faces_of[c]);
            const size_t base = faces_of.size();
            faces_of[c].clear();
            faces_of.resize(base + parts - 1);
            for (size_t i = 0; i < old.size(); ++i) {
                const uint32_t dst = part[i] == 0 ? c : uint32_t(base + part[i] - 1);
                faces_of[dst].push_back(old[i]);
                chart[old[i]] = dst;
            }
            next.push_back(c);
            for (uint32_t p = 1; p < parts; ++p)
                next.push_back(uint32_t(base + p - 1));
        }
        work = std::move(next);
    }
    chart_count = Renumber(chart);
    MergeSmall(s, min_faces, options.max_chart_vertices, chart_count, chart, &report.merged_charts);
    chart_count = Renumber(chart);

    // Report.
    report.charts = chart_count;
    {
        std::vector<Proxy> fitted(chart_count, Proxy{{}, {}, 0});
        std::vector<Vec3d> sum_n(chart_count);
        for (uint32_t f = 0; f < nf; ++f)
            sum_n[chart[f]] += s.normal[f] * s.area[f];
        for (size_t c = 0; c < chart_count; ++c)
            fitted[c].normal = Normalize(sum_n[c]);
        const ChartStats st = Stats(s, fitted, chart);
        for (size_t c = 0; c < chart_count; ++c) {
            report.max_chart_faces = std::max<size_t>(report.max_chart_faces, st.faces[c]);
            report.max_chart_vertices = std::max<size_t>(report.max_chart_vertices, st.vertices[c]);
            report.max_normal_deviation_deg =
                std::max(report.max_normal_deviation_deg, st.deviation_deg[c]);
        }
    }
    if (report_out)
        *report_out = report;
    return chart;
}

}  // namespace
}  // namespace mebake::stream
