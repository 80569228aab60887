// Solver::RefineForBounces: receiver nodes for the indirect light, made before the first
// bounce is gathered (docs/method.md, "Receivers for the bounces").
//
// The gather (solver.cpp, Gatherer::Shoot) refines links down the receiver's quadtree but
// never below its leaves, and the leaves are what the direct light needed: where the direct
// light is smooth they stay large (lucy's folds: leaves 27-108 units wide), and light
// bounced across a fold a few units deep, a peak a few units wide, is fitted by one
// polynomial from 3 x 3 Gauss points that miss it (bench/RESULTS.md, "Issue 14 (session
// 9): lucy's dark bias"). The quadtree cannot grow once the gather starts (the fields then
// live in the coefficient pool, field_pool.h), so the receivers are split here, at the end
// of the chart's direct pass, by the rule the gather itself will apply: for the chart's
// own first shot (its direct light, the light that a fold exchanges), a leaf is split while
// some emitter region of the chart is a link the first batch could not stop at the leaf
// (not small against its distance, its irradiance bound above the error allowed there,
// link_refine.h) and would refine by the receiver (the leaf larger than the region's
// finest samples) — and light can pass: one of the region's finest samples faces one of
// the leaf's points with each in front of the other (TexelTransfer's culls; the normal-cone
// bound cannot tell a fold from a convex bump, where nothing passes). Other charts' light
// is not known yet; the leaves made here serve every emitter's links. Visibility is not
// traced: like the gather's bound, it is taken as 1. Deterministic (one chart, fixed
// order), within the chart's node budget.
#include "solve/link_refine.h"
#include "solve/solver.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace mebake::solve {

class Solver::BounceRefiner {
public:
    BounceRefiner(const Solver& s, uint32_t chart)
        : s_(s), sc_(s.charts_[chart]), finest_(sc_.geometry.finest_level()) {
        s.BuildEmitter(chart, true, &em_);
        top_ = int(em_.levels.size()) - 1;
        negligible_ = 1e-3 * s.opt_.settings.tolerance * s.reference_;
    }

    // Whether the first batch's links from the chart's own light would refine leaf `node`
    // (allowed: the error a link may make there): Gatherer::Shoot's rules with the receiver
    // held at the leaf.
    bool SplitsLeaf(const QuadNode& node, double allowed) {
        const LinkSide leaf = Shape(node);
        const double size_r = sc_.scale * node.size();
        stack_.assign(1, Region{0, 0, 0});
        while (!stack_.empty()) {
            const Region r = stack_.back();
            stack_.pop_back();
            const auto& et = em_.levels[size_t(r.level)][size_t(r.j) * (1u << r.level) + r.i];
            if (et.area <= 0 || et.db_max <= 0)
                continue;
            const double dist = double(Length(leaf.center - et.pos)) - leaf.radius - et.radius;
            const double size_e = em_.scale / double(1u << r.level);
            const bool emit_can = r.level < top_;
            const double bound = dist > 0 ? double(et.db_max) * et.area /
                                                (std::numbers::pi * dist * dist)
                                          : 1e300;
            const bool small = dist > 0 && size_r / dist <= s_.ReceiverTau() &&
                               size_e / dist <= s_.opt_.emitter_tau;
            if (small || bound < negligible_ || (!emit_can && size_r <= size_e))
                continue;
            const double b = ConeLinkBound(et.db_max, Luminance(et.db) * et.area, leaf,
                                           {et.hull, et.hull_radius, {et.nrm, et.cone}});
            if (b <= allowed)
                continue;  // accepted, or the sides face away
            if (!emit_can || size_r >= size_e) {
                if (Facing(r))
                    return true;  // the gather would split the receiver here
                continue;
            }
            for (int c = 3; c >= 0; --c)
                stack_.push_back(Region{r.level + 1, r.i * 2 + uint32_t(c & 1),
                                        r.j * 2 + uint32_t(c >> 1)});
        }
        return false;
    }

private:
    struct Region {
        int level;
        uint32_t i, j;
    };
    struct Sample {
        Vec3f pos, nrm;
    };

    // The leaf's side of the bound (a sphere around it, the cone of its normals) from the
    // geometry texels two levels below it (or the finest) inside it, kept in points_.
    LinkSide Shape(const QuadNode& node) {
        LinkSide side;
        NodeSphere(sc_, node, &side.center, &side.radius);
        const int level = int(node.level);
        const int gl = std::min(finest_, level + 2);
        // A node finer than the finest level reads the one texel holding it.
        const int shift = std::max(0, gl - level);
        const uint32_t span = 1u << shift;
        const uint32_t i0 = level <= gl ? node.i << shift : node.i >> (level - gl);
        const uint32_t j0 = level <= gl ? node.j << shift : node.j >> (level - gl);
        points_.clear();
        normals_.clear();
        Vec3f sum{};
        for (uint32_t j = 0; j < span; ++j)
            for (uint32_t i = 0; i < span; ++i) {
                const auto& g = sc_.geometry.At(gl, i0 + i, j0 + j);
                if (g.area <= 0)
                    continue;
                points_.push_back({g.position, g.normal});
                normals_.push_back(g.normal);
                sum += g.normal;
            }
        if (Length(sum) > 0)
            side.cone = ConeAround(Normalize(sum), normals_.data(), normals_.size());
        return side;
    }

    // Whether a finest sample of region r and a point of the leaf lie each in front of the
    // other (the pairs TexelTransfer does not cull).
    bool Facing(const Region& r) const {
        const uint32_t span = 1u << (top_ - r.level), row = 1u << top_;
        const auto& texels = em_.levels[size_t(top_)];
        for (uint32_t b = 0; b < span; ++b)
            for (uint32_t a = 0; a < span; ++a) {
                const auto& t = texels[size_t(r.j * span + b) * row + r.i * span + a];
                if (t.area <= 0 || t.db_max <= 0)
                    continue;
                for (const Sample& p : points_) {
                    const Vec3f d = t.pos - p.pos;
                    if (Dot(d, p.nrm) > 0 && Dot(d, t.nrm) < 0)
                        return true;
                }
            }
        return false;
    }

    const Solver& s_;
    const SolveChart& sc_;
    const int finest_;
    Emitter em_;
    int top_ = 0;
    double negligible_ = 0;
    std::vector<Region> stack_;
    std::vector<Sample> points_;
    std::vector<Vec3f> normals_;
};

void Solver::RefineForBounces(uint32_t chart, int max_level) {
    const double scale = LinkToleranceScale();
    if (scale <= 0 || opt_.settings.max_bounces < 1)
        return;  // without the error-driven stop the gather refines by distance alone
    ChartField& field = fields_[chart];
    const SolveChart& sc = charts_[chart];
    BounceRefiner refiner(*this, chart);
    const double floor = opt_.link_floor * reference_;
    // Split leaves go on the stack: their children, with the parent's polynomial
    // restricted (the direct light was smooth there), are tested in turn.
    std::vector<size_t> stack;
    for (size_t n = field.node_count(); n-- > 0;)
        if (field.node(n).leaf())
            stack.push_back(n);
    while (!stack.empty() && field.node_count() + 4 <= NodeBudget(sc)) {
        const size_t n = stack.back();
        stack.pop_back();
        const QuadNode node = field.node(n);
        if (int(node.level) >= max_level ||
            !refiner.SplitsLeaf(node, scale * std::max(NodeIrradiance(field, n), floor)))
            continue;
        const int32_t first = field.Subdivide(n);
        for (int c = 3; c >= 0; --c)
            stack.push_back(size_t(first + c));
    }
}

}  // namespace mebake::solve
