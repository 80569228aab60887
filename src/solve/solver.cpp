#include "solve/solver.h"

#include "core/check.h"
#include "core/error.h"
#include "core/log.h"
#include "core/parallel.h"
#include "solve/direct.h"
#include "solve/field_pool.h"
#include "solve/link_refine.h"
#include "solve/polygon_light.h"
#include "solve/rays.h"
#include "solve/shading.h"
#include "solve/transfer.h"
#include "solve/visibility.h"

#include <algorithm>
#include <array>
#include <bit>
#include <chrono>
#include <cmath>
#include <numbers>
#include <numeric>
#include <queue>
#include <utility>

namespace mebake::solve {

namespace {

using Clock = std::chrono::steady_clock;
double Since(Clock::time_point t) {
    return std::chrono::duration<double>(Clock::now() - t).count();
}

// How far the real points of a part (centre pos, unit normal nrm; within `radius` of pos
// and within `relief` of its own plane) can lie from the plane through base with unit
// normal n: its offset, its rim lifted by its tilt, and its own relief.
float ReliefOf(const Vec3f& base, const Vec3f& n, const Vec3f& pos, const Vec3f& nrm, float radius,
               float relief) {
    const float c = std::min(1.f, std::abs(Dot(nrm, n)));
    return std::abs(Dot(pos - base, n)) + radius * std::sqrt(1.f - c * c) + relief;
}

// The mean of a chart's unshot field (or its value) over texel (i, j) of an n x n grid,
// from 2 x 2 Gauss points (exact up to cubics): quadtree leaves finer than the texel would
// otherwise give the value of the one leaf whose corner is the texel centre.
void TexelMean(const ChartField& field, bool unshot, uint32_t i, uint32_t j, uint32_t n,
               float* val) {
    std::fill(val, val + 9, 0.f);
    for (int q = 0; q < 4; ++q) {
        double gs, gt, w;
        GaussPoint2D(2, q, &gs, &gt, &w);
        float part[9];
        if (unshot)
            field.EvalUnshot((i + gs) / n, (j + gt) / n, part);
        else
            field.EvalValue((i + gs) / n, (j + gt) / n, part);
        for (int k = 0; k < field.blocks(); ++k)
            val[k] += float(w) * part[k];
    }
}

// The radiosity a texel reflects from its field's value `val` (TexelMean): the radiosity
// itself in radiosity mode, else rho (n . E)+ per colour.
Vec3f TexelRadiosity(const float* val, const Vec3f& n, const Vec3f& rho, bool radiosity) {
    Vec3f b;
    for (int c = 0; c < 3; ++c) {
        if (radiosity) {
            b[c] = std::max(0.f, val[c]);
        } else {
            const float irr = n.x * val[3 * c] + n.y * val[3 * c + 1] + n.z * val[3 * c + 2];
            b[c] = rho[c] * std::max(0.f, irr);
        }
    }
    return b;
}
}  // namespace

Solver::Solver(const Scene& scene, const std::vector<SolveChart>& charts,
               const VisibilityScene& vis, SolveOptions opt)
    : scene_(scene), charts_(charts), vis_(vis), opt_(std::move(opt)) {
    const int blocks = opt_.settings.radiosity ? 3 : 9;
    fields_.reserve(charts_.size());
    for (size_t c = 0; c < charts_.size(); ++c)
        fields_.emplace_back(opt_.settings.order, blocks);
    emissive_.assign(charts_.size(), 0);
    if (opt_.shoot_emission) {
        for (size_t c = 0; c < charts_.size(); ++c) {
            const GeometryPin pin = charts_[c].geometry.Pin();
            const auto& finest = charts_[c].geometry.levels.back();
            for (const auto& t : finest)
                if (t.area > 0 && scene_.MaterialOf(t.material).emissive()) {
                    emissive_[c] = 1;
                    break;
                }
        }
    }
}

Vec3f Solver::HorizonNormal(const stream::SurfaceSample& finest) {
    // A continuous normal field: the chart's finest geometry level, interpolated.
    // Continuity matters: where light grazes, a horizon that jumped from node to node
    // showed as blocks. It must also follow the surface: the 8 x 8 level used before
    // averaged the normals of a thin feature's rim (an ear, a leg, a fold) into a plane
    // that faced away from lit points, which lost the key light there (bench/RESULTS.md,
    // issue 14 session 8: the bunny's away-side picture 4.97 -> 3.29 %).
    // The caller's sample of that level at the point (PointAt has it already: a second
    // lookup was ~1/3 of SampleBilinear's cost in the direct pass).
    return finest.normal;
}

size_t Solver::NodeBudget(const SolveChart& sc) const {
    // The budget follows the chart's light-map texels: at 8192 nodes whatever the size, the
    // bunny's merged 512-texel charts stopped refining with their shadows half fitted
    // (bench/RESULTS.md, "Issue 13 (session 8)").
    const int extra = std::max(0, TexelLevel(sc) - kBudgetLevel);
    return opt_.max_nodes_per_chart << (2 * extra);
}

std::vector<uint32_t> Solver::LargestFirst() const {
    // The direct pass's work grows with a chart's light-map texels (its node budget): charts
    // with more texels start first, in chart order among equals, so that a large chart does
    // not run alone at the end of the pass (igea's bake had one core idle ~2 s there; bench/
    // RESULTS.md, issue 13 session 16). Among charts of one size the work varies ~20-fold
    // with their light, which nothing cheap predicts. Each chart's result is independent of
    // the order.
    std::vector<uint32_t> order(charts_.size());
    std::iota(order.begin(), order.end(), 0u);
    std::stable_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
        return TexelLevel(charts_[a]) > TexelLevel(charts_[b]);
    });
    return order;
}

int Solver::EmitterTop(const SolveChart& sc) const {
    const int finest = sc.geometry.finest_level();
    int top = opt_.max_emitter_level;
    if (opt_.settings.emitter_texels > 0) {
        const int span = std::countr_zero(unsigned(opt_.settings.emitter_texels));
        top = std::max(top, TexelLevel(sc) - span);
    }
    top = std::max(top, sc.emitter_level);
    return std::min(finest, top);
}

ReceiverPoint Solver::PointAt(const SolveChart& sc, int level, float u, float v,
                              const stream::SurfaceSample& smp, bool horizon) {
    // Rays start from the finest geometry, not from the coarser level the point's E is
    // sampled at: coarse texels average positions, which lie inside a convex surface by
    // the sagitta (a texel of 1/16 of a unit sphere's chart: 3e-3, six times the ray
    // offset), so rays from there hit the surface they leave and the sky went dark
    // between texel centres.
    const int finest = sc.geometry.finest_level();
    const stream::SurfaceSample fine =
        level >= finest ? smp : SampleBilinear(sc.geometry, finest, u, v);
    ReceiverPoint rp{smp.position, smp.normal, fine.vis_point,
                     horizon ? HorizonNormal(fine) : Vec3f{}};
    rp.outline = !(fine.vis_point == fine.position);
    return rp;
}

float Solver::RayOffset(uint32_t chart) const {
    // Shadow rays start half a light-map texel off the surface: shadows of bumps smaller
    // than a texel cannot be represented by the light map (that detail comes back through
    // the full-resolution normal at display), and chasing them would refine every node.
    const SolveChart& sc = charts_[chart];
    return std::max(opt_.ray_offset, float(0.5 * sc.scale / double(1u << TexelLevel(sc))));
}

Vec3f Solver::Albedo(uint32_t material, const Vec3f& color) const {
    return SurfaceAlbedo(scene_.MaterialOf(material), color);
}

// Receiver points at a node's ng x ng Gauss points, from the geometry pyramid two
// levels below the node (or the finest), with their albedo.
void Solver::GaussPoints(const SolveChart& sc, const QuadNode& node, int ng, bool horizon,
                         std::vector<ReceiverPoint>* pts, std::vector<Vec3f>* albedo) const {
    pts->clear();
    albedo->clear();
    const int gl = std::min(sc.geometry.finest_level(), int(node.level) + 2);
    for (int p = 0; p < ng * ng; ++p) {
        double s, t, w;
        GaussPoint2D(ng, p, &s, &t, &w);
        const float u = float(node.U(s)), v = float(node.V(t));
        auto smp = SampleBilinear(sc.geometry, gl, u, v);
        pts->push_back(PointAt(sc, gl, u, v, smp, horizon));
        albedo->push_back(Albedo(smp.material, smp.color));
    }
}

