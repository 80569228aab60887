// Uniform-grid point location with exact nearest-triangle queries for the master
// element's virtual part (see chart_grid.h).
//
// Why the per-cell candidate sets are exact: a point outside every triangle has its
// nearest chart point on the outline of the union of triangles, and with no flipped
// triangle that outline is made of boundary edges (a closed fan of counter-clockwise
// triangles covers a neighbourhood of its vertex). So the outline triangles (boundary
// edge, or flipped/zero area) always contain a nearest triangle. For a cell C, let T0 be
// the outline triangle nearest to C's centre and ub = max over C's corners of dist(corner,
// T0) (distance to a convex set is convex, so this bounds dist(p, T0) for all p in C).
// Any p in C has its nearest triangle T* within ub, and dist(C, T*) <= dist(p, T*) <= ub:
// keeping every outline triangle with dist(C, T) <= ub keeps T*. A cell that no outline
// triangle touches and whose centre is inside the chart is inside the chart entirely and
// needs no candidates.
#include "stream/chart_grid.h"

#include "core/check.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <utility>

namespace mebake::stream {

namespace {

// Points this close (in uv) to a triangle count as inside it: a few float ulps at 1.0,
// the resolution of the uv the grid is given.
constexpr double kInsideDistance = 0x1p-22;

struct Tri2 {
    Vec2d p[3];
};

Tri2 TriangleAt(const ChartGrid& g, uint32_t t) {
    Tri2 r;
    for (int k = 0; k < 3; ++k) {
        const Vec2f& q = g.uv[g.triangles[t][k]];
        r.p[k] = Vec2d(q.x, q.y);
    }
    return r;
}

// Signed barycentrics; false for a zero-area triangle.
bool Barycentric(const Tri2& t, const Vec2d& u, double b[3]) {
    const double area = Cross(t.p[1] - t.p[0], t.p[2] - t.p[0]);
    if (area == 0 || !std::isfinite(area))
        return false;
    b[0] = Cross(t.p[1] - u, t.p[2] - u) / area;
    b[1] = Cross(t.p[2] - u, t.p[0] - u) / area;
    b[2] = 1 - b[0] - b[1];
    return true;
}

struct Closest {
    double dist2 = INFINITY;
    double b[3] = {1, 0, 0};
    Vec2d point;
};

// Closest point of the edges of triangle t to u, with its barycentrics.
Closest ClosestOnEdges(const Tri2& t, const Vec2d& u) {
    Closest c;
    for (int k = 0; k < 3; ++k) {
        const Vec2d& a = t.p[k];
        const Vec2d e = t.p[(k + 1) % 3] - a;
        const double len2 = Dot(e, e);
        const double s = len2 > 0 ? std::clamp(Dot(u - a, e) / len2, 0.0, 1.0) : 0.0;
        const Vec2d q = a + e * s;
        const double d2 = Dot(u - q, u - q);
        if (d2 < c.dist2) {
            c.dist2 = d2;
            c.b[k] = 1 - s;
            c.b[(k + 1) % 3] = s;
            c.b[(k + 2) % 3] = 0;
            c.point = q;
        }
    }
    return c;
}

// Closest point of triangle t to u (u itself when inside), with its barycentrics.
Closest ClosestPoint(const Tri2& t, const Vec2d& u) {
    double b[3];
    if (Barycentric(t, u, b) && b[0] >= 0 && b[1] >= 0 && b[2] >= 0) {
        Closest c;
        c.dist2 = 0;
        std::copy(b, b + 3, c.b);
        c.point = u;
        return c;
    }
    return ClosestOnEdges(t, u);
}

struct Box {
    Vec2d lo, hi;
};

double PointBoxDist2(const Vec2d& p, const Box& b) {
    const double dx = std::max({b.lo.x - p.x, 0.0, p.x - b.hi.x});
    const double dy = std::max({b.lo.y - p.y, 0.0, p.y - b.hi.y});
    return dx * dx + dy * dy;
}

double BoxBoxDist2(const Box& a, const Box& b) {
    const double dx = std::max({b.lo.x - a.hi.x, 0.0, a.lo.x - b.hi.x});
    const double dy = std::max({b.lo.y - a.hi.y, 0.0, a.lo.y - b.hi.y});
    return dx * dx + dy * dy;
}

// Separating-axis test of a (closed) box and a triangle: the box axes and the triangle's
// edge normals. Works for zero-area triangles (segments) too.
bool Overlaps(const Tri2& t, const Box& b) {
    for (int axis = 0; axis < 2; ++axis) {
        const double lo = std::min({t.p[0][axis], t.p[1][axis], t.p[2][axis]});
        const double hi = std::max({t.p[0][axis], t.p[1][axis], t.p[2][axis]});
        if (hi < b.lo[axis] || lo > b.hi[axis])
            return false;
    }
    const Vec2d corners[4] = {b.lo, {b.hi.x, b.lo.y}, b.hi, {b.lo.x, b.hi.y}};
    for (int k = 0; k < 3; ++k) {
        const Vec2d e = t.p[(k + 1) % 3] - t.p[k];
        const Vec2d n(-e.y, e.x);
        if (n.x == 0 && n.y == 0)
            continue;
        const double tri_a = Dot(n, t.p[k]), tri_b = Dot(n, t.p[(k + 2) % 3]);
        const double tri_lo = std::min(tri_a, tri_b), tri_hi = std::max(tri_a, tri_b);
        double box_lo = INFINITY, box_hi = -INFINITY;
        for (const Vec2d& c : corners) {
            box_lo = std::min(box_lo, Dot(n, c));
            box_hi = std::max(box_hi, Dot(n, c));
        }
        if (box_hi < tri_lo || box_lo > tri_hi)
            return false;
    }
    return true;
}

Box BoxOf(const Tri2& t) {
    return {Vec2d(std::min({t.p[0].x, t.p[1].x, t.p[2].x}), std::min({t.p[0].y, t.p[1].y, t.p[2].y})),
            Vec2d(std::max({t.p[0].x, t.p[1].x, t.p[2].x}), std::max({t.p[0].y, t.p[1].y, t.p[2].y}))};
}

// Whether a triangle lies within sqrt(r2) of a box. Their distance is 0 if they overlap,
// else the least of the triangle's vertices' distances to the box and the box's corners'
// distances to the triangle, so any one of those within r2 decides: the cheap ones are
// tried first. Apart, no corner lies inside the triangle, so a corner's distance is to the
// triangle's edges (where rounding would put a corner inside, both are ~1e-32, far below
// any bound the grid compares them with).
bool TriBoxWithin(const Tri2& t, const Box& b, double r2) {
    for (const Vec2d& p : t.p)
        if (PointBoxDist2(p, b) <= r2)
            return true;
    if (Overlaps(t, b))
        return true;
    const Vec2d corners[4] = {b.lo, {b.hi.x, b.lo.y}, b.hi, {b.lo.x, b.hi.y}};
    for (const Vec2d& c : corners)
        if (ClosestOnEdges(t, c).dist2 <= r2)
            return true;
    return false;
}

// A bounding-volume hierarchy over the outline triangles, used at build time only.
class OutlineBvh {
public:
    explicit OutlineBvh(const std::vector<Tri2>& tris) : tris_(tris) {
        prims_.resize(tris.size());
        std::iota(prims_.begin(), prims_.end(), 0u);
        boxes_.resize(tris.size());
        for (size_t i = 0; i < tris.size(); ++i) {
            Box& b = boxes_[i];
            b.lo = b.hi = tris[i].p[0];
            for (const Vec2d& p : tris[i].p) {
                b.lo = Vec2d(std::min(b.lo.x, p.x), std::min(b.lo.y, p.y));
                b.hi = Vec2d(std::max(b.hi.x, p.x), std::max(b.hi.y, p.y));
            }
        }
        if (!tris.empty())
            BuildNode(0, uint32_t(tris.size()));
    }

