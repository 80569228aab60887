// DirectLight::Penumbra: the visible part of one polygon light at points in its penumbra.
// Per point, the light's fan triangles start as 2 x 2 grids of cells whose corners are
// tested with one ray each (the classification rays give the light's own vertices); a cell
// whose corners agree is taken as wholly visible or hidden, one whose corners disagree is
// split in four, down to the finest grid, where a mixed cell counts as 1/4 or 3/4 visible
// (or, where the shadow edge runs along a row of cells, is visible as one fixed
// low-discrepancy point in it is). Corners well below the point's horizon are not traced
// and do not count. Rays go only where a shadow edge crosses the light, and all points of a
// level share one Embree batch. docs/method.md, "Direct light", says why.
#include "solve/direct.h"
#include "solve/penumbra_grid.h"
#include "solve/polygon_light.h"
#include "solve/rays.h"
#include "solve/thread_scratch.h"

#include <algorithm>
#include <cmath>

namespace mebake::solve {

namespace {

// Light-grid vertices more than this (sine of the angle, ~3.4 degrees) below a point's
// smooth horizon get no visibility ray and do not decide whether a cell is uniform. E
// ignores light below that horizon, but the real surface departs from it: just below, a
// visible vertex still says the light above it is visible (a convex bump falls away). At 0
// the noisy sphere's penumbra rays halve again but the bunny's error grew by 0.03 points;
// 0.06 left it unchanged (bench/RESULTS.md, "Speed, session 3").
constexpr double kHorizonMargin = 0.06;

// Grid vertex states per point.
enum : uint8_t { kUnknown = 0, kRequested = 1, kVisible = 2, kHidden = 3 };

// The directed edges of one point's cells with their summed weights: an edge added the
// other way round (a neighbour cell's) subtracts from the same entry. One slot per edge of
// the light's grid (PenumbraGrid::EdgeSlot; a hash of the vertex pair cost about half of
// what the shared edges saved); entries in the order first added (the sum's order,
// deterministic).
class EdgeTable {
public:
    struct Edge {
        uint32_t from, to;  // from < to
        float weight;       // summed weights of the cells that have it as from -> to
        uint32_t slot;
    };
    std::vector<Edge> edges;

    // Room for the grid's slots, all empty.
    void Reset(size_t slots) {
        Clear();
        if (at_.size() < slots)
            at_.resize(slots, kEmpty);
    }
    void Clear() {
        for (const Edge& d : edges)
            at_[d.slot] = kEmpty;
        edges.clear();
    }
    void Add(uint32_t slot, uint32_t from, uint32_t to, float weight) {
        uint32_t& at = at_[slot];
        if (at == kEmpty) {
            at = uint32_t(edges.size());
            edges.push_back({std::min(from, to), std::max(from, to), 0.0f, slot});
        }
        edges[at].weight += from < to ? weight : -weight;
    }

private:
    static constexpr uint32_t kEmpty = ~uint32_t(0);
    std::vector<uint32_t> at_;  // per slot: its entry in edges
};

// A cell: a triangle of grid vertices (a[k], b[k]) in fan triangle t, for point q, with
// their vertex indices (PenumbraGrid::VertexIndex; every level asks for them again).
struct Cell {
    uint32_t q;  // penumbra point
    uint16_t t;  // fan triangle
    uint8_t a[3], b[3];
    uint32_t v[3];
};

// What a pass allocates, kept per thread across passes (a pass runs per light and node: its
// ~20 vectors' malloc and free were ~1.5 % of the bunny's solve). Every field is reset or
// overwritten before use, so a pass computes the same whatever ran before it.
struct PenumbraScratch {
    std::vector<uint8_t> state, height, cut, aligned;
    std::vector<double> sign;
    std::vector<Vec3d> clip;
    std::vector<Cell> visible, cur, next, finest;
    std::vector<float> part;
    std::vector<uint32_t> traced, first, fill;
    std::vector<std::pair<const Cell*, float>> cells;
    std::vector<std::pair<uint32_t, uint32_t>> asked;  // (point, vertex)
    EdgeTable edges;
    SegmentBatch batch;
};

}  // namespace

class DirectLight::PenumbraPass {
public:
    PenumbraPass(const DirectLight& dl, const Light& l, std::span<const ReceiverPoint> points,
                 std::span<const size_t> penumbra, PenumbraScratch* scratch)
        : dl_(dl),
          l_(l),
          points_(points),
          penumbra_(penumbra),
          grid_{l.grid, l.vertices.size() - 2},
          g_(l.grid),
          nt_(grid_.nt),
          nv_(grid_.vertices()),
          s_(*scratch) {
        s_.state.assign(penumbra.size() * nv_, kUnknown);
        s_.height.assign(penumbra.size() * nv_, kHeightUnknown);
        PrepareHorizons();
        s_.clip.resize(6 * std::max<size_t>(3, l.vertices.size()));
        s_.visible.clear();
        // Room for twice the coarse level's cells (4 per fan triangle and point): the uniform
        // cells' list regrowing cost ~1 % of the bunny's solve in malloc and free.
        s_.visible.reserve(penumbra.size() * nt_ * 8);
    }

