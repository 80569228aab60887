#include "stream/orient.h"

#include "core/log.h"
#include "core/parallel.h"
#include "stream/topology.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <numeric>

namespace mebake::stream {

namespace {

// A brick reads its vertices in ascending id order; a few pages per file are enough.
constexpr size_t kCacheBytes = size_t(3) << 20;
constexpr int kBricksInFlight = 2;

// One component's part in one brick: sums that add up over the parts. Positions are taken
// relative to the mesh's box centre (precision).
struct Piece {
    uint32_t brick = 0, label = 0;  // the brick and the part's label in it
    uint64_t triangles = 0;
    double area = 0;
    Vec3d vector_area{};  // sum of (v1 - v0) x (v2 - v0) / 2
    Vec3d moment{};       // sum of area * centroid
    double volume = 0;    // sum of det(v0, v1, v2) / 6
    Vec3d lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
    bool shared = false;  // touches a vertex of another brick

    void Add(const Piece& o) {
        triangles += o.triangles;
        area += o.area;
        vector_area += o.vector_area;
        moment += o.moment;
        volume += o.volume;
        lo = Min(lo, o.lo);
        hi = Max(hi, o.hi);
    }
};

struct BrickPieces {
    std::vector<Piece> kept;
    std::vector<std::pair<uint64_t, uint32_t>> shared;  // (vertex id, index in kept)
    uint64_t dropped = 0;  // whole components too small to matter (counted only)
};

// Component label per triangle of the brick (0.. in order of first triangle); vertices at
// the same position are one (repair's exact weld). Returns the number of labels.
uint32_t LabelComponents(const TriMesh& m, std::vector<uint32_t>* label) {
    const uint32_t nv = uint32_t(m.vertex_count());
    DisjointSets sets(nv);
    std::vector<uint32_t> order(nv);
    std::iota(order.begin(), order.end(), 0u);
    auto bits = [&](uint32_t v) {
        std::array<uint32_t, 3> b;
        std::memcpy(b.data(), &m.position[v], sizeof(b));
        return b;
    };
    std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
        return std::make_pair(bits(a), a) < std::make_pair(bits(b), b);
    });
    for (uint32_t i = 1; i < nv; ++i)
        if (bits(order[i]) == bits(order[i - 1]))
            sets.Union(order[i], order[i - 1]);
    for (const auto& t : m.triangles)
        sets.Union(t[0], t[1]), sets.Union(t[0], t[2]);
    std::vector<uint32_t> of_root(nv, kNoIndex);
    uint32_t count = 0;
    label->resize(m.triangle_count());
    for (size_t f = 0; f < m.triangle_count(); ++f) {
        uint32_t& l = of_root[sets.Find(m.triangles[f][0])];
        if (l == kNoIndex)
            l = count++;
        (*label)[f] = l;
    }
    return count;
}

// The rule's two measures (orient.h): openness w and volume ratio q.
struct Shape {
    double openness = 1, volume_ratio = 0;
};

Shape Measure(const Piece& p) {
    if (!(p.area > 0))
        return {};
    const Vec3d c = p.moment * (1 / p.area);
    const double volume = p.volume - Dot(c, p.vector_area) / 3;
    const double sphere = std::pow(p.area, 1.5) / (6 * std::sqrt(M_PI));
    return {Length(p.vector_area) / p.area, volume / sphere};
}

// Inside out and nearly closed (rules 1 and 2 of orient.h; nesting is looked at later).
bool InsideOut(const Piece& p) {
    const Shape s = Measure(p);
    return s.openness <= kMaxOpenness && s.volume_ratio <= -kMinVolumeRatio;
}