// What the field stores at each point: E itself (9 blocks), or for a radiosity
// solution B = rho (n . E)+ per colour (3 blocks).
void Solver::ToFieldValues(std::span<const ReceiverPoint> pts, std::span<const Vec3f> albedo,
                           const std::vector<float>& e9, bool radiosity, std::vector<float>* vals) {
    vals->assign(pts.size() * (radiosity ? 3 : 9), 0.f);
    for (size_t p = 0; p < pts.size(); ++p) {
        if (!radiosity) {
            std::copy(&e9[p * 9], &e9[p * 9] + 9, &(*vals)[p * 9]);
            continue;
        }
        for (int c = 0; c < 3; ++c) {
            const float* e = &e9[p * 9 + size_t(3 * c)];
            float irr = pts[p].normal.x * e[0] + pts[p].normal.y * e[1] + pts[p].normal.z * e[2];
            (*vals)[p * 3 + size_t(c)] = albedo[p][c] * std::max(0.f, irr);
        }
    }
}

void Solver::BuildEmitter(uint32_t chart, bool first_shot, Emitter* e) const {
    const SolveChart& sc = charts_[chart];
    const GeometryPin pin = sc.geometry.Pin();
    const ChartField& field = fields_[chart];
    const RegionPin field_pin = field.Pin();
    const int top = EmitterTop(sc);
    e->chart = chart;
    e->scale = sc.scale;
    e->levels.assign(size_t(top) + 1, {});
    const uint32_t n = 1u << top;
    // One level of finest samples from the geometry at level l: each texel's mean unshot
    // radiosity (and emission on the first shot), and its relief over its children.
    auto sample_level = [&](int l, std::vector<Emitter::Texel>* out) {
        const uint32_t m = 1u << l;
        out->resize(size_t(m) * m);
        for (uint32_t j = 0; j < m; ++j) {
            for (uint32_t i = 0; i < m; ++i) {
                const auto& g = sc.geometry.At(l, i, j);
                Emitter::Texel& t = (*out)[size_t(j) * m + i];
                t.pos = g.position;
                t.nrm = g.normal;
                t.vis = g.vis_point;
                t.area = g.area;
                t.radius = g.radius;
                t.hull = g.position;
                t.hull_radius = g.radius;
                for (uint32_t c = 0; l < sc.geometry.finest_level() && c < 4; ++c) {
                    const auto& k = sc.geometry.At(l + 1, 2 * i + (c & 1), 2 * j + (c >> 1));
                    if (k.area > 0)
                        t.relief = std::max(t.relief, ReliefOf(t.vis, t.nrm, k.position,
                                                               k.normal, k.radius, 0.f));
                }
                if (g.area <= 0)
                    continue;
                t.db = SampleRadiosity(chart, field, g, i, j, m, true, first_shot);
                t.db_max = Luminance(t.db);
            }
        }
    };
    auto& lv = e->levels[size_t(top)];
    sample_level(top, &lv);
    if (top < sc.geometry.finest_level()) {
        e->facets.resize(size_t(n) * n * 4);
        for (uint32_t j = 0; j < n; ++j)
            for (uint32_t i = 0; i < n; ++i)
                for (uint32_t c = 0; c < 4; ++c) {
                    const auto& g = sc.geometry.At(top + 1, 2 * i + (c & 1), 2 * j + (c >> 1));
                    e->facets[(size_t(j) * n + i) * 4 + c] = {g.position, g.normal, g.vis_point,
                                                               g.area};
                }
    }
    // The finest samples' children, for the near pairs (CollectPairs): the same as a
    // finest sample one level down, each with its own unshot radiosity.
    if (opt_.settings.near_emitter_split > 0 && top < sc.geometry.finest_level())
        sample_level(top + 1, &e->near);
    // Coarser samples: area-weighted means.
    for (int l = top - 1; l >= 0; --l) {
        const auto& fine = e->levels[size_t(l) + 1];
        auto& coarse = e->levels[size_t(l)];
        const uint32_t m = 1u << l, fm = m * 2;
        coarse.resize(size_t(m) * m);
        for (uint32_t j = 0; j < m; ++j) {
            for (uint32_t i = 0; i < m; ++i) {
                Emitter::Texel& t = coarse[size_t(j) * m + i];
                const auto& g = sc.geometry.At(l, i, j);
                t.pos = g.position;
                t.vis = g.vis_point;
                t.radius = g.radius;
                Vec3f nrm{}, db{};
                float area = 0;
                for (uint32_t c = 0; c < 4; ++c) {
                    const auto& k = fine[size_t(2 * j + (c >> 1)) * fm + 2 * i + (c & 1)];
                    area += k.area;
                    nrm += k.nrm * k.area;
                    db += k.db * k.area;
                    t.db_max = std::max(t.db_max, k.db_max);
                }
                t.area = area;
                t.nrm = Length(nrm) > 0 ? Normalize(nrm) : g.normal;
                t.db = area > 0 ? db / area : Vec3f{};
                // The region's normal cone (link_refine.h), from its finest samples', and
                // its relief, from its children's.
                NormalCone cone{t.nrm, 0};
                for (uint32_t c = 0; c < 4; ++c) {
                    const auto& k = fine[size_t(2 * j + (c >> 1)) * fm + 2 * i + (c & 1)];
                    if (k.area <= 0)
                        continue;
                    cone = Enclose(t.nrm, cone, NormalCone{k.nrm, k.cone});
                    t.relief = std::max(t.relief,
                                        ReliefOf(t.vis, t.nrm, k.pos, k.nrm, k.radius, k.relief));
                }
                t.cone = cone.angle;
                // And its tight sphere: around the children's and their sample points (a
                // region is evaluated at its children's positions, virtual ones included).
                SphereBuilder hull;
                for (uint32_t c = 0; c < 4; ++c) {
                    const auto& k = fine[size_t(2 * j + (c >> 1)) * fm + 2 * i + (c & 1)];
                    if (k.area > 0) {
                        hull.Add(k.hull, k.hull_radius);
                        hull.Add(k.pos, 0);
                    }
                }
                hull.Get(t.pos, t.radius, &t.hull, &t.hull_radius);
            }
        }
    }
    // Each sample's facet spread (transfer.h), from the facets the gather reads.
    for (int l = 0; l <= top && (l < top || !e->facets.empty()); ++l) {
        const uint32_t m = 1u << l;
        for (uint32_t j = 0; j < m; ++j)
            for (uint32_t i = 0; i < m; ++i) {
                Emitter::Texel& t = e->levels[size_t(l)][size_t(j) * m + i];
                TexelSource f[4];
                Vec3f vis[4];
                e->FacetsOf(l, i, j, f, vis);
                t.spread = SpreadOf({t.pos, t.nrm, t.area}, f);
            }
    }
    const auto& root = sc.geometry.At(0, 0, 0);
    e->center = root.position;
    e->radius = root.radius;
}

void Solver::Emitter::FacetsOf(int l, uint32_t i, uint32_t j, TexelSource f[4],
                               Vec3f vis[4]) const {
    const uint32_t row = 1u << l;
    for (uint32_t c = 0; c < 4; ++c) {
        if (l + 1 < int(levels.size())) {
            const Texel& k =
                levels[size_t(l) + 1][size_t(2 * j + (c >> 1)) * row * 2 + 2 * i + (c & 1)];
            f[c] = {k.pos, k.nrm, k.area};
            vis[c] = k.vis;
        } else {
            const Facet& g = facets[(size_t(j) * row + i) * 4 + c];
            f[c] = {g.pos, g.nrm, g.area};
            vis[c] = g.vis;
        }
    }
}

Vec3f Solver::SampleRadiosity(uint32_t chart, const ChartField& field,
                              const stream::GeometryTexel& g, uint32_t i, uint32_t j, uint32_t n,
                              bool unshot, bool emission) const {
    float val[9];
    TexelMean(field, unshot, i, j, n, val);
    Vec3f db = TexelRadiosity(val, g.normal, Albedo(g.material, g.color), opt_.settings.radiosity);
    // Emission is radiance; a Lambertian emitter's radiosity is pi times it.
    if (emission && emissive_[chart]) {
        const Material& mat = scene_.MaterialOf(g.material);
        for (int c = 0; c < 3; ++c)
            db[c] += float(std::numbers::pi) * mat.emission[c];
    }
    return db;
}

double Solver::FinestPower(uint32_t chart, bool unshot, bool emission) const {
    // The finest samples alone: building the whole emitter (its coarser levels, facets and
    // the near samples, four times the finest) for the unshot power was 4.8 % of pepper's
    // bounce pass.
    const SolveChart& sc = charts_[chart];
    const GeometryPin pin = sc.geometry.Pin();
    const ChartField& field = fields_[chart];
    const RegionPin field_pin = field.Pin();
    const int top = EmitterTop(sc);
    const uint32_t n = 1u << top;
    double p = 0;
    for (uint32_t j = 0; j < n; ++j)
        for (uint32_t i = 0; i < n; ++i) {
            const auto& g = sc.geometry.At(top, i, j);
            if (g.area <= 0)
                continue;
            const Vec3f b = SampleRadiosity(chart, field, g, i, j, n, unshot, emission);
            p += double(Luminance(b)) * g.area;
        }
    return p;
}