    // Index (into the outline list) of the triangle nearest to u; lowest index on ties.
    // `hint` (an outline index or kNoTriangle), e.g. the previous cell's answer, only
    // tightens the search bound: equally near triangles are still visited, so the
    // answer does not depend on it.
    uint32_t Nearest(const Vec2d& u, uint32_t hint = kNoTriangle) {
        uint32_t best = kNoTriangle;
        double best_d2 = INFINITY;
        if (hint != kNoTriangle) {
            best = hint;
            best_d2 = ClosestPoint(tris_[hint], u).dist2;
        }
        std::vector<uint32_t>& stack = stack_;  // reused: no allocation per query
        stack.assign(1, 0);
        while (!stack.empty()) {
            const Node& node = nodes_[stack.back()];
            stack.pop_back();
            if (PointBoxDist2(u, node.box) > best_d2)
                continue;
            if (node.count > 0) {
                for (uint32_t i = node.first; i < node.first + node.count; ++i) {
                    const double d2 = ClosestPoint(tris_[prims_[i]], u).dist2;
                    if (d2 < best_d2 || (d2 == best_d2 && prims_[i] < best)) {
                        best_d2 = d2;
                        best = prims_[i];
                    }
                }
                continue;
            }
            // Visit the nearer child first (pushed last).
            const uint32_t l = node.first, r = node.first + 1;
            const bool left_first =
                PointBoxDist2(u, nodes_[l].box) <= PointBoxDist2(u, nodes_[r].box);
            stack.push_back(left_first ? r : l);
            stack.push_back(left_first ? l : r);
        }
        return best;
    }