    // Vertex states from an earlier pass over the same points (or none), and the light's
    // own vertices from the classification rays.
    void SeedStates(std::span<const uint8_t> classified, bool centre_traced,
                    const uint8_t* prior) {
        const size_t nk = l_.classify.size();
        classified_ = classified;
        centre_ = centre_traced && l_.centre_t >= 0
                      ? grid_.VertexIndex(size_t(l_.centre_t), l_.centre_a, l_.centre_b)
                      : nv_;
        for (size_t q = 0; q < penumbra_.size(); ++q) {
            uint8_t* st = &s_.state[q * nv_];
            if (prior)
                std::copy(prior, prior + nv_, st);
            const uint8_t* cls = &classified[q * nk];
            for (size_t t = 0; t < nt_; ++t) {
                st[grid_.VertexIndex(t, 0, 0)] = cls[0] ? kHidden : kVisible;
                st[grid_.VertexIndex(t, g_, 0)] = cls[t + 1] ? kHidden : kVisible;
                st[grid_.VertexIndex(t, 0, g_)] = cls[t + 2] ? kHidden : kVisible;
            }
        }
    }

    // E of the visible part at each penumbra point: the visible cells' closed forms plus
    // each finest mixed cell's times its visible part (FinestParts), summed over the cells'
    // edges (Sum).
    void Run(std::vector<Vec3d>* e) {
        RefineCells();
        FinestParts();
        Sum(e);
    }

    // The vertex states, requests forgotten (for the probe cache).
    void TakeStates(std::vector<uint8_t>* states) {
        for (auto& st : s_.state)
            st = st == kRequested ? uint8_t(kUnknown) : st;
        states->swap(s_.state);
    }

private:
    Cell MakeCell(uint32_t q, size_t t, const uint8_t a[3], const uint8_t b[3]) const {
        Cell c{q, uint16_t(t), {a[0], a[1], a[2]}, {b[0], b[1], b[2]}, {}};
        for (int k = 0; k < 3; ++k)
            c.v[k] = uint32_t(grid_.VertexIndex(t, a[k], b[k]));
        return c;
    }

    // Per point: the sign that turns the Lambert sum into E (all cells lie in the light's
    // plane with its winding), and whether the horizon or the face plane cuts the light.
    void PrepareHorizons() {
        s_.sign.resize(penumbra_.size());
        s_.cut.resize(penumbra_.size());
        for (size_t q = 0; q < penumbra_.size(); ++q) {
            const ReceiverPoint& rp = points_[penumbra_[q]];
            const Vec3d x(rp.position), h(rp.horizon), f(rp.face);
            const double side = Dot(x - l_.vertices[0], l_.normal);
            s_.sign[q] = side > 0 ? -0.5 : l_.two_sided && side < 0 ? 0.5 : 0.0;
            s_.cut[q] = 0;
            for (const auto& v : l_.vertices)
                s_.cut[q] |= Dot(v - x, h) < 0 || Dot(v - x, f) < 0;
        }
    }

    // The coarse level into `cells`: each fan triangle of each point as 2 x 2 cells (or the
    // grid's own), but those wholly below the point's horizon.
    void InitialCells(std::vector<Cell>* cells) const {
        cells->clear();
        const int start = std::min(g_, 2), s = g_ / start;
        for (uint32_t q = 0; q < penumbra_.size(); ++q) {
            for (size_t t = 0; t < nt_; ++t) {
                for (int b = 0; b < g_; b += s) {
                    for (int a = 0; a + b < g_; a += s) {
                        const uint8_t ua[3] = {uint8_t(a), uint8_t(a + s), uint8_t(a)};
                        const uint8_t ub[3] = {uint8_t(b), uint8_t(b), uint8_t(b + s)};
                        cells->push_back(MakeCell(q, t, ua, ub));
                        if (Below(cells->back()))
                            cells->pop_back();
                        if (a + b + 2 * s <= g_) {
                            const uint8_t da[3] = {uint8_t(a + s), uint8_t(a + s), uint8_t(a)};
                            const uint8_t db[3] = {uint8_t(b), uint8_t(b + s), uint8_t(b + s)};
                            cells->push_back(MakeCell(q, t, da, db));
                            if (Below(cells->back()))
                                cells->pop_back();
                        }
                    }
                }
            }
        }
    }