std::vector<uint8_t> Solver::LaggingCharts(const std::vector<double>& unshot) const {
    // A chart whose unshot power is still a fair share of what it reflects has light left
    // to give itself and its neighbours: a fold's two walls trade most of their light at
    // close range, bounce after bounce, while the scan's total unshot power, which the
    // global stop and the batches' largest-first choice look at, is long negligible (the
    // horse's hind leg: 3 batches, its fold at 0.68 of the path tracer; bench/RESULTS.md,
    // issue 14 session 14). Such charts shoot in every batch until they fall below
    // chart_stop_fraction of their own reflected power.
    const uint32_t nc = uint32_t(charts_.size());
    std::vector<uint8_t> lagging(nc, 0);
    if (opt_.settings.chart_stop_fraction <= 0)
        return lagging;
    ParallelFor(0, nc, [&](int64_t c) {
        if (unshot[size_t(c)] > 0)
            lagging[size_t(c)] = unshot[size_t(c)] >= opt_.settings.chart_stop_fraction *
                                                             ReflectedPower(uint32_t(c));
    });
    return lagging;
}

// One receiver chart's gather from a batch of emitters: link refinement (hierarchical
// radiosity) picks pairs (receiver node, emitter region) at a suitable scale, and each link
// is evaluated at the node's Gauss points from the region's texels, with one visibility
// ray per point and texel; the projection goes to the node's pending coefficients.
class Solver::Gatherer {
public:
    Gatherer(Solver& solver, uint32_t receiver)
        : s_(solver),
          sc_(solver.charts_[receiver]),
          pin_(sc_.geometry.Pin()),
          field_(solver.fields_[receiver]),
          field_pin_(field_.Pin()),
          order_(field_.order()),
          ng_(order_ + 1),
          finest_(sc_.geometry.finest_level()),
          eps_(solver.RayOffset(receiver)),
          tolerance_(field_, solver.LinkToleranceScale(),
                     solver.opt_.link_floor * solver.reference_),
          coeffs_(size_t(field_.stride())),
          values_per_node_(size_t(ng_ * ng_ * field_.blocks())) {
        receiver_tau_ = solver.ReceiverTau();
        // Links whose irradiance bound is below this are evaluated where they stand.
        negligible_ = 1e-3 * s_.opt_.settings.tolerance * s_.reference_;
        // The first batch (most of the bounced light) keeps the whole bound: there the
        // share cost lucy 0.04 point of RMS, from the second batch on 0.006.
        if (s_.next_batch_ >= 1)
            size_error_ = s_.opt_.settings.link_size_error;
    }

    // A cluster link's share for this chart: the link (root node, whole emitter) as Shoot()
    // would evaluate it, at the same emitter samples, with the cluster's visibility `vis`
    // in place of one ray per pair.
    void ShootCluster(const Emitter& em, float vis) {
        const int top = int(em.levels.size()) - 1;
        EvaluateLink(0, em, Link{0, 0, 0, 0, kVisUnknown}, std::min(top, 1), vis);
    }

    // A pair (receiver node, emitter region) is evaluated when both are small against
    // their distance, or when the error it can still make is within the receiver's
    // tolerance (link_refine.h), or its irradiance bound is negligible; otherwise the
    // larger side is subdivided.
    void Shoot(const Emitter& em) {
        const int top = int(em.levels.size()) - 1;
        std::vector<Link> stack(1, Link{0, 0, 0, 0, kVisUnknown});
        while (!stack.empty()) {
            const Link lk = stack.back();
            stack.pop_back();
            const QuadNode node = field_.node(lk.node);
            const auto& et = em.levels[size_t(lk.level)][size_t(lk.j) * (1u << lk.level) + lk.i];
            if (et.area <= 0 || et.db_max <= 0)
                continue;
            const auto [rc, rr] = ReceiverSphere(lk.node);
            const double dist = double(Length(rc - et.pos)) - rr - et.radius;
            const double size_r = sc_.scale * node.size();
            const double size_e = em.scale / double(1u << lk.level);
            const bool recv_can = !node.leaf();
            const bool emit_can = lk.level < top;
            const double bound =
                dist > 0 ? double(et.db_max) * et.area / (std::numbers::pi * dist * dist) : 1e300;
            const bool small =
                dist > 0 && size_r / dist <= receiver_tau_ && size_e / dist <= s_.opt_.emitter_tau;
            // A receiver node already smaller than the finest emitter samples gains nothing
            // from splitting: the samples' size bounds the link's accuracy.
            const bool emitter_bound = !emit_can && size_r <= size_e;
            bool accept = small || bound < negligible_ || (!recv_can && !emit_can) || emitter_bound;
            double b = 1e300;
            if (!accept && tolerance_.enabled()) {
                // The error-driven stop, with the cosines at both ends (link_refine.h).
                b = Bound(lk.node, et);
                if (b <= 0)
                    continue;  // the sides face away: no light can pass
                accept = tolerance_.Accepts(lk.node, b);
                // Apart, the link's value errs by its point samples' share of the bound
                // (SolverSettings::link_size_error), not by the whole bound.
                if (!accept && dist > 0 && size_error_ > 0) {
                    const double rho = std::max(size_r, size_e) / dist;
                    const double share = std::min(1.0, size_error_ * rho * rho);
                    accept = tolerance_.Accepts(lk.node, b * share);
                }
            }
            if (accept) {
                // Sample the region one level finer than itself when possible, two when
                // the spheres touch (its samples then lie next to the node's points, where
                // the kernel varies fastest and coarse point samples of it err low). A
                // touching link stops here only by its error bound (the geometric rules
                // need a gap or the finest samples), which holds for any estimate within
                // [0, bound]: sampling it at the finest level, as before, spent up to 1024
                // x 9 pairs on a link worth at most the allowance (lucy: link rays
                // 103.0M -> 95.7M, RMS unchanged; bench/RESULTS.md, issue 13 session 11).
                const int ls = std::min(top, lk.level + (dist > 0 ? 1 : 2));
                EvaluateLink(lk.node, em, lk, ls, lk.vis == kVisible ? 1.f : -1.f);
                continue;
            }
            // A split whose probes agree hands their answer to its whole subtree when a
            // wrong answer could cost no more than the allowance (SplitVisibility).
            int8_t vis = lk.vis;
            if (vis == kVisUnknown && s_.opt_.split_probes && tolerance_.enabled())
                vis = SplitVisibility(lk, em, top, b / tolerance_.allowed(lk.node));
            if (vis == kHidden)
                continue;
            const bool split_receiver = recv_can && (!emit_can || size_r >= size_e);
            if (split_receiver) {
                for (int c = 3; c >= 0; --c)
                    stack.push_back(
                        Link{uint32_t(node.first_child + c), lk.level, lk.i, lk.j, vis});
            } else {
                for (int c = 3; c >= 0; --c)
                    stack.push_back(Link{lk.node, lk.level + 1, lk.i * 2 + uint32_t(c & 1),
                                         lk.j * 2 + uint32_t(c >> 1), vis});
            }
        }
    }

private:
    // A link's visibility as far as the refinement knows it (SplitVisibility).
    static constexpr int8_t kVisUnknown = -1, kHidden = 0, kVisible = 1;
    struct Link {
        uint32_t node;  // receiver node
        int level;      // emitter region (level, i, j)
        uint32_t i, j;
        int8_t vis;     // kVisUnknown, or what a split above it found for its whole subtree
    };
    struct Pair {
        uint32_t point;
        uint32_t texel;  // kNearTexel set: Emitter::near[texel & ~kNearTexel]
        Vec3f contribution;  // E per unit radiosity of the texel
        int8_t carrier;      // its ray ends at the sample (-1) or at this facet (FacetedTransfer)
    };
    static constexpr uint32_t kNearTexel = 1u << 31;
    struct Deferred {  // a link made, not yet summed (EvaluateLink, Resolve)
        uint32_t node, points;  // receiver node, its first point in set_pts_ (ng^2 of them)
        const Emitter* em;
        int ls;    // the emitter level sampled
        float vis; // < 0: one ray per pair
        size_t pair0, pair1;  // its pairs_
    };