    // Appends the outline indices of triangles within sqrt(r2) of box b.
    void WithinBox(const Box& b, double r2, std::vector<uint32_t>* out) {
        std::vector<uint32_t>& stack = stack_;  // reused: no allocation per query
        stack.assign(1, 0);
        while (!stack.empty()) {
            const Node& node = nodes_[stack.back()];
            stack.pop_back();
            if (BoxBoxDist2(b, node.box) > r2)
                continue;
            if (node.count > 0) {
                for (uint32_t i = node.first; i < node.first + node.count; ++i)
                    if (BoxBoxDist2(b, boxes_[prims_[i]]) <= r2 &&  // a lower bound, cheap
                        TriBoxWithin(tris_[prims_[i]], b, r2))
                        out->push_back(prims_[i]);
                continue;
            }
            stack.push_back(node.first);
            stack.push_back(node.first + 1);
        }
    }

private:
    struct Node {
        Box box;
        uint32_t first = 0;  // leaf: first primitive; inner: left child (right = first + 1)
        uint32_t count = 0;  // primitives in a leaf, 0 for an inner node
    };
    static constexpr uint32_t kLeafSize = 4;

    // Builds the tree over prims_[begin, end) with a work list (no recursion). Children
    // are allocated in pairs, so a node only stores its left child.
    void BuildNode(uint32_t begin, uint32_t end) {
        nodes_.push_back({});
        std::vector<std::array<uint32_t, 3>> work = {{0, begin, end}};  // node, begin, end
        while (!work.empty()) {
            const auto [index, lo, hi] = work.back();
            work.pop_back();
            Box box = boxes_[prims_[lo]];
            Box centres{{INFINITY, INFINITY}, {-INFINITY, -INFINITY}};
            for (uint32_t i = lo; i < hi; ++i) {
                const Box& b = boxes_[prims_[i]];
                box.lo = Vec2d(std::min(box.lo.x, b.lo.x), std::min(box.lo.y, b.lo.y));
                box.hi = Vec2d(std::max(box.hi.x, b.hi.x), std::max(box.hi.y, b.hi.y));
                const Vec2d c = (b.lo + b.hi) * 0.5;
                centres.lo = Vec2d(std::min(centres.lo.x, c.x), std::min(centres.lo.y, c.y));
                centres.hi = Vec2d(std::max(centres.hi.x, c.x), std::max(centres.hi.y, c.y));
            }
            nodes_[index].box = box;
            if (hi - lo <= kLeafSize) {
                nodes_[index].first = lo;
                nodes_[index].count = hi - lo;
                continue;
            }
            const int axis = (centres.hi.x - centres.lo.x) >= (centres.hi.y - centres.lo.y) ? 0 : 1;
            const uint32_t mid = lo + (hi - lo) / 2;
            std::nth_element(prims_.begin() + lo, prims_.begin() + mid, prims_.begin() + hi,
                             [&](uint32_t a, uint32_t b) {
                                 const double ca = boxes_[a].lo[axis] + boxes_[a].hi[axis];
                                 const double cb = boxes_[b].lo[axis] + boxes_[b].hi[axis];
                                 return ca < cb || (ca == cb && a < b);
                             });
            const uint32_t left = uint32_t(nodes_.size());
            nodes_.push_back({});
            nodes_.push_back({});
            nodes_[index].first = left;
            nodes_[index].count = 0;
            work.push_back({left, lo, mid});
            work.push_back({left + 1, mid, hi});
        }
    }