    // The cell's E if it were wholly visible, above the point's horizon and face plane.
    Vec3d ClosedForm(const Cell& c) const {
        const Vec3d tri[3] = {l_.grid_pos[c.v[0]], l_.grid_pos[c.v[1]], l_.grid_pos[c.v[2]]};
        return AbovePlanes(tri, 3, c.q);
    }

    // E at point q of the polygon v[0..nv) where it is above the point's horizon and face
    // plane (clipped only where the light crosses them, cut).
    Vec3d AbovePlanes(const Vec3d* v, int nv, uint32_t q) const {
        const ReceiverPoint& rp = points_[penumbra_[q]];
        const Vec3d x(rp.position);
        if (!s_.cut[q])
            return LambertSum(v, nv, x) * s_.sign[q];
        // Each clip at most doubles the vertex count: 2 nv, then 4 nv (clip holds 6 x the
        // light's or a triangle's count).
        Vec3d* poly = s_.clip.data();
        Vec3d* both = s_.clip.data() + 2 * nv;
        const int n = ClipToHalfSpace(v, nv, x, Vec3d(rp.horizon), poly);
        if (n < 3)
            return Vec3d{};
        if (Dot(rp.face, rp.face) == 0)
            return LambertSum(poly, n, x) * s_.sign[q];
        const int m = ClipToHalfSpace(poly, n, x, Vec3d(rp.face), both);
        if (m < 3)
            return Vec3d{};
        return LambertSum(both, m, x) * s_.sign[q];
    }

    Vec3f Origin(uint32_t q) const {
        const ReceiverPoint& rp = points_[penumbra_[q]];
        return rp.vis_point + rp.normal * dl_.offset_;
    }

    // E counts only light above the point's (smooth) horizon, so a grid vertex well below it
    // (kHorizonMargin) gets no ray, and a cell is uniform when its other corners agree (the
    // part of it that counts lies on their side). A cell wholly below adds nothing: no rays,
    // no splitting (where the light sets, half of it can be).
    double Height(uint32_t q, size_t v) const {
        const ReceiverPoint& rp = points_[penumbra_[q]];
        const Vec3d d = l_.grid_pos[v] - Vec3d(rp.position);
        double h = Dot(d, Vec3d(rp.horizon));
        if (Dot(rp.face, rp.face) > 0)
            h = std::min(h, Dot(d, Vec3d(rp.face)));
        // h >= 0 exactly where ClipToHalfSpace keeps the vertex (no division to underflow).
        return h >= 0 ? h : h / std::max(Length(d), 1e-30);
    }
    // Height's verdict on a grid vertex, computed once per point and vertex (every level
    // asks again for the corners its cells share): kWellBelow, kJustBelow or kAboveHorizon.
    enum : uint8_t { kHeightUnknown = 0, kWellBelow, kJustBelow, kAboveHorizon };
    uint8_t HeightClass(uint32_t q, size_t v) const {
        uint8_t& h = s_.height[q * nv_ + v];
        if (h == kHeightUnknown) {
            const double x = Height(q, v);
            h = x >= 0 ? kAboveHorizon : x >= -kHorizonMargin ? kJustBelow : kWellBelow;
        }
        return h;
    }
    bool Above(uint32_t q, size_t v) const {
        return !s_.cut[q] || HeightClass(q, v) != kWellBelow;
    }
    // Above both planes, as ClipToHalfSpace decides it: a cell with all three corners so is
    // not clipped.
    bool Unclipped(uint32_t q, size_t v) const { return HeightClass(q, v) == kAboveHorizon; }
    bool Below(const Cell& c) const {
        if (!s_.cut[c.q])
            return false;
        for (int k = 0; k < 3; ++k)
            if (HeightClass(c.q, c.v[k]) == kAboveHorizon)
                return false;
        return true;
    }