BrickPieces ScanBrick(const std::string& dir, uint32_t brick, const Vec3d& origin,
                      double kept_area) {
    BrickPieces out;
    std::vector<uint8_t> on_cut;
    const TriMesh m = LoadBrick(dir, brick, kCacheBytes, &on_cut);
    std::vector<uint32_t> label;
    std::vector<Piece> pieces(LabelComponents(m, &label));
    for (size_t f = 0; f < m.triangle_count(); ++f) {
        Piece& p = pieces[label[f]];
        ++p.triangles;
        Vec3d v[3];
        for (int k = 0; k < 3; ++k) {
            v[k] = Vec3d(m.position[m.triangles[f][size_t(k)]]) - origin;
            p.shared |= on_cut[m.triangles[f][size_t(k)]] != 0;
        }
        if (!std::isfinite(v[0].x + v[0].y + v[0].z + v[1].x + v[1].y + v[1].z + v[2].x + v[2].y +
                           v[2].z))
            continue;  // repair drops it
        const Vec3d n = Cross(v[1] - v[0], v[2] - v[0]) * 0.5;
        const double a = Length(n);
        p.area += a;
        p.vector_area += n;
        p.moment += (v[0] + v[1] + v[2]) * (a / 3);
        p.volume += Dot(v[0], Cross(v[1], v[2])) / 6;
        for (const Vec3d& x : v)
            p.lo = Min(p.lo, x), p.hi = Max(p.hi, x);
    }
    std::vector<uint32_t> kept_index(pieces.size(), kNoIndex);
    for (uint32_t l = 0; l < pieces.size(); ++l) {
        Piece& p = pieces[l];
        p.brick = brick;
        p.label = l;
        if (p.shared || p.area >= kept_area || InsideOut(p)) {
            kept_index[l] = uint32_t(out.kept.size());
            out.kept.push_back(p);
        } else {
            ++out.dropped;
        }
    }
    for (size_t f = 0; f < m.triangle_count(); ++f)
        for (uint32_t v : m.triangles[f])
            if (on_cut[v])
                out.shared.emplace_back(m.vertex_id[v], kept_index[label[f]]);
    std::sort(out.shared.begin(), out.shared.end());
    out.shared.erase(std::unique(out.shared.begin(), out.shared.end()), out.shared.end());
    return out;
}

bool Contains(const Piece& a, const Piece& b) {
    return a.lo.x <= b.lo.x && a.lo.y <= b.lo.y && a.lo.z <= b.lo.z && b.hi.x <= a.hi.x &&
           b.hi.y <= a.hi.y && b.hi.z <= a.hi.z;
}

// The rule of orient.h per component: 1 where it is turned outwards.
std::vector<uint8_t> Decide(const std::vector<Piece>& comps, double surface_area,
                            const Vec3d& origin, OrientReport* report) {
    std::vector<uint8_t> flip(comps.size(), 0);
    for (size_t c = 0; c < comps.size(); ++c) {
        if (comps[c].area >= 0.01 * surface_area) {
            const Shape s = Measure(comps[c]);
            spdlog::debug("orientation: component of {} triangles ({:.1f} % of the area): "
                          "openness {:.3f}, volume ratio {:+.3f}",
                          comps[c].triangles, 100 * comps[c].area / surface_area, s.openness,
                          s.volume_ratio);
        }
        if (!InsideOut(comps[c]))
            continue;
        bool nested = false;
        for (size_t o = 0; o < comps.size() && !nested; ++o)
            nested = o != c && comps[o].area >= kNestedArea * comps[c].area &&
                     (Contains(comps[c], comps[o]) || Contains(comps[o], comps[c]));
        if (nested) {
            ++report->nested_kept;
            continue;
        }
        spdlog::debug("orientation: turning outwards {} triangles in the box [{:.4g} {:.4g} "
                      "{:.4g}] - [{:.4g} {:.4g} {:.4g}]",
                      comps[c].triangles, comps[c].lo.x + origin.x, comps[c].lo.y + origin.y,
                      comps[c].lo.z + origin.z, comps[c].hi.x + origin.x, comps[c].hi.y + origin.y,
                      comps[c].hi.z + origin.z);
        flip[c] = 1;
        ++report->flipped_components;
        report->flipped_triangles += comps[c].triangles;
    }
    return flip;
}