    // What the error-driven stop knows of node n's receiver points (cached per node): the
    // cone of the normals GaussPoints() gives there, from the level-gl texels its bilinear
    // samples blend (one ring beyond the node), widened where samples within half a texel
    // of the square's edge are extrapolated (weights in [-0.5, 1.5] per axis: the sum of
    // |weights| is at most 4, so the blend's tangent part grows to 4 sin theta against an
    // axial part of at least 2.5 cos theta - 1.5); and a sphere around the node's real
    // points and the ring's sample points, when tighter than NodeSphere()'s.
    const LinkSide& NodeShape(size_t n) {
        if (node_shapes_.size() != field_.node_count())
            node_shapes_.assign(field_.node_count(), LinkSide{Vec3f{}, -1.f, {}});
        LinkSide& cached = node_shapes_[n];
        if (cached.radius >= 0)
            return cached;
        const QuadNode node = field_.node(n);
        NodeSphere(sc_, node, &cached.center, &cached.radius);
        const int gl = std::min(std::max(std::min(finest_, int(node.level) + 2), 1), finest_);
        const int nn = 1 << gl;
        auto range = [&](double lo, double hi, int* a, int* b) {
            const double x0 = lo * nn - 0.5, x1 = hi * nn - 0.5;
            *a = nn > 1 ? std::clamp(int(std::floor(x0)), 0, nn - 2) : 0;
            *b = nn > 1 ? std::clamp(int(std::floor(x1)), 0, nn - 2) + 1 : 0;
            return x0 < 0 || x1 > nn - 1;  // extrapolated
        };
        int i0, i1, j0, j1;
        bool edge = range(node.U(0), node.U(1), &i0, &i1);
        edge = range(node.V(0), node.V(1), &j0, &j1) || edge;
        cone_normals_.clear();
        Vec3f sum{};
        SphereBuilder hull;
        for (int j = j0; j <= j1; ++j)
            for (int i = i0; i <= i1; ++i) {
                const auto& g = sc_.geometry.At(gl, uint32_t(i), uint32_t(j));
                cone_normals_.push_back(g.normal);
                sum += g.normal;
                // Texels inside the node bring their real points, the ring its samples.
                const double u = (i + 0.5) / nn, v = (j + 0.5) / nn;
                const bool inside =
                    u > node.U(0) && u < node.U(1) && v > node.V(0) && v < node.V(1);
                hull.Add(g.position, inside ? g.radius : 0.f);
            }
        NormalCone cone;  // any direction
        if (Length(sum) > 0)
            cone = ConeAround(Normalize(sum), cone_normals_.data(), cone_normals_.size());
        if (edge && cone.angle < std::numbers::pi / 2) {
            const double axial = 2.5 * std::cos(cone.angle) - 1.5;
            cone.angle = axial > 0 ? float(std::atan2(4 * std::sin(cone.angle), axial))
                                   : float(std::numbers::pi);
        }
        cached.cone = cone;
        if (int(node.level) + 2 <= finest_)  // the texels cover the node: the sphere holds
            hull.Get(cached.center, cached.radius, &cached.center, &cached.radius);
        return cached;
    }

    // NodeSphere() of receiver node n, cached: the refinement meets a node once per
    // emitter region it is linked against, and below the geometry's finest level each
    // call sampled the pyramid bilinearly (2 % of the horse's bounce pass).
    std::pair<Vec3f, float> ReceiverSphere(size_t n) {
        if (node_spheres_.size() != field_.node_count())
            node_spheres_.assign(field_.node_count(), {Vec3f{}, -1.f});
        auto& cached = node_spheres_[n];
        if (cached.second < 0)
            NodeSphere(sc_, field_.node(n), &cached.first, &cached.second);
        return cached;
    }

    // The error-driven stop's bound for a link (receiver node n, emitter region et).
    double Bound(size_t n, const Emitter::Texel& et) {
        return ConeLinkBound(et.db_max, Luminance(et.db) * et.area, NodeShape(n),
                             {et.hull, et.hull_radius, {et.nrm, et.cone}});
    }


    // One link: the emitter texels at level `ls` inside region lk, at the receiver node's
    // Gauss points; adds the projection to the node's pending set. vis < 0: one ray per
    // pair; otherwise every pair is weighted by vis (a cluster link's estimate). The link
    // waits with its pairs until link_defer_pairs have gathered (Resolve).
    void EvaluateLink(size_t n, const Emitter& em, const Link& lk, int ls, float vis = -1) {
        NodePoints(n);
        Deferred d{uint32_t(n), 0, &em, ls, vis, pairs_.size(), 0};
        CollectPairs(em, lk, ls);
        d.pair1 = pairs_.size();
        if (d.pair1 == d.pair0)
            return;  // no pair carries light (lucy: half the candidate pairs are in such links)
        if (n != set_node_) {  // the same node's points serve every emitter
            set_pts_.insert(set_pts_.end(), pts_.begin(), pts_.end());
            set_albedo_.insert(set_albedo_.end(), albedo_.begin(), albedo_.end());
            set_bounds_.insert(set_bounds_.end(), bounds_.begin(), bounds_.end());
            set_node_ = n;
        }
        d.points = uint32_t(set_pts_.size() - pts_.size());
        deferred_.push_back(d);
        if (pairs_.size() >= s_.opt_.link_defer_pairs)
            Resolve();
    }

    // Memory-coherent link rays (Pharr et al. 1997): the deferred links' rays go to the
    // visibility in two calls, so a paged visibility meets each piece once per batch of
    // thousands of rays instead of once per link (it routes a call's rays piece by piece,
    // resident pieces first). First every link's probes: a stratified subset of link_probes
    // pairs (at most half of them: 4 of a 3 x 3-point link to one texel); when those agree
    // (the link wholly visible or wholly hidden, the usual case), their answer stands for
    // every pair. Then the other pairs of the partial links, so a partial link costs one ray
    // per pair as without probes. Last the links are summed in the order they were made.
    // Each ray's answer is its own, so the bytes are those of tracing link by link.
    void Resolve() {
        const size_t probes_wanted = size_t(std::max(0, s_.opt_.link_probes));
        auto probe_count = [&](const Deferred& d) {
            return std::min(probes_wanted, (d.pair1 - d.pair0) / 2);
        };
        // Links with fewer than 2 probes trace every pair here.
        probe_.Clear();
        for (const Deferred& d : deferred_) {
            if (d.vis >= 0)
                continue;
            const size_t n = d.pair1 - d.pair0, probes = probe_count(d);
            if (probes < 2)
                for (size_t q = d.pair0; q < d.pair1; ++q)
                    AddLinkSegment(d, q, &probe_);
            else
                for (size_t k = 0; k < probes; ++k)
                    AddLinkSegment(d, d.pair0 + ProbePair(k, n, probes), &probe_);
        }
        probe_.Trace(s_.vis_, RayKind::kLink);
        // The partial links' other pairs; every pair's answer into occluded_.
        occluded_.assign(pairs_.size(), 0);
        rest_.Clear();
        std::vector<uint8_t> partial(deferred_.size(), 0);
        for (size_t at = 0, i = 0; i < deferred_.size(); ++i) {
            const Deferred& d = deferred_[i];
            if (d.vis >= 0)
                continue;
            const size_t n = d.pair1 - d.pair0, probes = probe_count(d);
            uint8_t* occ = &occluded_[d.pair0];
            if (probes < 2) {
                std::copy(&probe_.occluded[at], &probe_.occluded[at] + n, occ);
                at += n;
                continue;
            }
            const size_t hidden = size_t(std::count(&probe_.occluded[at],
                                                    &probe_.occluded[at] + probes, uint8_t(1)));
            if (hidden == 0 || hidden == probes) {
                std::fill(occ, occ + n, hidden == 0 ? 0 : 1);
            } else {
                partial[i] = 1;
                for (size_t q = 0, k = 0; q < n; ++q) {
                    if (k < probes && q == ProbePair(k, n, probes))
                        occ[q] = probe_.occluded[at + k++];
                    else
                        AddLinkSegment(d, d.pair0 + q, &rest_);
                }
            }
            at += probes;
        }
        rest_.Trace(s_.vis_, RayKind::kLink);
        for (size_t r = 0, i = 0; i < deferred_.size(); ++i) {
            if (!partial[i])
                continue;
            const Deferred& d = deferred_[i];
            const size_t n = d.pair1 - d.pair0, probes = probe_count(d);
            for (size_t q = 0, k = 0; q < n; ++q) {
                if (k < probes && q == ProbePair(k, n, probes))
                    ++k;
                else
                    occluded_[d.pair0 + q] = rest_.occluded[r++];
            }
        }
        for (const Deferred& d : deferred_)
            SumLink(d);
        deferred_.clear();
        pairs_.clear();
        set_pts_.clear();
        set_albedo_.clear();
        set_bounds_.clear();
        set_node_ = SIZE_MAX;
    }

    // The emitter sample of a link's pair.
    static const Emitter::Texel& Sample(const Deferred& d, const Pair& pr) {
        return pr.texel & kNearTexel ? d.em->near[pr.texel & ~kNearTexel]
                                     : d.em->levels[size_t(d.ls)][pr.texel];
    }

