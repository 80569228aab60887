#include "solve/direct.h"

#include "core/check.h"
#include "solve/polygon_light.h"
#include "solve/rays.h"
#include "solve/visibility.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <numeric>

namespace mebake::solve {
namespace {

// Penumbrae: light-grid vertices more than this (sine of the angle, ~3.4 degrees) below a
// point's smooth horizon get no visibility ray and do not decide whether a cell is uniform.
// E ignores light below that horizon, but the real surface departs from it: just below, a
// visible vertex still says the light above it is visible (a convex bump falls away). At 0
// the noisy sphere's penumbra rays halve again but the bunny's error grew by 0.03 points;
// 0.06 left it unchanged (bench/RESULTS.md, "Speed, session 3").
constexpr double kHorizonMargin = 0.06;

// The point with barycentrics (a, b) in fan triangle `tri` of a polygon.
Vec3d PolygonPoint(const std::vector<Vec3d>& v, size_t tri, double a, double b) {
    return v[0] + (v[tri + 1] - v[0]) * a + (v[tri + 2] - v[0]) * b;
}

// Orthonormal frame with n as z (Duff et al. 2017).
void Frame(const Vec3f& n, Vec3f* t, Vec3f* b) {
    float sign = std::copysign(1.0f, n.z);
    float a = -1.0f / (sign + n.z);
    float c = n.x * n.y * a;
    *t = Vec3f(1.0f + sign * n.x * n.x * a, sign * c, -sign * n.x);
    *b = Vec3f(c, sign + n.y * n.y * a, -n.y);
}

}  // namespace

std::vector<Vec3d> ClipToHalfSpace(std::span<const Vec3d> poly, const Vec3d& x, const Vec3d& n) {
    std::vector<Vec3d> out(2 * poly.size());
    out.resize(size_t(ClipToHalfSpace(poly.data(), int(poly.size()), x, n, out.data())));
    return out;
}

DirectLight::DirectLight(const Scene& scene, const SolverSettings& settings,
                         const VisibilityScene& vis, float ray_offset, float scene_size)
    : vis_(vis), sky_(scene.sky), offset_(ray_offset), far_(scene_size * 100) {
    const int per_tri =
        std::max(2, int(std::ceil(std::sqrt(double(settings.light_samples)) - 1e-9)));
    for (const auto& pl : scene.lights) {
        Light l;
        l.vertices = pl.vertices;
        l.radiance = pl.radiance;
        l.two_sided = pl.two_sided;
        l.normal = PolygonNormal(pl.vertices);
        l.area = PolygonArea(pl.vertices);
        if (l.area <= 0)
            continue;
        Vec3d centre{};
        for (const auto& v : l.vertices)
            centre += v;
        centre = centre / double(l.vertices.size());
        // Classification points: vertices pulled 1% toward the centre, and the centre.
        for (const auto& v : l.vertices)
            l.classify.push_back(Vec3f(v + (centre - v) * 0.01));
        l.classify.push_back(Vec3f(centre));
        // Penumbra grid: per_tri cells per side of each fan triangle, a power of two so
        // that cells halve down to it.
        l.grid = 1;
        while (l.grid < per_tri && l.grid < 64)
            l.grid *= 2;
        const int g1 = l.grid + 1;
        for (size_t t = 0; t + 2 < l.vertices.size(); ++t) {
            for (int b = 0; b < g1; ++b) {
                for (int a = 0; a < g1; ++a) {
                    const Vec3d p =
                        PolygonPoint(l.vertices, t, double(a) / l.grid, double(b) / l.grid);
                    l.grid_pos.push_back(p);
                    l.grid_target.push_back(Vec3f(p + (centre - p) * 0.01));
                }
            }
        }
        lights_.push_back(std::move(l));
    }
    if (sky_.type != Sky::Type::None) {
        // Uniform directions (pdf 1 / (2 pi)), stratified in up . w (k rings of equal
        // area, midpoints) and azimuth (k per ring, each ring turned by the golden angle).
        // Not cosine-weighted about up: E . n for a tilted n weighs near-horizon directions
        // by tan(zenith) against that density, and an 11 x 11 cosine grid missed 24% of a
        // vertical face's sky. This rule is exact for an upward face (the rings' mean
        // height is 1/2) and within 0.5% for most tilts (1.5% facing nearly down).
        const int k = std::max(2, int(std::lround(std::sqrt(double(settings.sky_directions)))));
        for (int i = 0; i < k; ++i) {
            const double z = (i + 0.5) / k, radius = std::sqrt(1 - z * z);
            for (int j = 0; j < k; ++j) {
                const double phi = 2 * std::numbers::pi * (j + 0.5 + 0.618034 * i) / k;
                sky_dirs_.push_back(
                    Vec3f(float(radius * std::cos(phi)), float(radius * std::sin(phi)), float(z)));
            }
        }
    }
}

double DirectLight::EmittedPower() const {
    double p = 0;
    for (const auto& l : lights_) {
        double lum = (l.radiance.x + l.radiance.y + l.radiance.z) / 3;
        p += std::numbers::pi * lum * l.area * (l.two_sided ? 2 : 1);
    }
    return p;
}

// Penumbra of one light at the given points. Per point, the light's fan triangles start as
// 2 x 2 grids of cells whose corners are tested with one ray each (the classification rays
// give the light's own vertices); a cell whose corners agree is taken as wholly visible or
// hidden, one whose corners disagree is split in four, down to the finest grid, where a mixed
// cell counts as 1/4 or 3/4 visible (or, where the shadow edge runs along a row of cells, is
// visible as one fixed low-discrepancy point in it is). Corners well below the point's
// horizon are not traced and do not count. Rays go only where a shadow edge crosses the
// light, and all points of a level share one Embree batch.
void DirectLight::Penumbra(const Light& l, std::span<const ReceiverPoint> points,
                           std::span<const size_t> penumbra, std::span<const uint8_t> classified,
                           const uint8_t* prior, std::vector<Vec3d>* e,
                           std::vector<uint8_t>* states) const {
    e->assign(penumbra.size(), Vec3d{});
    if (penumbra.empty())
        return;
    const int g = l.grid, g1 = g + 1;
    const size_t nt = l.vertices.size() - 2, per_t = size_t(g1) * size_t(g1);
    const size_t nv = nt * per_t, nk = l.classify.size();
    // Vertex states per point: 0 unknown, 1 requested, 2 visible, 3 hidden.
    std::vector<uint8_t> state(penumbra.size() * nv, 0);
    // Fan triangles t and t+1 share the edge v0 v[t+2]: its vertices (a, 0) in t+1 are
    // (0, a) in t (the same point, computed the same way), so they are traced once.
    auto vidx = [&](size_t t, int a, int b) {
        if (b == 0 && t > 0)
            return (t - 1) * per_t + size_t(a) * size_t(g1);
        return t * per_t + size_t(b) * size_t(g1) + size_t(a);
    };
    for (size_t q = 0; q < penumbra.size(); ++q) {
        uint8_t* st = &state[q * nv];
        if (prior)
            std::copy(prior, prior + nv, st);
        const uint8_t* cls = &classified[q * nk];
        for (size_t t = 0; t < nt; ++t) {
            st[vidx(t, 0, 0)] = cls[0] ? 3 : 2;
            st[vidx(t, g, 0)] = cls[t + 1] ? 3 : 2;
            st[vidx(t, 0, g)] = cls[t + 2] ? 3 : 2;
        }
    }
    struct Cell {
        uint32_t q;  // penumbra point
        uint16_t t;  // fan triangle
        uint8_t a[3], b[3];
    };
    std::vector<Cell> cur, next, finest;
    const int start = std::min(g, 2);
    for (uint32_t q = 0; q < penumbra.size(); ++q) {
        for (size_t t = 0; t < nt; ++t) {
            const int s = g / start;
            for (int b = 0; b < g; b += s) {
                for (int a = 0; a + b < g; a += s) {
                    cur.push_back({q,
                                   uint16_t(t),
                                   {uint8_t(a), uint8_t(a + s), uint8_t(a)},
                                   {uint8_t(b), uint8_t(b), uint8_t(b + s)}});
                    if (a + b + 2 * s <= g)
                        cur.push_back({q,
                                       uint16_t(t),
                                       {uint8_t(a + s), uint8_t(a + s), uint8_t(a)},
                                       {uint8_t(b), uint8_t(b + s), uint8_t(b + s)}});
                }
            }
        }
    }
    // Per point: the sign that turns the Lambert sum into E (all cells lie in the light's
    // plane with its winding), and whether the horizon plane cuts the light at all.
    std::vector<double> sign(penumbra.size());
    std::vector<uint8_t> cut(penumbra.size());
    for (size_t q = 0; q < penumbra.size(); ++q) {
        const ReceiverPoint& rp = points[penumbra[q]];
        const Vec3d x(rp.position), h(rp.horizon);
        const double side = Dot(x - l.vertices[0], l.normal);
        sign[q] = side > 0 ? -0.5 : l.two_sided && side < 0 ? 0.5 : 0.0;
        cut[q] = 0;
        for (const auto& v : l.vertices)
            cut[q] |= Dot(v - x, h) < 0;
    }
    auto closed_form = [&](const Cell& c) {
        const Vec3d tri[3] = {l.grid_pos[vidx(c.t, c.a[0], c.b[0])],
                              l.grid_pos[vidx(c.t, c.a[1], c.b[1])],
                              l.grid_pos[vidx(c.t, c.a[2], c.b[2])]};
        const ReceiverPoint& rp = points[penumbra[c.q]];
        const Vec3d x(rp.position);
        if (!cut[c.q])
            return LambertSum(tri, 3, x) * sign[c.q];
        Vec3d poly[6];
        const int n = ClipToHalfSpace(tri, 3, x, Vec3d(rp.horizon), poly);
        if (n < 3)
            return Vec3d{};
        return LambertSum(poly, n, x) * sign[c.q];
    };
    auto origin = [&](uint32_t q) {
        const ReceiverPoint& rp = points[penumbra[q]];
        return rp.vis_point + rp.normal * offset_;
    };
    SegmentBatch batch;
    std::vector<std::pair<uint32_t, uint32_t>> asked;  // (point, vertex)
    // E counts only light above the point's (smooth) horizon, so a grid vertex well below it
    // (kHorizonMargin) gets no ray, and a cell is uniform when its other corners agree (the
    // part of it that counts lies on their side). A cell wholly below adds nothing: no rays,
    // no splitting (where the light sets, half of it can be).
    auto height = [&](uint32_t q, size_t v) {
        const ReceiverPoint& rp = points[penumbra[q]];
        const Vec3d d = l.grid_pos[v] - Vec3d(rp.position);
        return Dot(d, Vec3d(rp.horizon)) / std::max(Length(d), 1e-30);
    };
    auto above = [&](uint32_t q, size_t v) {
        return !cut[q] || height(q, v) >= -kHorizonMargin;
    };
    auto below = [&](const Cell& c) {
        if (!cut[c.q])
            return false;
        for (int k = 0; k < 3; ++k)
            if (height(c.q, vidx(c.t, c.a[k], c.b[k])) >= 0)
                return false;
        return true;
    };
    // A cell's corners not well below the horizon: how many are visible and hidden.
    auto corners = [&](const Cell& c, int* visible, int* hidden) {
        const uint8_t* st = &state[c.q * nv];
        *visible = *hidden = 0;
        for (int k = 0; k < 3; ++k) {
            const size_t v = vidx(c.t, c.a[k], c.b[k]);
            if (!above(c.q, v))
                continue;
            *visible += st[v] == 2;
            *hidden += st[v] == 3;
        }
    };
    while (!cur.empty()) {
        cur.erase(std::remove_if(cur.begin(), cur.end(), below), cur.end());
        batch.Clear();
        asked.clear();
        for (const Cell& c : cur) {
            for (int k = 0; k < 3; ++k) {
                const size_t v = vidx(c.t, c.a[k], c.b[k]);
                uint8_t& st = state[c.q * nv + v];
                if (st != 0 || !above(c.q, v))
                    continue;
                st = 1;
                asked.push_back({c.q, uint32_t(v)});
                batch.AddSegment(origin(c.q), l.grid_target[v]);
            }
        }
        batch.Trace(vis_, RayKind::kPenumbra);
        for (size_t r = 0; r < asked.size(); ++r)
            state[asked[r].first * nv + asked[r].second] = batch.occluded[r] ? 3 : 2;
        next.clear();
        for (const Cell& c : cur) {
            int visible, hidden;
            corners(c, &visible, &hidden);
            if (visible == 0 || hidden == 0) {
                if (hidden == 0)
                    (*e)[c.q] += closed_form(c);
                continue;
            }
            int side = 0;
            for (int k = 0; k < 3; ++k)
                side = std::max({side, std::abs(int(c.a[k]) - int(c.a[(k + 1) % 3])),
                                 std::abs(int(c.b[k]) - int(c.b[(k + 1) % 3]))});
            if (side <= 1) {
                finest.push_back(c);
                continue;
            }
            // Midpoints of the edges 01, 12, 20; the four children.
            const uint8_t ma[3] = {uint8_t((c.a[0] + c.a[1]) / 2), uint8_t((c.a[1] + c.a[2]) / 2),
                                   uint8_t((c.a[2] + c.a[0]) / 2)};
            const uint8_t mb[3] = {uint8_t((c.b[0] + c.b[1]) / 2), uint8_t((c.b[1] + c.b[2]) / 2),
                                   uint8_t((c.b[2] + c.b[0]) / 2)};
            next.push_back({c.q, c.t, {c.a[0], ma[0], ma[2]}, {c.b[0], mb[0], mb[2]}});
            next.push_back({c.q, c.t, {ma[0], c.a[1], ma[1]}, {mb[0], c.b[1], mb[1]}});
            next.push_back({c.q, c.t, {ma[2], ma[1], c.a[2]}, {mb[2], mb[1], c.b[2]}});
            next.push_back({c.q, c.t, {ma[0], ma[1], ma[2]}, {mb[0], mb[1], mb[2]}});
        }
        std::swap(cur, next);
    }
    // Finest cells that a shadow edge crosses (all made by the last level) count as partly
    // visible without a ray: with one corner visible, the visible part is the corner's
    // triangle cut off by the edge, s t of the cell for crossings at s and t along its two
    // sides, 1/4 on average over uniform crossings (two corners: 3/4), with less variance than
    // one ray (1/9 - 1/16 against 1/4 - 1/9). An edge parallel to a family of cell rows crosses
    // them all at the same offset, which biases that by up to half a row: where four or more
    // of a point's mixed cells in a fan triangle lie in one row of a family, each mixed cell
    // of the point gets one ray to a fixed point of an R2 low-discrepancy sequence indexed by
    // the cell (a shadow edge parallel to cell rows cuts the samples at varied offsets).
    struct Span {
        int lo[3] = {1 << 20, 1 << 20, 1 << 20}, hi[3] = {-1, -1, -1}, count = 0;
    };
    std::vector<Span> spans(penumbra.size() * nt);  // per point and fan triangle
    auto canonical = [](const Cell& c, int* a0, int* b0, bool* down) {
        *a0 = std::min({c.a[0], c.a[1], c.a[2]});
        *b0 = std::min({c.b[0], c.b[1], c.b[2]});
        *down = c.a[0] + c.a[1] + c.a[2] - 3 * *a0 == 2;
    };
    for (const Cell& c : finest) {
        int a0, b0;
        bool down;
        canonical(c, &a0, &b0, &down);
        Span& sp = spans[c.q * nt + c.t];
        const int row[3] = {a0, b0, a0 + b0 + (down ? 1 : 0)};
        for (int f = 0; f < 3; ++f)
            sp.lo[f] = std::min(sp.lo[f], row[f]), sp.hi[f] = std::max(sp.hi[f], row[f]);
        ++sp.count;
    }
    std::vector<uint8_t> aligned(spans.size() / std::max<size_t>(nt, 1), 0);
    for (size_t k = 0; k < spans.size(); ++k) {
        const Span& sp = spans[k];
        aligned[k / nt] |=
            sp.count >= 4 && (sp.hi[0] == sp.lo[0] || sp.hi[1] == sp.lo[1] || sp.hi[2] == sp.lo[2]);
    }
    batch.Clear();
    std::vector<uint32_t> traced;
    for (uint32_t k = 0; k < finest.size(); ++k) {
        const Cell& c = finest[k];
        if (!aligned[c.q]) {
            int visible, hidden;
            corners(c, &visible, &hidden);
            (*e)[c.q] += closed_form(c) * (visible + hidden == 2 ? 0.5
                                           : visible == 1        ? 0.25
                                                                 : 0.75);
            continue;
        }
        // The cell in canonical form: up (a,b) (a+1,b) (a,b+1) or down (a+1,b) (a+1,b+1) (a,b+1).
        int a0, b0;
        bool down;
        canonical(c, &a0, &b0, &down);
        const uint64_t id = (uint64_t(c.t) * uint64_t(g) + uint64_t(a0)) * uint64_t(2 * g) +
                            uint64_t(2 * b0 + (down ? 1 : 0));
        double a = std::fmod(0.5 + 0.7548776662466927 * double(id + 1), 1.0);
        double b = std::fmod(0.5 + 0.5698402909980532 * double(id + 1), 1.0);
        if (a + b > 1)
            a = 1 - a, b = 1 - b;
        const Vec3d& p0 = l.grid_pos[down ? vidx(c.t, a0 + 1, b0) : vidx(c.t, a0, b0)];
        const Vec3d& p1 = l.grid_pos[down ? vidx(c.t, a0 + 1, b0 + 1) : vidx(c.t, a0 + 1, b0)];
        const Vec3d& p2 = l.grid_pos[vidx(c.t, a0, b0 + 1)];
        batch.AddSegment(origin(c.q), Vec3f(p0 + (p1 - p0) * a + (p2 - p0) * b));
        traced.push_back(k);
    }
    batch.Trace(vis_, RayKind::kPenumbra);
    for (size_t r = 0; r < traced.size(); ++r)
        if (!batch.occluded[r])
            (*e)[finest[traced[r]].q] += closed_form(finest[traced[r]]);
    if (states) {
        for (auto& st : state)
            st = st == 1 ? 0 : st;
        *states = std::move(state);
    }
}

// One light at the points `which`. prior_cls / prior_grid (may be null): visibility states
// (2 visible, 3 hidden, 0 unknown) of the classification targets / grid vertices taken as
// known for every point, so no ray is spent on them. cls_out / grid_out (may be null)
// receive every point's states, for use as a prior elsewhere: a fully lit point counts as
// seeing every vertex, an umbra point none, a point the light cannot reach is unknown.
void DirectLight::EvaluateLight(const Light& l, std::span<const ReceiverPoint> points,
                                std::span<const size_t> which, const uint8_t* prior_cls,
                                const uint8_t* prior_grid, std::span<float> out,
                                std::vector<uint8_t>* cls_out,
                                std::vector<uint8_t>* grid_out) const {
    const size_t nk = l.classify.size();
    const size_t nv = (l.vertices.size() - 2) * size_t(l.grid + 1) * size_t(l.grid + 1);
    // 1. Classify each point with a few rays (skip points the light cannot reach).
    SegmentBatch batch;
    std::vector<uint8_t> faces(which.size(), 0), cls(which.size() * nk, 0);
    std::vector<std::pair<size_t, size_t>> asked;
    for (size_t q = 0; q < which.size(); ++q) {
        const auto& rp = points[which[q]];
        // E does not involve the receiver's normal (that is what keeps it smooth on
        // noisy scans): what lies below the surface is removed by visibility alone.
        double side = Dot(Vec3d(rp.position) - l.vertices[0], l.normal);
        bool above = Dot(rp.horizon, rp.horizon) == 0;
        for (const auto& v : l.vertices)
            above |= Dot(v - Vec3d(rp.position), Vec3d(rp.horizon)) > 0;
        faces[q] = (side > 0 || (l.two_sided && side < 0)) && above;
        if (!faces[q])
            continue;
        const Vec3f o = rp.vis_point + rp.normal * offset_;
        for (size_t k = 0; k < nk; ++k) {
            if (prior_cls && prior_cls[k] != 0) {
                cls[q * nk + k] = prior_cls[k];
                continue;
            }
            asked.push_back({q, k});
            batch.AddSegment(o, l.classify[k]);
        }
    }
    batch.Trace(vis_, RayKind::kClassify);
    for (size_t r = 0; r < asked.size(); ++r)
        cls[asked[r].first * nk + asked[r].second] = batch.occluded[r] ? 3 : 2;
    enum : uint8_t { kAway, kLit, kUmbra, kPenumbra };
    std::vector<uint8_t> kind(which.size(), kAway);
    std::vector<size_t> penumbra;
    std::vector<uint8_t> classified;  // per penumbra point: occluded[] of its classify rays
    for (size_t q = 0; q < which.size(); ++q) {
        if (!faces[q])
            continue;
        size_t vis = 0;
        for (size_t k = 0; k < nk; ++k)
            vis += cls[q * nk + k] == 2 ? 1 : 0;
        kind[q] = vis == nk ? kLit : vis == 0 ? kUmbra : kPenumbra;
        if (kind[q] != kPenumbra)
            continue;
        penumbra.push_back(which[q]);
        for (size_t k = 0; k < nk; ++k)
            classified.push_back(cls[q * nk + k] == 3 ? 1 : 0);
    }
    // 2. Penumbra points: adaptive cells of the light (see Penumbra()).
    std::vector<Vec3d> pen_e;
    std::vector<uint8_t> pen_states;
    Penumbra(l, points, penumbra, classified, prior_grid, &pen_e, grid_out ? &pen_states : nullptr);
    auto add = [&](size_t p, const Vec3d& e) {
        for (int c = 0; c < 3; ++c)
            for (int k = 0; k < 3; ++k)
                out[p * 9 + size_t(3 * c + k)] += float(l.radiance[c] * e[k]);
    };
    for (size_t q = 0; q < penumbra.size(); ++q)
        add(penumbra[q], pen_e[q]);
    // 3. Fully lit points: the closed form above the point's horizon.
    const Emission emission = l.two_sided ? Emission::kBoth : Emission::kFront;
    for (size_t q = 0; q < which.size(); ++q) {
        if (kind[q] != kLit)
            continue;
        const size_t p = which[q];
        const Vec3d x(points[p].position), h(points[p].horizon);
        if (Dot(h, h) == 0) {
            add(p, VectorIrradiance(l.vertices, 1.0, x, emission));
        } else {
            auto clipped = ClipToHalfSpace(l.vertices, x, h);
            if (clipped.size() >= 3)
                add(p, VectorIrradiance(clipped, 1.0, x, emission));
        }
    }
    if (cls_out) {
        cls_out->assign(which.size() * nk, 0);
        for (size_t q = 0; q < which.size(); ++q)
            if (faces[q])
                std::copy(&cls[q * nk], &cls[q * nk] + nk, &(*cls_out)[q * nk]);
    }
    if (grid_out) {
        grid_out->assign(which.size() * nv, 0);
        size_t at = 0;
        for (size_t q = 0; q < which.size(); ++q) {
            uint8_t* g = &(*grid_out)[q * nv];
            if (kind[q] == kLit || kind[q] == kUmbra)
                std::fill(g, g + nv, kind[q] == kLit ? 2 : 3);
            if (kind[q] == kPenumbra)
                std::copy(&pen_states[at * nv], &pen_states[(at + 1) * nv], g), ++at;
        }
    }
}

void DirectLight::Evaluate(std::span<const ReceiverPoint> points, std::span<float> out, int parts,
                           size_t probes, ProbeCache* cache, std::span<const ProbeKey> keys) const {
    CHECK_EQ(out.size(), points.size() * 9);
    std::fill(out.begin(), out.end(), 0.f);
    SegmentBatch batch;
    if (cache)
        CHECK_EQ(keys.size(), probes);

    const bool coherent = (parts & kLights) && probes > 0 && probes < points.size();
    // Probes found in the cache, and records for the others (filled light by light).
    std::vector<const ProbeCache::Record*> found(coherent ? probes : 0, nullptr);
    std::vector<ProbeCache::Record> fresh(coherent ? probes : 0);
    if (coherent && cache) {
        for (size_t q = 0; q < probes; ++q) {
            auto it = cache->map_.find(keys[q]);
            if (it != cache->map_.end())
                found[q] = &it->second;
        }
    }
    size_t state_at = 0;  // this light's offset in a record's states
    std::vector<float> probe_e;
    // Without probes every point is evaluated on its own; with them, the points after the
    // probes take the probes' agreement as a prior.
    std::vector<size_t> others(points.size() - (coherent ? probes : 0));
    std::iota(others.begin(), others.end(), coherent ? probes : 0);
    for (const auto& l : lights_) {
        if (!(parts & kLights))
            break;
        if (!coherent) {
            EvaluateLight(l, points, others, nullptr, nullptr, out, nullptr, nullptr);
            continue;
        }
        // Points of one small patch: the probes are evaluated first; where all of them agree
        // on a light vertex's visibility, the other points take it without a ray.
        const size_t nk = l.classify.size();
        const size_t nv = (l.vertices.size() - 2) * size_t(l.grid + 1) * size_t(l.grid + 1);
        std::vector<size_t> uncached;  // probes not in the cache: traced now
        for (size_t q = 0; q < probes; ++q)
            if (!found[q])
                uncached.push_back(q);
        std::vector<uint8_t> cls, grid;
        probe_e.assign(out.size(), 0.f);
        EvaluateLight(l, points, uncached, nullptr, nullptr, probe_e, &cls, &grid);
        // Every probe's states (nk then nv), cached or new; E added to out.
        std::vector<uint8_t> st(probes * (nk + nv));
        for (size_t q = 0, t = 0; q < probes; ++q) {
            uint8_t* dst = &st[q * (nk + nv)];
            const float* e;
            if (found[q]) {
                std::copy(&found[q]->states[state_at], &found[q]->states[state_at + nk + nv], dst);
                e = &found[q]->e[9 * size_t(&l - lights_.data())];
            } else {
                std::copy(&cls[t * nk], &cls[(t + 1) * nk], dst);
                std::copy(&grid[t * nv], &grid[(t + 1) * nv], dst + nk);
                e = &probe_e[q * 9];
                fresh[q].e.insert(fresh[q].e.end(), e, e + 9);
                fresh[q].states.insert(fresh[q].states.end(), dst, dst + nk + nv);
                ++t;
            }
            for (int k = 0; k < 9; ++k)
                out[q * 9 + size_t(k)] += e[k];
        }
        std::vector<uint8_t> prior(st.begin(), st.begin() + std::ptrdiff_t(nk + nv));
        for (size_t q = 1; q < probes; ++q)
            for (size_t k = 0; k < nk + nv; ++k)
                if (st[q * (nk + nv) + k] != prior[k])
                    prior[k] = 0;
        EvaluateLight(l, points, others, prior.data(), prior.data() + nk, out, nullptr, nullptr);
        state_at += nk + nv;
    }
    if (coherent && cache) {
        for (size_t q = 0; q < probes; ++q)
            if (!found[q])
                cache->map_.emplace(keys[q], std::move(fresh[q]));
    }

    if (sky_.type != Sky::Type::None && (parts & kSky)) {
        // Fixed world-frame directions about the sky's up axis (uniform), so E
        // changes with position only where visibility does.
        batch.Clear();
        const Vec3f up(sky_.up);
        Vec3f t, b;
        Frame(up, &t, &b);
        std::vector<Vec3f> dirs(sky_dirs_.size());
        for (size_t k = 0; k < sky_dirs_.size(); ++k)
            dirs[k] = t * sky_dirs_[k].x + b * sky_dirs_[k].y + up * sky_dirs_[k].z;
        for (const auto& rp : points) {
            const Vec3f o = rp.vis_point + rp.normal * offset_;
            for (const auto& w : dirs) {
                // Below the horizon: no ray, counted as blocked (tfar 0 never hits).
                bool below = Dot(w, rp.horizon) < 0;
                batch.Add(o, w, below ? -1.f : far_);
            }
        }
        batch.Trace(vis_, RayKind::kSky);
        for (size_t k = 0; k < batch.size(); ++k)
            if (batch.segments[k].tfar < 0)
                batch.occluded[k] = 1;
        // Estimator of E = integral of L(w) V w dw with the uniform pdf 1 / (2 pi):
        // sum L w 2 pi / N.
        const float scale = 2 * float(std::numbers::pi) / float(sky_dirs_.size());
        size_t at = 0;
        for (size_t p = 0; p < points.size(); ++p) {
            for (size_t k = 0; k < dirs.size(); ++k) {
                if (batch.occluded[at++])
                    continue;
                const Vec3f& w = dirs[k];
                const float cos_up = sky_dirs_[k].z;
                const double gain = sky_.type == Sky::Type::Overcast ? (1 + 2 * cos_up) / 3.0 : 1.0;
                for (int c = 0; c < 3; ++c) {
                    const float l = float(sky_.radiance[c] * gain) * scale;
                    for (int e = 0; e < 3; ++e)
                        out[p * 9 + size_t(3 * c + e)] += l * w[e];
                }
            }
        }
    }
}

}  // namespace mebake::solve