// Reverses the faces of the given labels in one brick.
void FlipLabels(const std::string& dir, uint32_t brick, const std::vector<uint32_t>& labels) {
    std::vector<uint8_t> on_cut;
    const TriMesh m = LoadBrick(dir, brick, kCacheBytes, &on_cut);
    std::vector<uint32_t> label;
    LabelComponents(m, &label);
    std::vector<BrickFace> faces = ReadBrick(dir, brick);
    for (size_t f = 0; f < faces.size(); ++f)
        if (std::binary_search(labels.begin(), labels.end(), label[f]))
            std::swap(faces[f].v[1], faces[f].v[2]);
    WriteBrick(dir, brick, faces);
}

}  // namespace

OrientReport OrientOutwards(const std::string& dir, const BrickPlan& plan, const Vec3d& bbox_min,
                            const Vec3d& bbox_max, ProgressStage* progress) {
    const uint32_t bricks = uint32_t(plan.bricks.size());
    const Vec3d origin = (bbox_min + bbox_max) * 0.5;
    const double kept_area = kKeptArea * plan.surface_area;
    std::vector<BrickPieces> scanned(bricks);
    std::atomic<uint32_t> next{0};
    ParallelFor(0, kBricksInFlight, [&](int64_t) {
        for (uint32_t b = next++; b < bricks; b = next++) {
            scanned[b] = ScanBrick(dir, b, origin, kept_area);
            if (progress)
                progress->Add(plan.bricks[b].face_count);
        }
    });

    // All kept pieces in brick order; pieces sharing a vertex are one component.
    OrientReport report;
    std::vector<Piece> pieces;
    std::vector<std::pair<uint64_t, uint32_t>> shared;
    for (auto& s : scanned) {
        const uint32_t base = uint32_t(pieces.size());
        for (const auto& [v, k] : s.shared)
            shared.emplace_back(v, base + k);
        pieces.insert(pieces.end(), s.kept.begin(), s.kept.end());
        report.components += s.dropped;
        s = BrickPieces();
    }
    std::sort(shared.begin(), shared.end());
    DisjointSets sets(pieces.size());
    for (size_t i = 1; i < shared.size(); ++i)
        if (shared[i].first == shared[i - 1].first)
            sets.Union(shared[i].second, shared[i - 1].second);
    std::vector<Piece> comps;
    std::vector<uint32_t> comp_of(pieces.size());
    std::vector<uint32_t> index_of_root(pieces.size(), kNoIndex);
    for (uint32_t i = 0; i < pieces.size(); ++i) {
        uint32_t& c = index_of_root[sets.Find(i)];
        if (c == kNoIndex) {
            c = uint32_t(comps.size());
            comps.emplace_back();
        }
        comps[c].Add(pieces[i]);
        comp_of[i] = c;
    }
    report.components += comps.size();

    const std::vector<uint8_t> flip = Decide(comps, plan.surface_area, origin, &report);

    // Labels to flip, per brick (pieces are in brick order, labels ascending in a brick).
    for (uint32_t i = 0; i < pieces.size();) {
        const uint32_t brick = pieces[i].brick;
        std::vector<uint32_t> labels;
        for (; i < pieces.size() && pieces[i].brick == brick; ++i)
            if (flip[comp_of[i]])
                labels.push_back(pieces[i].label);
        if (!labels.empty())
            FlipLabels(dir, brick, labels);
    }
    spdlog::info("orientation: {} component(s), {} turned outwards ({} triangles){}",
                 report.components, report.flipped_components, report.flipped_triangles,
                 report.nested_kept ? fmt::format(", {} inside out but nested in another, kept",
                                                  report.nested_kept)
                                    : std::string());
    return report;
}

}  // namespace mebake::stream