    // Pair q's link ray (of link d), into `out`: built only for the pairs traced, the
    // probes and the partial links' others (most links are settled by their probes, and
    // building every pair's segment was 3 % of the bounce pass). The same segment as
    // built at the pair, from the same points, samples and bounds.
    void AddLinkSegment(const Deferred& d, size_t q, SegmentBatch* out) {
        const Pair& pr = pairs_[q];
        const ReceiverPoint& rp = set_pts_[d.points + pr.point];
        const SampleBound& at = set_bounds_[d.points + pr.point];
        const Emitter::Texel& t = Sample(d, pr);
        const Vec3f org = rp.vis_point + rp.normal * eps_;
        if (pr.carrier < 0) {
            out->AddSegmentBetween(org, t.vis + t.nrm * eps_, at, {t.vis, t.nrm, t.radius, t.relief});
            return;
        }
        const uint32_t row = 1u << d.ls;
        d.em->FacetsOf(d.ls, pr.texel % row, pr.texel / row, facets_.data(), facet_vis_.data());
        const size_t c = size_t(pr.carrier);
        out->AddSegmentBetween(org, facet_vis_[c] + facets_[c].nrm * eps_, at,
                               {t.vis, t.nrm, 0.5f * t.radius, t.relief});
    }

    // A resolved link's light at its node's Gauss points, added to the node's sum.
    void SumLink(const Deferred& d) {
        const size_t np = size_t(ng_ * ng_);
        const std::span<const ReceiverPoint> pts(&set_pts_[d.points], np);
        const std::span<const Vec3f> albedo(&set_albedo_[d.points], np);
        e9_.assign(np * 9, 0.f);
        for (size_t q = d.pair0; q < d.pair1; ++q) {
            if (d.vis < 0 && occluded_[q])
                continue;
            const Pair& pr = pairs_[q];
            const Vec3f& tdb = Sample(d, pr).db;
            const Vec3f db = d.vis < 0 ? tdb : tdb * d.vis;
            for (int c = 0; c < 3; ++c)
                for (int k = 0; k < 3; ++k)
                    e9_[pr.point * 9 + size_t(3 * c + k)] += db[c] * pr.contribution[k];
        }
        float* acc = NodeValues(d.node);
        if (!s_.opt_.settings.radiosity) {  // E itself: ToFieldValues() would copy it
            for (size_t k = 0; k < e9_.size(); ++k)
                acc[k] += e9_[k];
            return;
        }
        ToFieldValues(pts, albedo, e9_, true, &vals_);
        for (size_t k = 0; k < vals_.size(); ++k)
            acc[k] += vals_[k];
    }

public:
    // Resolves the links still deferred, then projects every node's summed link values onto
    // its pending coefficients (in the order the nodes were first linked) and empties the
    // sums. The projection is linear, so once per node and gather instead of once per link
    // (it was 10 % of lucy's solve).
    void Flush() {
        Resolve();
        FlushSums();
    }

private:
    // Flush() of the sums alone (the links they hold are resolved).
    void FlushSums() {
        for (size_t slot = 0; slot < slot_nodes_.size(); ++slot) {
            const uint32_t n = slot_nodes_[slot];
            ProjectGauss(order_, ng_, &node_values_[slot * values_per_node_], field_.blocks(),
                         coeffs_.data());
            float* pend = field_.pending(n);
            for (int k = 0; k < field_.stride(); ++k)
                pend[k] += coeffs_[size_t(k)];
            node_slot_[n] = -1;
        }
        slot_nodes_.clear();
        node_values_.clear();
    }

    // The sum of node n's link values at its Gauss points (ToFieldValues' layout). At most
    // kMaxSlots nodes are summed at once (a bounded buffer: the order of the flushes
    // depends on the links alone, so the result does on no thread count).
    float* NodeValues(size_t n) {
        if (node_slot_.size() != field_.node_count())
            node_slot_.resize(field_.node_count(), -1);
        if (node_slot_[n] < 0) {
            if (slot_nodes_.size() == kMaxSlots)
                FlushSums();
            node_slot_[n] = int32_t(slot_nodes_.size());
            slot_nodes_.push_back(uint32_t(n));
            node_values_.resize(slot_nodes_.size() * values_per_node_, 0.f);
        }
        return &node_values_[size_t(node_slot_[n]) * values_per_node_];
    }

    // Node n's Gauss points, albedo and link-ray bounds: pts_, albedo_ and bounds_ view them
    // in their slot. The refinement comes back to a node for every emitter and between its
    // regions' subtrees, so those of the last kPointSlots nodes seen are kept (slot n mod
    // kPointSlots: the same values whatever was evicted, so the same result). They are read
    // in place (copying them out of the slot at every change of node was 2 % of the horse's
    // bounces).
    void NodePoints(size_t n) {
        if (n == pts_node_)
            return;  // the last slot filled or read is n's: still in place
        const size_t per = size_t(ng_ * ng_), slot = n % kPointSlots;
        if (point_slot_node_.empty()) {
            point_slot_node_.assign(kPointSlots, SIZE_MAX);
            point_cache_.resize(kPointSlots * per);
            albedo_cache_.resize(kPointSlots * per);
            bounds_cache_.resize(kPointSlots * per);
        }
        pts_ = {&point_cache_[slot * per], per};
        albedo_ = {&albedo_cache_[slot * per], per};
        bounds_ = {&bounds_cache_[slot * per], per};
        if (point_slot_node_[slot] != n) {
            s_.GaussPoints(sc_, field_.node(n), ng_, false, &gauss_pts_, &gauss_albedo_);
            std::copy(gauss_pts_.begin(), gauss_pts_.end(), &point_cache_[slot * per]);
            std::copy(gauss_albedo_.begin(), gauss_albedo_.end(), &albedo_cache_[slot * per]);
            ReceiverBounds(n, &bounds_cache_[slot * per]);
            point_slot_node_[slot] = n;
        }
        pts_node_ = n;
    }

    // The visibility of a link about to be split, for its whole subtree: k stratified probes
    // between the node's Gauss points and the region's texels that face each other (as
    // Resolve's, at most half the pairs; the texels one level below the region, or finer
    // when that gives too few pairs). All blocked: no link below it can carry light, and
    // the subtree is dropped; all free: its links are evaluated as wholly visible, without
    // rays; otherwise each link below traces its own. Smits' error estimate sets k: the
    // link's bound (link_refine.h) times the visibility uncertainty that k agreeing probes
    // leave, taken as 1 / k, must be within the allowance (k >= `ratio` = bound /
    // allowance); a wrong answer errs by at most `ratio` allowances, on about 1 / k of the
    // subtree's pairs when the probes are a fair sample.
    int8_t SplitVisibility(const Link& lk, const Emitter& em, int top, double ratio) {
        // k = the bound's ratio, at least link_probes, at most 4 x link_probes: the rays of
        // one 36-pair link traced in full.
        const int k0 = s_.opt_.link_probes;
        if (k0 < 2 || ratio > 4.0 * k0)
            return kVisUnknown;
        const size_t want = size_t(std::max(double(k0), std::ceil(ratio)));
        int ls = std::min(top, lk.level + 1);
        while (ls < top && size_t(ng_ * ng_) << (2 * (ls - lk.level)) < 2 * want)
            ++ls;
        NodePoints(lk.node);
        const auto& texels = em.levels[size_t(ls)];
        const uint32_t span = 1u << (ls - lk.level), row = 1u << ls;
        // The pairs first, their segments only for the probes: the probes are a few of
        // the pairs, and building every pair's segment was most of this function's cost.
        // The samples that can emit, in pair order, listed once instead of tested for
        // every point (their centre and normal side by side for the point loop).
        split_texels_.clear();
        for (uint32_t b = 0; b < span; ++b)
            for (uint32_t a = 0; a < span; ++a) {
                const uint32_t k = (lk.j * span + b) * row + lk.i * span + a;
                const auto& t = texels[k];
                if (!(t.area <= 0 || t.db_max <= 0))
                    split_texels_.push_back({k, t.pos, t.nrm});
            }
        split_pairs_.clear();
        for (uint32_t p = 0; p < pts_.size(); ++p) {
            const ReceiverPoint& rp = pts_[p];
            for (const SplitTexel& st : split_texels_) {
                const Vec3f d = st.pos - rp.position;
                if (Dot(d, rp.normal) <= 0 || Dot(d, st.nrm) >= 0)
                    continue;  // this pair cannot carry light
                split_pairs_.push_back({p, st.k});
            }
        }
        const size_t n = split_pairs_.size();
        const size_t probes = std::min(want, n / 2);
        if (probes < 2 || ratio > double(probes))
            return kVisUnknown;
        probe_.Clear();
        for (size_t k = 0; k < probes; ++k) {
            const auto [p, tk] = split_pairs_[ProbePair(k, n, probes)];
            const ReceiverPoint& rp = pts_[p];
            const auto& t = texels[tk];
            probe_.AddSegmentBetween(rp.vis_point + rp.normal * eps_, t.vis + t.nrm * eps_,
                                     bounds_[p], {t.vis, t.nrm, t.radius, t.relief});
        }
        probe_.Trace(s_.vis_, RayKind::kLink);
        const size_t hidden = size_t(std::count(probe_.occluded.begin(), probe_.occluded.end(), 1));
        return hidden == 0 ? kVisible : hidden == probes ? kHidden : kVisUnknown;
    }