    // A cell's corners not well below the horizon: how many are visible and hidden.
    void Corners(const Cell& c, int* visible, int* hidden) const {
        const uint8_t* st = &s_.state[c.q * nv_];
        *visible = *hidden = 0;
        for (int k = 0; k < 3; ++k) {
            const size_t v = c.v[k];
            if (!Above(c.q, v))
                continue;
            *visible += st[v] == kVisible;
            *hidden += st[v] == kHidden;
        }
    }

    // One ray per corner of `cells` whose visibility is not known yet, in one batch. The
    // light's centre (centre_) was a classification ray's end already: the same segment,
    // so its answer is taken (one ray fewer per penumbra point, the same states).
    void TraceCorners(const std::vector<Cell>& cells) {
        SegmentBatch& batch = s_.batch;
        batch.Clear();
        s_.asked.clear();
        const size_t nk = l_.classify.size();
        for (const Cell& c : cells) {
            for (int k = 0; k < 3; ++k) {
                const size_t v = c.v[k];
                uint8_t& st = s_.state[c.q * nv_ + v];
                if (st != kUnknown || !Above(c.q, v))
                    continue;
                if (v == centre_) {
                    st = classified_[c.q * nk + nk - 1] ? kHidden : kVisible;
                    continue;
                }
                st = kRequested;
                s_.asked.push_back({c.q, uint32_t(v)});
                batch.AddSegment(Origin(c.q), l_.grid_target[v]);
            }
        }
        batch.Trace(dl_.vis_, RayKind::kPenumbra);
        for (size_t r = 0; r < s_.asked.size(); ++r)
            s_.state[s_.asked[r].first * nv_ + s_.asked[r].second] =
                batch.occluded[r] ? kHidden : kVisible;
    }

    // Level by level: visible uniform cells go to visible (hidden ones and those wholly
    // below the horizon add nothing), mixed cells are split in four down to the finest grid,
    // the finest mixed cells go to finest, with their part from the corners (FinestParts).
    void RefineCells() {
        std::vector<Cell>& cur = s_.cur;
        std::vector<Cell>& next = s_.next;
        s_.finest.clear();
        s_.part.clear();
        InitialCells(&cur);
        // Every cell of a level has the same side (InitialCells' s, halved by each split).
        for (int side = g_ / std::min(g_, 2); !cur.empty(); side /= 2) {
            TraceCorners(cur);
            next.clear();
            for (const Cell& c : cur) {
                int visible, hidden;
                Corners(c, &visible, &hidden);
                if (visible == 0 || hidden == 0) {
                    if (hidden == 0)
                        s_.visible.push_back(c);
                    continue;
                }
                if (side <= 1) {
                    s_.finest.push_back(c);
                    s_.part.push_back(CornerPart(visible, hidden));
                } else {
                    Split(c, &next);
                }
            }
            std::swap(cur, next);
        }
    }

    // A finest mixed cell's visible part from its corners (FinestParts says why).
    static float CornerPart(int visible, int hidden) {
        return visible + hidden == 2 ? 0.5f : visible == 1 ? 0.25f : 0.75f;
    }

    // Midpoints of the edges 01, 12, 20; the four children (but those wholly below the
    // point's horizon).
    void Split(const Cell& c, std::vector<Cell>* out) const {
        const uint8_t ma[3] = {uint8_t((c.a[0] + c.a[1]) / 2), uint8_t((c.a[1] + c.a[2]) / 2),
                               uint8_t((c.a[2] + c.a[0]) / 2)};
        const uint8_t mb[3] = {uint8_t((c.b[0] + c.b[1]) / 2), uint8_t((c.b[1] + c.b[2]) / 2),
                               uint8_t((c.b[2] + c.b[0]) / 2)};
        uint32_t mv[3];
        for (int k = 0; k < 3; ++k)
            mv[k] = uint32_t(grid_.VertexIndex(c.t, ma[k], mb[k]));
        const Cell children[4] = {
            {c.q, c.t, {c.a[0], ma[0], ma[2]}, {c.b[0], mb[0], mb[2]}, {c.v[0], mv[0], mv[2]}},
            {c.q, c.t, {ma[0], c.a[1], ma[1]}, {mb[0], c.b[1], mb[1]}, {mv[0], c.v[1], mv[1]}},
            {c.q, c.t, {ma[2], ma[1], c.a[2]}, {mb[2], mb[1], c.b[2]}, {mv[2], mv[1], c.v[2]}},
            {c.q, c.t, {ma[0], ma[1], ma[2]}, {mb[0], mb[1], mb[2]}, {mv[0], mv[1], mv[2]}}};
        for (const Cell& child : children)
            if (!Below(child))
                out->push_back(child);
    }