    const std::vector<Tri2>& tris_;
    std::vector<uint32_t> prims_;
    std::vector<Box> boxes_;
    std::vector<Node> nodes_;
    std::vector<uint32_t> stack_;
};

struct LocateResult {
    uint32_t triangle = kNoTriangle;
    double b[3] = {1, 0, 0};
    bool real = false;
    Vec2d nearest;
    double dist2 = 0;
};

// The real part of the query: true (and r filled) when u lies in a triangle of its cell,
// or within kInsideDistance of one.
bool LocateInside(const ChartGrid& g, const Vec2d& u, size_t cell, LocateResult* out) {
    LocateResult& r = *out;
    for (uint32_t i = g.cell_start[cell]; i < g.cell_start[cell + 1]; ++i) {
        double b[3];
        if (!Barycentric(TriangleAt(g, g.cell_tris[i]), u, b))
            continue;
        if (b[0] < 0 || b[1] < 0 || b[2] < 0)
            continue;
        r.triangle = g.cell_tris[i];
        std::copy(b, b + 3, r.b);
        r.real = true;
        r.nearest = u;
        return true;
    }
    // Within float resolution of a triangle (e.g. a rounded point of a boundary edge):
    // real, at the closest point. No triangle here contains u (the same barycentric test
    // just failed), so its closest point is on its edges, as ClosestPoint would find; those
    // lie in the triangle's box up to rounding (~1e-16), so a box over twice the distance
    // away cannot hold one (most of a virtual texel's cell: skipped at a box test's cost).
    double best2 = kInsideDistance * kInsideDistance;
    for (uint32_t i = g.cell_start[cell]; i < g.cell_start[cell + 1]; ++i) {
        const Tri2 t = TriangleAt(g, g.cell_tris[i]);
        if (PointBoxDist2(u, BoxOf(t)) > 4 * kInsideDistance * kInsideDistance)
            continue;
        const Closest c = ClosestOnEdges(t, u);
        if (c.dist2 <= best2 && (!r.real || c.dist2 < best2)) {
            best2 = c.dist2;
            r.triangle = g.cell_tris[i];
            std::copy(c.b, c.b + 3, r.b);
            r.real = true;
        }
    }
    if (r.real)
        r.nearest = u;
    return r.real;
}

// A lower bound of ClosestPoint(t, u).dist2 as computed: the distance to t's bounding box
// less 1e-12 per axis (the closest point's rounding is ~1e-16 in the unit square), and 0
// within 1e-9 of the box (where the rounded barycentric test could call u inside a sliver).
double NearestLowerBound2(const Tri2& t, const Vec2d& u) {
    const double lo_x = std::min({t.p[0].x, t.p[1].x, t.p[2].x});
    const double hi_x = std::max({t.p[0].x, t.p[1].x, t.p[2].x});
    const double lo_y = std::min({t.p[0].y, t.p[1].y, t.p[2].y});
    const double hi_y = std::max({t.p[0].y, t.p[1].y, t.p[2].y});
    const double dx = std::max({lo_x - u.x, 0.0, u.x - hi_x});
    const double dy = std::max({lo_y - u.y, 0.0, u.y - hi_y});
    if (!(std::max(dx, dy) > 1e-9))  // NaN too
        return 0;
    const double ex = std::max(dx - 1e-12, 0.0), ey = std::max(dy - 1e-12, 0.0);
    return (ex * ex + ey * ey) * (1 - 1e-12);
}

size_t CellOf(const ChartGrid& g, const Vec2d& u) {
    const int res = g.resolution;
    const int ix = std::min(int(u.x * res), res - 1), iy = std::min(int(u.y * res), res - 1);
    return size_t(iy) * res + ix;
}

Vec2d ClampToSquare(Vec2f u) {
    return Vec2d(std::clamp(double(u.x), 0.0, 1.0), std::clamp(double(u.y), 0.0, 1.0));
}

LocateResult LocateDouble(const ChartGrid& g, Vec2f u_in) {
    LocateResult r;
    if (g.triangles.empty())
        return r;
    const Vec2d u = ClampToSquare(u_in);
    const size_t cell = CellOf(g, u);
    if (LocateInside(g, u, cell, &r))
        return r;
    // Virtual. A cell without candidates is inside the chart, so only rounding brings u
    // here: fall back to all outline triangles, which is exact too.
    const uint32_t* begin = g.near_tris.data() + g.near_start[cell];
    const uint32_t* end = g.near_tris.data() + g.near_start[cell + 1];
    if (begin == end) {
        begin = g.outline_tris.data();
        end = begin + g.outline_tris.size();
    }
    // The nearest candidate, the lowest index among equally near ones, as a scan in index
    // order keeping the first strictly nearer one finds it. The candidate whose box is
    // nearest is measured first; then only those whose box is not farther than the best
    // distance found can be as near (most of a cell's candidates are not). A long list (the
    // fallback) is scanned plainly.
    const size_t n = size_t(end - begin);
    if (n == 0)
        return r;
    constexpr size_t kMaxBounds = 64;
    double bound[kMaxBounds];
    size_t first = 0;
    if (n <= kMaxBounds) {
        for (size_t k = 0; k < n; ++k) {
            bound[k] = NearestLowerBound2(TriangleAt(g, begin[k]), u);
            if (bound[k] < bound[first])
                first = k;
        }
    }
    r.dist2 = INFINITY;
    auto measure = [&](uint32_t t) {
        const Closest c = ClosestPoint(TriangleAt(g, t), u);
        if (c.dist2 < r.dist2 || (c.dist2 == r.dist2 && r.dist2 < INFINITY && t < r.triangle)) {
            r.dist2 = c.dist2;
            r.triangle = t;
            std::copy(c.b, c.b + 3, r.b);
            r.nearest = c.point;
        }
    };
    if (n > kMaxBounds) {
        for (size_t k = 0; k < n; ++k)
            measure(begin[k]);
        return r;
    }
    measure(begin[first]);
    for (size_t k = 0; k < n; ++k)
        if (k != first && !(bound[k] > r.dist2))
            measure(begin[k]);
    return r;
}

}  // namespace

int DefaultGridResolution(size_t triangle_count) {
    const double g = std::ceil(std::sqrt(double(triangle_count)));
    return int(std::clamp(g, 1.0, 2048.0));
}

ChartGrid BuildChartGrid(const std::vector<Vec2f>& uv,
                         const std::vector<std::array<uint32_t, 3>>& triangles, int resolution) {
    CHECK(resolution >= 1 && resolution <= 16384);
    ChartGrid g;
    g.resolution = resolution;
    g.uv = uv;
    g.triangles = triangles;
    const size_t tri_count = triangles.size();
    const size_t cell_count = size_t(resolution) * resolution;
    for (const auto& f : triangles)
        for (uint32_t v : f)
            CHECK_LT(v, uv.size());

    std::vector<Tri2> tris(tri_count);
    for (size_t t = 0; t < tri_count; ++t)
        tris[t] = TriangleAt(g, uint32_t(t));
    const double h = 1.0 / resolution;
    // Cells are closed boxes, widened by Locate's tolerance so that a point finds every
    // triangle within the tolerance in its own cell's list.
    const double pad = kInsideDistance;
    auto cell_box = [&](size_t c) {
        const double x = double(c % resolution) * h, y = double(c / resolution) * h;
        return Box{{x - pad, y - pad}, {x + h + pad, y + h + pad}};
    };
    auto cell_range = [&](double lo, double hi, int* first, int* last) {
        *first = std::clamp(int(std::floor((lo - pad) * resolution)), 0, resolution - 1);
        *last = std::clamp(int(std::floor((hi + pad) * resolution)), 0, resolution - 1);
    };

    // Triangles per cell, counted then filled (CSR, ascending triangle order per cell).
    g.cell_start.assign(cell_count + 1, 0);
    for (int pass = 0; pass < 2; ++pass) {
        std::vector<uint32_t> fill;
        if (pass == 1) {
            for (size_t c = 0; c < cell_count; ++c)
                g.cell_start[c + 1] += g.cell_start[c];
            g.cell_tris.resize(g.cell_start[cell_count]);
            fill.assign(g.cell_start.begin(), g.cell_start.end() - 1);
        }
        for (size_t t = 0; t < tri_count; ++t) {
            const Tri2& tri = tris[t];
            int x0, x1, y0, y1;
            cell_range(std::min({tri.p[0].x, tri.p[1].x, tri.p[2].x}),
                       std::max({tri.p[0].x, tri.p[1].x, tri.p[2].x}), &x0, &x1);
            cell_range(std::min({tri.p[0].y, tri.p[1].y, tri.p[2].y}),
                       std::max({tri.p[0].y, tri.p[1].y, tri.p[2].y}), &y0, &y1);
            for (int y = y0; y <= y1; ++y) {
                for (int x = x0; x <= x1; ++x) {
                    const size_t c = size_t(y) * resolution + x;
                    if (!Overlaps(tri, cell_box(c)))
                        continue;
                    if (pass == 0)
                        ++g.cell_start[c + 1];
                    else
                        g.cell_tris[fill[c]++] = uint32_t(t);
                }
            }
        }
    }

    // Outline triangles: an edge not matched by exactly one oppositely oriented twin, or
    // a uv orientation that is not counter-clockwise.
    std::vector<char> outline(tri_count, 0);
    {
        struct HalfEdge {
            uint64_t key;  // (min, max) vertex pair
            uint32_t tri;
            bool forward;  // min -> max
        };
        std::vector<HalfEdge> edges;
        edges.reserve(3 * tri_count);
        for (size_t t = 0; t < tri_count; ++t) {
            for (int k = 0; k < 3; ++k) {
                const uint32_t a = triangles[t][k], b = triangles[t][(k + 1) % 3];
                edges.push_back(
                    {(uint64_t(std::min(a, b)) << 32) | std::max(a, b), uint32_t(t), a < b});
            }
            const Tri2& tri = tris[t];
            if (!(Cross(tri.p[1] - tri.p[0], tri.p[2] - tri.p[0]) > 0))
                outline[t] = 1;
        }
        std::sort(edges.begin(), edges.end(), [](const HalfEdge& a, const HalfEdge& b) {
            return a.key < b.key || (a.key == b.key && a.tri < b.tri);
        });
        for (size_t i = 0; i < edges.size();) {
            size_t j = i;
            while (j < edges.size() && edges[j].key == edges[i].key)
                ++j;
            const bool interior = j - i == 2 && edges[i].forward != edges[i + 1].forward;
            if (!interior)
                for (size_t k = i; k < j; ++k)
                    outline[edges[k].tri] = 1;
            i = j;
        }
    }
    for (size_t t = 0; t < tri_count; ++t)
        if (outline[t])
            g.outline_tris.push_back(uint32_t(t));
    if (g.outline_tris.empty()) {  // a closed surface: keep the query exact regardless
        g.outline_tris.resize(tri_count);
        std::iota(g.outline_tris.begin(), g.outline_tris.end(), 0u);
        std::fill(outline.begin(), outline.end(), 1);
    }

    std::vector<Tri2> outline_geom(g.outline_tris.size());
    for (size_t i = 0; i < g.outline_tris.size(); ++i)
        outline_geom[i] = tris[g.outline_tris[i]];
    OutlineBvh bvh(outline_geom);

    g.near_start.assign(cell_count + 1, 0);
    std::vector<uint32_t> found;
    uint32_t previous_nearest = kNoTriangle;
    for (size_t c = 0; c < cell_count; ++c) {
        g.near_start[c + 1] = g.near_start[c];
        if (tri_count == 0)
            continue;
        const Box box = cell_box(c);
        const Vec2d centre = (box.lo + box.hi) * 0.5;
        bool touches_outline = false, centre_inside = false;
        for (uint32_t i = g.cell_start[c]; i < g.cell_start[c + 1]; ++i) {
            const uint32_t t = g.cell_tris[i];
            if (outline[t]) {
                touches_outline = true;
                break;
            }
            double b[3];
            if (!centre_inside && Barycentric(tris[t], centre, b))
                centre_inside = b[0] >= 0 && b[1] >= 0 && b[2] >= 0;
        }
        if (!touches_outline && centre_inside)
            continue;

        const uint32_t nearest = bvh.Nearest(centre, previous_nearest);
        previous_nearest = nearest;
        double ub2 = 0;
        const Vec2d corners[4] = {box.lo, {box.hi.x, box.lo.y}, box.hi, {box.lo.x, box.hi.y}};
        for (const Vec2d& corner : corners)
            ub2 = std::max(ub2, ClosestPoint(outline_geom[nearest], corner).dist2);
        // Slack for rounding in the distance computations.
        const double ub = std::sqrt(ub2) * (1 + 1e-9) + 1e-12;
        found.clear();
        bvh.WithinBox(box, ub * ub, &found);
        for (uint32_t& f : found)
            f = g.outline_tris[f];
        std::sort(found.begin(), found.end());
        g.near_tris.insert(g.near_tris.end(), found.begin(), found.end());
        g.near_start[c + 1] = uint32_t(g.near_tris.size());
    }
    return g;
}

namespace {

GridLocation ToGridLocation(const LocateResult& r) {
    GridLocation out;
    out.triangle = r.triangle;
    out.real = r.real;
    for (int k = 0; k < 3; ++k)
        out.barycentric[k] = float(r.b[k]);
    out.nearest_uv = Vec2f(float(r.nearest.x), float(r.nearest.y));
    out.distance = float(std::sqrt(r.dist2));
    return out;
}

}  // namespace

GridLocation ChartGrid::Locate(Vec2f u) const {
    return ToGridLocation(LocateDouble(*this, u));
}

GridLocation ChartGrid::LocateReal(Vec2f u_in) const {
    if (triangles.empty())
        return {};
    const Vec2d u = ClampToSquare(u_in);
    LocateResult r;
    return LocateInside(*this, u, CellOf(*this, u), &r) ? ToGridLocation(r) : GridLocation{};
}

uint32_t ChartGrid::InsideTriangle(Vec2f u_in) const {
    if (triangles.empty())
        return kNoTriangle;
    const Vec2d u = ClampToSquare(u_in);
    LocateResult r;
    return LocateInside(*this, u, CellOf(*this, u), &r) ? r.triangle : kNoTriangle;
}

size_t ChartGrid::MemoryBytes() const {
    return uv.size() * sizeof(Vec2f) + triangles.size() * sizeof(triangles[0]) +
           (cell_start.size() + cell_tris.size() + near_start.size() + near_tris.size() +
            outline_tris.size()) *
               sizeof(uint32_t);
}

SurfacePoint Evaluate(const ChartGrid& grid, std::span<const Vec3f> position,
                      std::span<const Vec3f> vertex_normal, Vec2f u) {
    SurfacePoint s;
    const LocateResult r = LocateDouble(grid, u);
    if (r.triangle == kNoTriangle)
        return s;
    const auto& f = grid.triangles[r.triangle];
    const Vec3d p[3] = {Vec3d(position[f[0]]), Vec3d(position[f[1]]), Vec3d(position[f[2]])};
    const Vec3d at = p[0] * r.b[0] + p[1] * r.b[1] + p[2] * r.b[2];
    const Vec3d face_normal = Normalize(Cross(p[1] - p[0], p[2] - p[0]));
    s.triangle = r.triangle;
    s.real = r.real;
    s.visible_position = Vec3f(at);
    if (r.real) {
        s.position = s.visible_position;
        const Vec3d n =
            Normalize(Vec3d(vertex_normal[f[0]]) * r.b[0] + Vec3d(vertex_normal[f[1]]) * r.b[1] +
                      Vec3d(vertex_normal[f[2]]) * r.b[2]);
        s.normal = Vec3f(Dot(n, n) > 0 ? n : face_normal);
        return s;
    }
    // J = [p1 - p0, p2 - p0] Q^-1 with Q = [q1 - q0, q2 - q0] (uv edges as columns).
    const Tri2 t = TriangleAt(grid, r.triangle);
    const Vec2d q1 = t.p[1] - t.p[0], q2 = t.p[2] - t.p[0];
    const double det = Cross(q1, q2);
    Vec3d extrapolated = at;
    if (det != 0) {
        const Vec2d d(double(std::clamp(u.x, 0.f, 1.f)) - r.nearest.x,
                      double(std::clamp(u.y, 0.f, 1.f)) - r.nearest.y);
        // Q^-1 d = (cross(d, q2), cross(q1, d)) / det.
        const double a = Cross(d, q2) / det, b = Cross(q1, d) / det;
        extrapolated = at + (p[1] - p[0]) * a + (p[2] - p[0]) * b;
    }
    s.position = Vec3f(extrapolated);
    s.normal = Vec3f(face_normal);
    return s;
}

std::vector<Vec3f> VertexNormals(std::span<const Vec3f> position,
                                 std::span<const std::array<uint32_t, 3>> triangles) {
    std::vector<Vec3d> sum(position.size());
    for (const auto& f : triangles) {
        const Vec3d p[3] = {Vec3d(position[f[0]]), Vec3d(position[f[1]]), Vec3d(position[f[2]])};
        const Vec3d n = Normalize(Cross(p[1] - p[0], p[2] - p[0]));
        for (int k = 0; k < 3; ++k) {
            const Vec3d a = Normalize(p[(k + 1) % 3] - p[k]), b = Normalize(p[(k + 2) % 3] - p[k]);
            const double angle = std::acos(std::clamp(Dot(a, b), -1.0, 1.0));
            sum[f[k]] += n * angle;
        }
    }
    std::vector<Vec3f> out(position.size());
    for (size_t v = 0; v < sum.size(); ++v)
        out[v] = Vec3f(Normalize(sum[v]));
    return out;
}

}  // namespace mebake::stream