    // Probe k of n pairs is pair ProbePair(k): increasing, and distinct as n >= 2 probes.
    static size_t ProbePair(size_t k, size_t n, size_t probes) {
        return (2 * k + 1) * n / (2 * probes);
    }

    // The own samples of node's receiver points (pts_, NodePoints) for their link rays
    // (SegmentBatch::AddSegmentBetween), into out[]: the geometry texel each Gauss point is
    // sampled from (GaussPoints' level) and its children's relief about the point's plane,
    // the finest geometry texels taken as flat (as an emitter sample's, Texel::relief).
    void ReceiverBounds(size_t node, SampleBound* out) const {
        const QuadNode& nd = field_.node(node);
        const int gl = std::min(finest_, int(nd.level) + 2);
        const uint32_t res = 1u << gl;
        for (int p = 0; p < ng_ * ng_; ++p) {
            double s, t, w;
            GaussPoint2D(ng_, p, &s, &t, &w);
            const uint32_t i = std::min(res - 1, uint32_t(nd.U(s) * res));
            const uint32_t j = std::min(res - 1, uint32_t(nd.V(t) * res));
            const ReceiverPoint& rp = pts_[size_t(p)];
            SampleBound b{rp.vis_point, rp.normal, sc_.geometry.At(gl, i, j).radius, 0.f};
            for (uint32_t c = 0; c < 4 && gl < finest_; ++c) {
                const auto& k = sc_.geometry.At(gl + 1, 2 * i + (c & 1), 2 * j + (c >> 1));
                if (k.area > 0)
                    b.relief = std::max(b.relief, ReliefOf(rp.vis_point, rp.normal, k.position,
                                                           k.normal, k.radius, 0.f));
            }
            out[p] = b;
        }
    }

    // The bounds of the parts CollectPairs may test for link lk at level ls (transfer.h):
    // the samples that can emit, and their facets where it reads them.
    static RegionBound PairRegion(const Emitter& em, const Link& lk, int ls, bool faceted) {
        const auto& texels = em.levels[size_t(ls)];
        const uint32_t span = 1u << (ls - lk.level), row = 1u << ls;
        const auto& et = em.levels[size_t(lk.level)][size_t(lk.j) * (1u << lk.level) + lk.i];
        RegionBound region{et.hull, et.nrm};
        for (uint32_t b = 0; b < span; ++b)
            for (uint32_t a = 0; a < span; ++a) {
                const auto& t = texels[size_t(lk.j * span + b) * row + lk.i * span + a];
                if (t.area > 0 && t.db_max > 0)
                    region.Add(t.pos, t.nrm, faceted ? t.spread.reach : 0.f,
                               faceted ? t.spread.tilt : 0.f);
            }
        return region;
    }

    // A sample CollectPairs may pair, with what its pair loop reads of it.
    struct RegionTexel {
        uint32_t i, j, k;  // the sample (i, j), k = j x row + i
        Vec3d pos, nrm;    // src's in double
        TexelSource src;
        FacetSpread spread;
        int32_t facets = -1;  // its facets in region_facets_ once read (SampleFacets), or -1
    };
    // What CollectPairs' pairs share: the emitter level sampled, its row, the side of its
    // samples, whether they stand for facets, whether near pairs take their children.
    struct PairLevel {
        int ls;
        uint32_t row;
        double texel_side;
        bool faceted, near;
    };

    // Every (Gauss point, texel of the region) pair that can carry light, with its
    // transfer (transfer.h), appended to pairs_ (its ray's end in Pair::carrier). A
    // sample's facets are read only for the pairs where they may not all face the receiver
    // point the same way (FacetsAgree); the others take TexelTransfer's answer, which
    // FacetedTransfer would give them.
    void CollectPairs(const Emitter& em, const Link& lk, int ls) {
        const auto& texels = em.levels[size_t(ls)];
        const int top = int(em.levels.size()) - 1;
        const bool faceted = ls < top || !em.facets.empty();
        const uint32_t span = 1u << (ls - lk.level), row = 1u << ls;
        const PairLevel pl{ls, row, em.scale / double(row), faceted,
                           ls == top && !em.near.empty()};  // near: NearPairs
        const double near_r2 = std::pow(s_.opt_.settings.near_emitter_split * pl.texel_side, 2);
        // A region of one sample is tested as fast pair by pair (most links at the finest
        // level).
        const bool cull = span > 1;
        const RegionBound region = cull ? PairRegion(em, lk, ls, faceted) : RegionBound{};
        // The region's samples that can emit, in pair order, with what the pair loop reads
        // of them (their centre and normal in double once per link, as GeometryOf's), so
        // that it does not read the 100-byte Emitter::Texel per pair.
        region_texels_.clear();
        region_facets_.clear();
        for (uint32_t b = 0; b < span; ++b)
            for (uint32_t a = 0; a < span; ++a) {
                const uint32_t i = lk.i * span + a, j = lk.j * span + b, k = j * row + i;
                const auto& t = texels[k];
                if (t.area > 0 && t.db_max > 0)
                    region_texels_.push_back(
                        {i, j, k, Vec3d(t.pos), Vec3d(t.nrm), {t.pos, t.nrm, t.area}, t.spread});
            }
        if (region_texels_.size() == 1) {  // most links: the sample's data stays in registers
            RegionTexel& rt = region_texels_[0];
            for (uint32_t p = 0; p < pts_.size(); ++p)
                if (!cull || !RegionHidden(pts_[p], region))
                    TryPair(em, pl, near_r2, p, Vec3d(pts_[p].position), rt);
            return;
        }
        for (uint32_t p = 0; p < pts_.size(); ++p) {
            if (cull && RegionHidden(pts_[p], region))
                continue;  // every pair's horizon or facing test would fail
            const Vec3d x(pts_[p].position);
            for (RegionTexel& rt : region_texels_)
                TryPair(em, pl, near_r2, p, x, rt);
        }
    }

    static bool RegionHidden(const ReceiverPoint& rp, const RegionBound& region) {
        return RegionBelowHorizon(rp.position, rp.normal, region) ||
               RegionFacesAway(rp.position, region);
    }

    // Pair (receiver point p at x, sample rt) of CollectPairs, appended to pairs_ when it
    // can carry light. Inlined in both of CollectPairs' loops (a call per pair cost 5 %).
    [[gnu::always_inline]] void TryPair(const Emitter& em, const PairLevel& pl, double near_r2,
                                        uint32_t p, const Vec3d& x, RegionTexel& rt) {
        const ReceiverPoint& rp = pts_[p];
        const Vec3d d = rt.pos - x;  // GeometryOf(rp.position, rt.src), to the bit
        const PairGeometry g{d, Dot(d, d), -Dot(d, rt.nrm)};
        if (pl.near && g.r2 < near_r2) {
            NearPairs(em, p, rt.i, rt.j, pl.row, pl.texel_side);
            return;
        }
        // Below the point's horizon (a third of the pairs tested): TexelTransfer fails, and
        // so does FacetedTransfer unless a facet may rise above it (BelowHorizon), so the
        // facets' test is not needed to know it.
        if (Dot(g.d, Vec3d(rp.normal)) <= 0 &&
            (!pl.faceted || BelowHorizon(g, rp.normal, rt.spread)))
            return;
        Vec3d contrib;
        int carrier = -1;
        if (!pl.faceted || FacetsAgree(g, rt.spread)) {
            if (!TexelTransfer(rp.position, rp.normal, rt.src, g, pl.texel_side, &contrib))
                return;
        } else {
            if (!FacetedTransfer(rp.position, rp.normal, rt.src, g, SampleFacets(em, pl.ls, rt),
                                 pl.texel_side, &contrib, &carrier))
                return;
        }
        pairs_.push_back({p, rt.k, Vec3f(contrib), int8_t(carrier)});
    }