    // The cell in canonical form: up (a,b) (a+1,b) (a,b+1) or down (a+1,b) (a+1,b+1) (a,b+1).
    static void Canonical(const Cell& c, int* a0, int* b0, bool* down) {
        *a0 = std::min({c.a[0], c.a[1], c.a[2]});
        *b0 = std::min({c.b[0], c.b[1], c.b[2]});
        *down = c.a[0] + c.a[1] + c.a[2] - 3 * *a0 == 2;
    }

    // Points where four or more mixed finest cells of one fan triangle lie in one row of a
    // cell family: a shadow edge runs along that row (into s_.aligned, per point).
    void AlignedPoints() {
        struct Span {
            int lo[3] = {1 << 20, 1 << 20, 1 << 20}, hi[3] = {-1, -1, -1}, count = 0;
        };
        std::vector<Span> spans(penumbra_.size() * nt_);  // per point and fan triangle
        for (const Cell& c : s_.finest) {
            int a0, b0;
            bool down;
            Canonical(c, &a0, &b0, &down);
            Span& sp = spans[c.q * nt_ + c.t];
            const int row[3] = {a0, b0, a0 + b0 + (down ? 1 : 0)};
            for (int f = 0; f < 3; ++f)
                sp.lo[f] = std::min(sp.lo[f], row[f]), sp.hi[f] = std::max(sp.hi[f], row[f]);
            ++sp.count;
        }
        s_.aligned.assign(spans.size() / std::max<size_t>(nt_, 1), 0);
        for (size_t k = 0; k < spans.size(); ++k) {
            const Span& sp = spans[k];
            s_.aligned[k / nt_] |= sp.count >= 4 && (sp.hi[0] == sp.lo[0] ||
                                                     sp.hi[1] == sp.lo[1] || sp.hi[2] == sp.lo[2]);
        }
    }

    // Finest cells that a shadow edge crosses count as partly visible without a ray: with one
    // corner visible, the visible part is the corner's triangle cut off by the edge, s t of
    // the cell for crossings at s and t along its two sides, 1/4 on average over uniform
    // crossings (two corners: 3/4), with less variance than one ray (1/9 - 1/16 against
    // 1/4 - 1/9). An edge parallel to a family of cell rows crosses them all at the same
    // offset, which biases that by up to half a row: at such points each mixed cell gets one
    // ray to a fixed point of an R2 low-discrepancy sequence indexed by the cell (part 0 or 1).
    // In s_.part, per finest cell (RefineCells put CornerPart there; the rays replace it at
    // aligned points).
    void FinestParts() {
        AlignedPoints();
        const std::vector<Cell>& finest = s_.finest;
        std::vector<float>& part = s_.part;
        SegmentBatch& batch = s_.batch;
        batch.Clear();
        s_.traced.clear();
        for (uint32_t k = 0; k < finest.size(); ++k) {
            const Cell& c = finest[k];
            if (!s_.aligned[c.q])
                continue;
            batch.AddSegment(Origin(c.q), SamplePoint(c));
            s_.traced.push_back(k);
        }
        batch.Trace(dl_.vis_, RayKind::kPenumbra);
        for (size_t r = 0; r < s_.traced.size(); ++r)
            part[s_.traced[r]] = batch.occluded[r] ? 0.0f : 1.0f;
    }