    // Sample rt's facets (Emitter::FacetsOf), read once per link: each of the node's
    // points may ask for them (reading them per pair was 1.7 % of pepper's bounce pass).
    std::span<const TexelSource> SampleFacets(const Emitter& em, int ls, RegionTexel& rt) {
        if (rt.facets < 0) {
            rt.facets = int32_t(region_facets_.size());
            region_facets_.resize(region_facets_.size() + 4);
            em.FacetsOf(ls, rt.i, rt.j, &region_facets_[size_t(rt.facets)], facet_vis_.data());
        }
        return {&region_facets_[size_t(rt.facets)], 4};
    }

    // Hierarchical radiosity's refinement of the emitter side alone, for a receiver point p
    // near finest sample (i, j) of a row of `row`: the sample's four children
    // (Emitter::near), each with its own radiosity, transfer and ray, in its place. The
    // point-to-sample transfer errs by ~ (width / distance)^2 (the texel's solid angle
    // against its point form; the near form's square fixes the shape, not the radiosity or
    // the relief varying across it), and a slot's walls trade their light at that range.
    void NearPairs(const Emitter& em, uint32_t p, uint32_t i, uint32_t j, uint32_t row,
                   double texel_side) {
        const ReceiverPoint& rp = pts_[p];
        const uint32_t nrow = 2 * row;
        for (uint32_t c = 0; c < 4; ++c) {
            const uint32_t k = (2 * j + (c >> 1)) * nrow + 2 * i + (c & 1);
            const auto& t = em.near[k];
            if (t.area <= 0 || t.db_max <= 0)
                continue;
            Vec3d contrib;
            if (!TexelTransfer(rp.position, rp.normal, {t.pos, t.nrm, t.area}, 0.5 * texel_side,
                               &contrib))
                continue;
            pairs_.push_back({p, k | kNearTexel, Vec3f(contrib), -1});
        }
    }

    Solver& s_;
    const SolveChart& sc_;
    const GeometryPin pin_;
    ChartField& field_;
    const RegionPin field_pin_;
    const int order_, ng_, finest_;
    const float eps_;
    const LinkTolerance tolerance_;
    double receiver_tau_ = 0, negligible_ = 0;
    double size_error_ = 0;  // SolverSettings::link_size_error in this batch
    size_t pts_node_ = SIZE_MAX;  // the node pts_ belongs to (NodePoints)
    size_t set_node_ = SIZE_MAX;  // the node of the last points in set_pts_
    std::vector<LinkSide> node_shapes_;  // NodeShape(), radius < 0: not yet computed
    std::vector<std::pair<Vec3f, float>> node_spheres_;  // ReceiverSphere(), radius < 0: not yet
    std::vector<Vec3f> cone_normals_;
    std::span<const ReceiverPoint> pts_;  // NodePoints(): in their slot
    std::span<const Vec3f> albedo_;
    std::span<const SampleBound> bounds_;  // ReceiverBounds(): of pts_
    std::vector<ReceiverPoint> gauss_pts_;  // GaussPoints() for a slot
    std::vector<Vec3f> gauss_albedo_;
    static constexpr size_t kPointSlots = 1024;  // x 9 points x 104 B at M2: 0.96 MB
    std::vector<size_t> point_slot_node_;        // per slot: its node, or SIZE_MAX
    std::vector<ReceiverPoint> point_cache_;
    std::vector<Vec3f> albedo_cache_;
    std::vector<SampleBound> bounds_cache_;
    std::vector<ReceiverPoint> set_pts_;  // the deferred links' receiver points, ng^2 a node
    std::vector<Vec3f> set_albedo_;
    std::vector<SampleBound> set_bounds_;  // and their ReceiverBounds()
    std::vector<Deferred> deferred_;     // links waiting for their rays, in link order
    // Their pairs (at most SolveOptions::link_defer_pairs, plus one link's): 25 B a pair here
    // (its answer in occluded_), a traced pair's segment 32 B and ~100 in the paged
    // visibility: at most ~2.5 MB per gathering thread at 16K, less where probes settle links.
    std::vector<Pair> pairs_;
    std::array<TexelSource, 4> facets_;  // Emitter::FacetsOf()
    std::array<Vec3f, 4> facet_vis_;
    std::vector<float> e9_, vals_, coeffs_;
    SegmentBatch probe_, rest_;
    std::vector<uint8_t> occluded_;  // per pair of pairs_ (Resolve)
    struct SplitPair {
        uint32_t point, texel;
    };
    std::vector<SplitPair> split_pairs_;  // SplitVisibility's pairs, in trace order
    struct SplitTexel {
        uint32_t k;  // the sample's index in its level
        Vec3f pos, nrm;
    };
    std::vector<SplitTexel> split_texels_;    // SplitVisibility's samples that can emit
    std::vector<RegionTexel> region_texels_;  // CollectPairs' samples of its link
    std::vector<TexelSource> region_facets_;  // and their facets read (SampleFacets)
    static constexpr size_t kMaxSlots = 4096;  // x 81 floats at M2: 1.3 MB
    const size_t values_per_node_;             // ng^2 points x the field's blocks
    std::vector<int32_t> node_slot_;           // per node: its slot, or -1
    std::vector<uint32_t> slot_nodes_;
    std::vector<float> node_values_;
};

void Solver::NodeSphere(const SolveChart& sc, const QuadNode& node, Vec3f* center,
                        float* radius) {
    const int finest = sc.geometry.finest_level();
    if (int(node.level) <= finest) {
        const auto& g = sc.geometry.At(node.level, node.i, node.j);
        *center = g.position;
        *radius = g.radius;
    } else {
        auto smp = SampleBilinear(sc.geometry, finest, float(node.U(0.5)), float(node.V(0.5)));
        *center = smp.position;
        *radius = float(sc.scale * node.size() * 0.75);
    }
}

double Solver::ReceiverTau() const {
    // A constant (M0) receiver node holds one E for its whole area, while the E of a
    // source turns and falls off across it by ~ its size / distance (higher orders hold
    // the linear part). M0 gathers at nodes 4x smaller against their distance: at tau
    // 0.5 the furnace lost 0.36% per bounce, 3% at albedo 0.9.
    return opt_.settings.order == 0 ? 0.25 * opt_.receiver_tau : opt_.receiver_tau;
}

// link_refine.h: the allowance halves from batch to batch (next_batch_ is the batch being
// shot), so the coarse links' errors summed over every batch stay below twice the first's.
double Solver::LinkToleranceScale() const {
    // Constant (M0) receivers keep the geometric rule alone: a coarse link errs more there
    // (as for ReceiverTau()); the M0 furnace at albedo 0.9 lost 3.7 % with an allowance
    // scaled by the unshot power and 1.8 % with a quarter of that, against 1 % allowed.
    if (opt_.settings.order == 0)
        return 0;
    const int batch = std::clamp(next_batch_, 0, 60);
    return opt_.link_tolerance * opt_.settings.tolerance * std::ldexp(1.0, -batch);
}

// links: empty (every pair refined chart by chart) or, per emitter, per chart, what
// LinkClusters() decided. Emitters are taken in their fixed order.
void Solver::Gather(uint32_t receiver, const std::vector<Emitter>& emitters,
                    const std::vector<std::vector<float>>& links) {
    Gatherer gatherer(*this, receiver);
    for (size_t k = 0; k < emitters.size(); ++k) {
        const float link = links.empty() ? kOpenLink : links[k][receiver];
        if (link == kOpenLink)
            gatherer.Shoot(emitters[k]);
        else if (link > 0)
            gatherer.ShootCluster(emitters[k], link);
    }
    gatherer.Flush();
    fields_[receiver].PushPending();
}

void Solver::Restore(std::vector<ChartField> fields, double reference, int next_batch,
                     const SolveStats& stats) {
    CHECK_EQ(fields.size(), charts_.size());
    for (uint32_t c = 0; c < fields.size(); ++c)
        RestoreField(c, std::move(fields[c]));
    Restore(reference, next_batch, stats);
}

void Solver::RestoreField(uint32_t chart, ChartField field) {
    CHECK_LT(chart, fields_.size());
    fields_[chart] = std::move(field);
    StoreField(chart);
}

void Solver::Restore(double reference, int next_batch, const SolveStats& stats) {
    CHECK(next_batch >= 0);
    if (pool_)
        pool_->Map(&fields_);
    reference_ = reference;
    next_batch_ = next_batch;
    stats_ = stats;
}