    // E = sum_cells w_c L(c), w = 1 for a visible cell and the part for a finest mixed one.
    // All cells wind the same way, so an edge two cells share appears once each way: it is
    // evaluated once, with the difference of their weights, and not at all between two
    // visible cells (the sum runs over the visible part's outline and the finest cells: the
    // same sum up to rounding; on the bunny 26.1M terms for the unclipped cells' 54.7M
    // edges). A cell that the point's horizon or face plane cuts is clipped and summed on
    // its own (ClosedForm).
    void Sum(std::vector<Vec3d>* e) {
        const std::vector<Cell>& visible = s_.visible;
        const std::vector<Cell>& finest = s_.finest;
        // The cells of each point, together: counting sort by point.
        std::vector<uint32_t>& first = s_.first;
        first.assign(penumbra_.size() + 1, 0);
        for (const Cell& c : visible)
            ++first[c.q + 1];
        for (const Cell& c : finest)
            ++first[c.q + 1];
        for (size_t q = 0; q < penumbra_.size(); ++q)
            first[q + 1] += first[q];
        auto& cells = s_.cells;
        cells.resize(first.back());
        std::vector<uint32_t>& fill = s_.fill;
        fill.assign(first.begin(), first.end() - 1);
        for (const Cell& c : visible)
            cells[fill[c.q]++] = {&c, 1.0f};
        for (size_t k = 0; k < finest.size(); ++k)
            cells[fill[finest[k].q]++] = {&finest[k], s_.part[k]};
        EdgeTable& edges = s_.edges;
        edges.Reset(grid_.EdgeSlots());
        for (uint32_t q = 0; q < penumbra_.size(); ++q) {
            edges.Clear();
            Vec3d clipped;
            for (uint32_t k = first[q]; k < first[q + 1]; ++k) {
                const Cell& c = *cells[k].first;
                const float w = cells[k].second;
                if (w == 0)
                    continue;
                if (s_.cut[q] &&
                    !(Unclipped(q, c.v[0]) && Unclipped(q, c.v[1]) && Unclipped(q, c.v[2]))) {
                    clipped += ClosedForm(c) * double(w);
                    continue;
                }
                for (int j = 0; j < 3; ++j) {
                    const int i = j == 2 ? 0 : j + 1;
                    edges.Add(grid_.EdgeSlot(c.t, c.a[j], c.b[j], c.a[i], c.b[i]), c.v[j],
                              c.v[i], w);
                }
            }
            const Vec3d x(points_[penumbra_[q]].position);
            Vec3d sum;
            for (const EdgeTable::Edge& d : edges.edges)
                if (d.weight != 0)
                    sum += LambertEdge(l_.grid_pos[d.from], l_.grid_pos[d.to], x) * double(d.weight);
            (*e)[q] += sum * s_.sign[q] + clipped;
        }
        edges.Clear();
    }

    // The cell's fixed low-discrepancy point (R2 sequence indexed by the cell).
    Vec3f SamplePoint(const Cell& c) const {
        int a0, b0;
        bool down;
        Canonical(c, &a0, &b0, &down);
        const uint64_t id = (uint64_t(c.t) * uint64_t(g_) + uint64_t(a0)) * uint64_t(2 * g_) +
                            uint64_t(2 * b0 + (down ? 1 : 0));
        double a = std::fmod(0.5 + 0.7548776662466927 * double(id + 1), 1.0);
        double b = std::fmod(0.5 + 0.5698402909980532 * double(id + 1), 1.0);
        if (a + b > 1)
            a = 1 - a, b = 1 - b;
        const Vec3d& p0 = l_.grid_pos[down ? grid_.VertexIndex(c.t, a0 + 1, b0)
                                           : grid_.VertexIndex(c.t, a0, b0)];
        const Vec3d& p1 = l_.grid_pos[down ? grid_.VertexIndex(c.t, a0 + 1, b0 + 1)
                                           : grid_.VertexIndex(c.t, a0 + 1, b0)];
        const Vec3d& p2 = l_.grid_pos[grid_.VertexIndex(c.t, a0, b0 + 1)];
        return Vec3f(p0 + (p1 - p0) * a + (p2 - p0) * b);
    }

    const DirectLight& dl_;
    const Light& l_;
    std::span<const ReceiverPoint> points_;
    std::span<const size_t> penumbra_;
    const PenumbraGrid grid_;
    const int g_;
    const size_t nt_, nv_;
    // Every buffer of the pass (state, height per point and grid vertex; the cells; the
    // batches), the calling thread's.
    PenumbraScratch& s_;
    std::span<const uint8_t> classified_;  // per point: occluded[] of its classify rays
    size_t centre_ = 0;                    // the centre's grid vertex (nv_: none reused)
};

void DirectLight::Penumbra(const Light& l, std::span<const ReceiverPoint> points,
                           std::span<const size_t> penumbra, std::span<const uint8_t> classified,
                           bool centre_traced, const uint8_t* prior, std::vector<Vec3d>* e,
                           std::vector<uint8_t>* states) const {
    e->assign(penumbra.size(), Vec3d{});
    if (penumbra.empty())
        return;
    ThreadScratch<PenumbraScratch> scratch;
    PenumbraPass pass(*this, l, points, penumbra, &*scratch);
    pass.SeedStates(classified, centre_traced, prior);
    pass.Run(e);
    if (states)
        pass.TakeStates(states);
}

}  // namespace mebake::solve