// The brightest root-level direct irradiance: the floor of the refinement scale.
double Solver::ReferenceIrradiance() const {
    DirectLight direct(scene_, opt_.settings, vis_, opt_.ray_offset, opt_.scene_size);
    std::vector<ReceiverPoint> pts;
    for (const auto& c : charts_) {
        // Pinned, so the pages read are counted and evicted (unpinned, the 100M solve kept
        // ~220 MB of pyramid pages mapped from here on: each read maps 64 KiB around it).
        const GeometryPin pin = c.geometry.Pin();
        for (int k = 0; k < std::min(c.geometry.finest_level(), 2) + 1; ++k) {
            for (const auto& g : c.geometry.levels[size_t(k)])
                if (g.area > 0)
                    pts.push_back({g.position, g.normal, g.vis_point});
        }
    }
    std::vector<float> e(pts.size() * 9, 0.f);
    // In chunks (each point's light is its own, so the same bits): the rays of every
    // chart's points at once took memory in proportion to the chart count (~60 MiB of
    // the peak at 16M triangles).
    constexpr size_t kChunk = 256;
    for (size_t p0 = 0; p0 < pts.size() && !direct.empty(); p0 += kChunk) {
        const size_t n = std::min(kChunk, pts.size() - p0);
        direct.Evaluate(std::span<const ReceiverPoint>(pts).subspan(p0, n),
                        std::span<float>(e).subspan(p0 * 9, n * 9));
    }
    double ref = 0;
    for (size_t p = 0; p < pts.size(); ++p)
        for (int c = 0; c < 3; ++c) {
            const float* v = &e[p * 9 + size_t(3 * c)];
            ref = std::max(ref, double(Length(Vec3f(v[0], v[1], v[2]))));
        }
    return ref;
}

// Nodes per level, leaves and field memory, for the statistics.
void Solver::CountNodes() {
    for (const auto& f : fields_) {
        const RegionPin pin = f.Pin();
        for (const auto& n : f.nodes()) {
            if (stats_.nodes_per_level.size() <= n.level)
                stats_.nodes_per_level.resize(n.level + 1u);
            ++stats_.nodes_per_level[n.level];
            stats_.leaves += n.leaf() ? 1 : 0;
        }
        stats_.field_bytes += f.MemoryBytes();
    }
    if (pool_)
        stats_.field_bytes += pool_->file_bytes();
}

// A refined field moves to the pool. Without room on disk it stays in memory (the same
// values, so the same solution), with one warning.
void Solver::StoreField(uint32_t chart) {
    if (!pool_)
        return;
    try {
        pool_->Store(chart, &fields_[chart]);
    } catch (const Error& e) {
        if (e.kind() != ErrorKind::Io)
            throw;
        static std::atomic<bool> warned{false};
        if (!warned.exchange(true))
            spdlog::warn("{}; coefficient pools stay in memory", e.what());
    }
}

// The bounces a stop leaves unshot (progressive radiosity's ambient term, Cohen et al.
// 1988, taken per node rather than spread by area): after a few batches the light a chart
// receives keeps its distribution and shrinks by a nearly steady ratio r per batch, so the
// batches left add about the last one's light, the unshot coefficients, times r + r^2 + ...
// = r / (1 - r). r is per chart, what it received in the last batch against the batch
// before (a fold's walls keep trading light when the scan's total has long faded), or the
// scan's received / shot power where the chart received nothing then; capped at
// kTailRatioCap (a chart lit by a shooter that waited a batch can show any ratio).
// The same bits for any thread count: one multiply-add per coefficient.
double Solver::AddUnshotTail(const std::vector<double>& received) {
    constexpr double kTailRatioCap = 0.5;
    const double total = std::accumulate(received.begin(), received.end(), 0.0);
    const std::vector<double>& before = stats_.chart_received;
    if (!(stats_.shot_power > 0) || !(total > 0) || before.size() != received.size())
        return 0;
    const double scan_ratio = std::min(total / stats_.shot_power, kTailRatioCap);
    std::vector<double> gains(fields_.size(), 0.0);
    ParallelFor(0, int64_t(fields_.size()), [&](int64_t c) {
        ChartField& f = fields_[size_t(c)];
        if (!f.has_unshot() || f.node_count() == 0)
            return;
        const double r = before[size_t(c)] > 0
                             ? std::min(received[size_t(c)] / before[size_t(c)], kTailRatioCap)
                             : scan_ratio;
        const float gain = float(r / (1 - r));
        gains[size_t(c)] = gain * received[size_t(c)];
        const RegionPin pin = f.Pin();
        float* value = f.value(0);
        const float* unshot = f.unshot(0);
        const size_t n = f.node_count() * size_t(f.stride());
        for (size_t k = 0; k < n; ++k)
            value[k] += gain * unshot[k];
    });
    const double mean = std::accumulate(gains.begin(), gains.end(), 0.0) / total;
    spdlog::debug("unshot tail: scan ratio {:.4f}, mean gain {:.4f}", scan_ratio, mean);
    return mean;
}

void Solver::Run(const Progress& progress) {
    const auto t0 = Clock::now();
    const uint32_t nc = uint32_t(charts_.size());
    // A resumed run continues the counters and the time limit of the runs before it.
    const uint64_t rays0 = TotalRays() - stats_.rays;
    const double seconds_before = stats_.seconds_direct + stats_.seconds_indirect;
    const double indirect_before = stats_.seconds_indirect;
    auto kinds0 = RaysByKind();
    for (size_t k = 0; k < kinds0.size() && k < stats_.rays_by_kind.size(); ++k)
        kinds0[k] -= stats_.rays_by_kind[k];

    progress_ = &progress;
    if (next_batch_ < 0) {
        reference_ = ReferenceIrradiance();
        std::atomic<uint64_t> refined{0};
        ParallelForInOrder(LargestFirst(), [&](uint32_t c) {
            if (!stop_ || !stop_->load())
                RefineDirect(c);
            StoreField(c);
            if (progress)
                progress({-1, ++refined, nc, 1, 0});
        });
        if (pool_)
            pool_->Map(&fields_);
        stats_.seconds_direct = Since(t0);
        if (stop_ && stop_->load()) {
            stats_.stop_reason = "interrupted";
            return;
        }
        next_batch_ = 0;
        stats_.rays = TotalRays() - rays0;
        if (batch_hook_ && !batch_hook_(next_batch_)) {
            stats_.stop_reason = "interrupted";
            return;
        }
    }

    // Southwell batches.
    const auto t1 = Clock::now();
    if (opt_.cluster_links && clusters_.empty())
        BuildClusters();
    std::vector<double> power(nc);
    bool first = next_batch_ == 0;
    for (int batch = next_batch_;; ++batch) {
        ParallelFor(0, nc, [&](int64_t c) { power[size_t(c)] = UnshotPower(uint32_t(c), first); });
        double total = 0, largest = 0;
        for (double p : power) {
            total += p;
            largest = std::max(largest, p);
        }
        if (first)
            stats_.emitted_power = total;
        // What each chart received in the last batch: its unshot power now less what the
        // batch left unshot.
        std::vector<double> received(nc, 0.0);
        if (!first && stats_.chart_kept.size() == nc)
            for (uint32_t c = 0; c < nc; ++c)
                received[c] = std::max(0.0, power[c] - stats_.chart_kept[c]);
        stats_.unshot_power = total;
        const double fraction = stats_.emitted_power > 0 ? total / stats_.emitted_power : 0;
        if (progress)
            progress({batch, 0, 0, fraction, TotalRays() - rays0});
        const std::vector<uint8_t> lagging =
            first ? std::vector<uint8_t>(size_t(nc), 0) : LaggingCharts(power);
        const bool any_lagging = std::find(lagging.begin(), lagging.end(), 1) != lagging.end();
        if (total <= 0 || (fraction < opt_.settings.stop_fraction && !any_lagging)) {
            stats_.stop_reason = "converged";
            if (opt_.settings.unshot_tail && total > 0)
                stats_.tail_gain = AddUnshotTail(received);
            break;
        }
        if (batch >= opt_.settings.max_bounces) {
            stats_.stop_reason = "bounce limit";
            break;
        }
        if (opt_.settings.time_limit > 0 && seconds_before + Since(t0) > opt_.settings.time_limit) {
            stats_.stop_reason = "time limit";
            break;
        }
        stats_.chart_received = std::move(received);
        stats_.shots += ShootBatch(power, fraction < opt_.settings.stop_fraction ? INFINITY : largest,
                                   first, lagging, &stats_.shot_power, &stats_.chart_kept);
        stats_.batches = batch + 1;
        first = false;
        next_batch_ = batch + 1;
        stats_.seconds_indirect = indirect_before + Since(t1);
        stats_.rays = TotalRays() - rays0;
        if (batch_hook_ && !batch_hook_(next_batch_)) {
            stats_.stop_reason = "interrupted";
            return;
        }
    }
    stats_.seconds_indirect = indirect_before + Since(t1);
    stats_.rays = TotalRays() - rays0;
    const auto kinds1 = RaysByKind();
    stats_.rays_by_kind.resize(kinds1.size());
    for (size_t k = 0; k < kinds1.size(); ++k)
        stats_.rays_by_kind[k] = kinds1[k] - kinds0[k];
    CountNodes();
}

}  // namespace mebake::solve
