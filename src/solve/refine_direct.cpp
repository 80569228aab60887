// Solver::RefineDirect: one chart's direct light (polygon lights and small emitters, then
// the sky) fitted node by node in its quadtree (seed 000, adaptive subdivision). Three
// steps: DirectSampler evaluates the light at a node's Gauss points and control grid,
// FitDirectLights refines where a node's polynomial misses its control points (largest
// integrated error first, within the chart's node budget), GatherSky adds the sky at a
// fixed level, deeper where its fit misses, and pushes it down.
#include "core/check.h"
#include "core/log.h"
#include "solve/direct.h"
#include "solve/extremal_boundary.h"
#include "solve/multi_emitter.h"
#include "solve/multi_emitter_debug.h"
#include "solve/rays.h"
#include "solve/shading.h"
#include "solve/slave_nodes.h"
#include "solve/solver.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <queue>
#include <unordered_map>

namespace mebake::solve {

namespace {

// Nodes this many levels above the light-map texel or finer share light visibility between
// their points (DirectLight::Evaluate probes; the sky's directions, SkyShared): shadow
// detail smaller than a few texels is what the light map cannot hold anyway.
constexpr int kCoherentLevels = 3;

// --multi-emitter simplify: the extremal boundaries are resolved down to this many levels
// above the direct light's depth cap; finer detail of a straddled node is left to the
// refinement (it is marked penumbra). Measured on the Cornell box with 4 lights: the pass at
// the cap cost 1.16M of 2.17M classification rays, two levels above it 0.4M.
constexpr int kBoundaryLevelsAboveCap = 2;

// A node whose fit passes is still split where the lights' visibility changes between the
// points of a grid this fine (at most) that its own points missed: a shadow smaller than the
// spacing of its control points (lucy's folds, the crevices of nefertiti's crown).
constexpr int kEdgeGrid = 16;

// At the depth cap (nodes M+1 texels wide) a node whose points see a light's centre from
// some points and not from others holds a shadow edge: its polynomial rings across it (lucy's
// umbra points lit at 5-10 % of the lit side, lit points 10 % over), while the light map's
// texels could hold the step. Such nodes are split this many levels below the cap.
constexpr int kEdgeLevelsBelowCap = 1;

// The depth below sky_level the sky was tested to before the deeper sky became the default
// (session 18): nodes deeper than that are GatherSky's deep levels (sky_deep_floor).
constexpr int kSkyDefaultDepth = 2;

// The direct light's ray offset, in units of Solver::RayOffset (half a light-map texel).
constexpr float kDirectOffset = 0.25f;

float MaxAbs(const std::vector<float>& v) {
    float m = 0;
    for (float x : v)
        m = std::max(m, std::abs(x));
    return m;
}

}  // namespace

// Field values of the direct light at a node's ng x ng Gauss points (gauss_vals) and, with
// control, at its gc x gc control grid (ctrl_vals): E (9 blocks) or B = rho (n.E)+ (3
// blocks). All points go to the direct light in one call; on small nodes the four outermost
// points are its probes (visibility shared across the node, DirectLight::Evaluate).
class Solver::DirectSampler {
public:
    // control_grid: points per side of the control grid (0: order + 2; 2: the corners).
    DirectSampler(const Solver& solver, const SolveChart& sc, int order, int max_level,
                  DirectLight& direct, int control_grid = 0)
        : solver_(solver),
          sc_(sc),
          ng_(order + 1),
          gc_(control_grid > 0 ? control_grid : order + 2),
          finest_(sc.geometry.finest_level()),
          max_level_(max_level),
          direct_(direct) {}

    void Evaluate(const QuadNode& node, bool control) {
        const int gl = std::min(finest_, int(node.level) + 2);
        const int n_gauss = ng_ * ng_, n_ctrl = control ? gc_ * gc_ : 0;
        const size_t probes = OrderPoints(node, control, n_gauss, n_ctrl);
        SamplePoints(node, gl, n_gauss, probes);
        e9_all_.assign(all_pts_.size() * 9, 0.f);
        if (parts == DirectLight::kSky && direct_.has_sky())
            SkyShared(node, gl, n_gauss, probes);
        else if (parts != DirectLight::kSky && direct_.has_lights())
            direct_.Evaluate(all_pts_, e9_all_, parts, probes, &probe_cache_, keys_, known,
                             light_inherited);
        ToGaussAndControl(n_gauss, n_ctrl, control);
    }

    // A shadow the node's own points all missed: the lights' visibility at one point per
    // node of the depth cap, up to kEdgeGrid x kEdgeGrid, where that is finer than the
    // control grid (docs/method.md, "Refinement").
    bool MissedShadowEdge(const QuadNode& node) {
        const int n = std::min(kEdgeGrid, 1 << std::max(0, max_level_ - int(node.level)));
        return n > gc_ && ShadowEdgeOnGrid(node, n);
    }

    // The lights' visibility changes between the centres of an n x n grid over the node.
    bool ShadowEdgeOnGrid(const QuadNode& node, int n) {
        const int gl = std::min(finest_, int(node.level) + 2);
        edge_pts_.clear();
        for (int b = 0; b < n; ++b) {
            for (int a = 0; a < n; ++a) {
                const float u = float(node.U((a + 0.5) / n)), v = float(node.V((b + 0.5) / n));
                auto smp = SampleBilinear(sc_.geometry, gl, u, v);
                edge_pts_.push_back(PointAt(sc_, gl, u, v, smp));
            }
        }
        return direct_.ShadowEdgeAmong(edge_pts_);
    }

    // The light states the probes of `node` (evaluated with its control grid) agreed on,
    // from the cache (empty: it had no probes, or they are not all there).
    std::vector<uint8_t> LightProbeAgreement(const QuadNode& node) const {
        if (!Coherent(node))
            return {};
        const int gl = std::min(finest_, int(node.level) + 2), n_gauss = ng_ * ng_;
        const uint32_t code = KnownCode(known);
        std::vector<ProbeKey> keys;
        for (int k : ProbeSlots(true, n_gauss))
            keys.push_back(KeyAt(node, k, n_gauss, gl, code));
        return direct_.ProbeAgreement(probe_cache_, keys);
    }

    int order() const { return ng_ - 1; }
    std::vector<float> gauss_vals, ctrl_vals;
    // The lights' states taken as known at new probes (light_probes_inherit; empty: none).
    std::vector<uint8_t> light_inherited;
    // Per light, as DirectLight::Evaluate's `known` (empty: every light traced).
    std::vector<uint8_t> known;
    bool use_probes = true;  // false: no shared visibility and no cache (masked evaluations)
    int parts = DirectLight::kLights;  // or kSky (GatherSky)
    // The sky's directions taken as known at the probes (the tested parent's agreement, as
    // DirectLight::EvaluateSky's prior; empty: all traced), and the last node's probes'
    // agreement (SkyProbes; empty without probes).
    std::vector<uint8_t> sky_inherited, sky_prior;

private:
    // Chart coordinates of point idx: Gauss points 0..n_gauss-1, then the control grid.
    std::pair<float, float> Uv(const QuadNode& node, int idx, int n_gauss) const {
        double s, t, w;
        if (idx < n_gauss) {
            GaussPoint2D(ng_, idx, &s, &t, &w);
        } else {
            s = ControlPoint(gc_, (idx - n_gauss) % gc_);
            t = ControlPoint(gc_, (idx - n_gauss) / gc_);
        }
        return std::make_pair(float(node.U(s)), float(node.V(t)));
    }

    // Whether a node's points share the visibility of probes (small nodes, near the cap).
    bool Coherent(const QuadNode& node) const {
        return use_probes && int(node.level) + kCoherentLevels >= max_level_ && ng_ > 1;
    }

    // The probes' point indices: the control grid's corners, or the Gauss grid's.
    std::array<int, 4> ProbeSlots(bool control, int n_gauss) const {
        if (control)
            return {n_gauss, n_gauss + gc_ - 1, n_gauss + gc_ * (gc_ - 1), n_gauss + gc_ * gc_ - 1};
        return {0, ng_ - 1, ng_ * (ng_ - 1), ng_ * ng_ - 1};
    }

    // The cache key of point `idx` of a node: its exact chart coordinates and level.
    ProbeKey KeyAt(const QuadNode& node, int idx, int n_gauss, int gl, uint32_t code) const {
        const auto [u, v] = Uv(node, idx, n_gauss);
        return {std::bit_cast<uint32_t>(u), std::bit_cast<uint32_t>(v), uint32_t(gl), code};
    }

    // slot_: evaluation order -> point index, probes first (the control grid's corners, or
    // the Gauss grid's). Returns the number of probes.
    size_t OrderPoints(const QuadNode& node, bool control, int n_gauss, int n_ctrl) {
        slot_.clear();
        if (Coherent(node))
            for (int k : ProbeSlots(control, n_gauss))
                slot_.push_back(k);
        const size_t probes = slot_.size();
        for (int k = 0; k < n_gauss + n_ctrl; ++k)
            if (std::find(slot_.begin(), slot_.begin() + std::ptrdiff_t(probes), k) ==
                slot_.begin() + std::ptrdiff_t(probes))
                slot_.push_back(k);
        return probes;
    }

    // Surface points and albedos in slot_ order, and the probes' cache keys.
    void SamplePoints(const QuadNode& node, int gl, int n_gauss, size_t probes) {
        all_pts_.resize(slot_.size());
        all_albedo_.resize(slot_.size());
        for (size_t k = 0; k < slot_.size(); ++k) {
            const auto [u, v] = Uv(node, slot_[k], n_gauss);
            auto smp = SampleBilinear(sc_.geometry, gl, u, v);
            all_pts_[k] = PointAt(sc_, gl, u, v, smp);
            all_albedo_[k] = solver_.Albedo(smp.material, smp.color);
        }
        keys_.resize(probes);
        const uint32_t code = KnownCode(known);
        for (size_t k = 0; k < probes; ++k)
            keys_[k] = KeyAt(node, slot_[k], n_gauss, gl, code);
    }

    // The sky at all_pts_: control points on a node's edges are its neighbours' too (same
    // chart coordinates and geometry level, so the same value): each is traced once per
    // chart and kept by its exact coordinates. A third fewer sky rays where GatherSky tests.
    // With probes (small nodes, OrderPoints), the probes are traced in every direction
    // first (or found with their directions' states) and a direction all of them see, or
    // all find occluded, is taken as such at the node's other points without a ray: the
    // lights' reuse of visibility across a patch (DirectLight::Evaluate), for the sky.
    // The probes themselves take sky_inherited (their tested parent's agreement) as known.
    void SkyShared(const QuadNode& node, int gl, int n_gauss, size_t probes) {
        std::vector<ProbeKey> keys(slot_.size());
        for (size_t k = 0; k < slot_.size(); ++k)
            keys[k] = KeyAt(node, slot_[k], n_gauss, gl, 0);
        sky_prior = SkyProbes(keys, n_gauss, probes);
        const std::vector<uint8_t>& prior = sky_prior;
        std::vector<size_t> uncached;
        std::vector<ReceiverPoint> pts;
        for (size_t k = probes; k < slot_.size(); ++k) {
            auto it = sky_cache_.find(keys[k]);
            if (it != sky_cache_.end()) {
                std::copy(it->second.begin(), it->second.end(), &e9_all_[k * 9]);
            } else {
                uncached.push_back(k);
                pts.push_back(all_pts_[k]);
            }
        }
        std::vector<float> e9(pts.size() * 9);
        direct_.EvaluateSky(pts, e9, prior, nullptr);
        for (size_t q = 0; q < uncached.size(); ++q)
            KeepSky(uncached[q], keys[uncached[q]], &e9[q * 9], n_gauss);
    }

    // The sky at the first `probes` points (traced in every direction, or found with their
    // directions' states), and the directions' prior for the node's other points: a
    // direction's state where every probe sees it or every probe finds it occluded,
    // kSkyBelow (trace it) elsewhere. Empty without probes.
    std::vector<uint8_t> SkyProbes(const std::vector<ProbeKey>& keys, int n_gauss, size_t probes) {
        if (probes == 0)
            return {};
        const size_t nd = direct_.sky_direction_count();
        std::vector<uint8_t> states(probes * nd);  // probes x directions
        std::vector<size_t> traced;                // probes traced now
        std::vector<ReceiverPoint> pts;
        for (size_t k = 0; k < probes; ++k) {
            auto it = sky_states_.find(keys[k]);
            if (it == sky_states_.end()) {
                traced.push_back(k);
                pts.push_back(all_pts_[k]);
                continue;
            }
            std::copy(it->second.begin(), it->second.end(), &states[k * nd]);
            const auto& e = sky_cache_.at(keys[k]);
            std::copy(e.begin(), e.end(), &e9_all_[k * 9]);
        }
        std::vector<float> e9(pts.size() * 9);
        std::vector<uint8_t> st;
        direct_.EvaluateSky(pts, e9, sky_inherited, &st);
        for (size_t q = 0; q < traced.size(); ++q) {
            const size_t k = traced[q];
            std::copy(&st[q * nd], &st[(q + 1) * nd], &states[k * nd]);
            if (KeepSky(k, keys[k], &e9[q * 9], n_gauss))
                sky_states_.emplace(keys[k], std::vector<uint8_t>(&st[q * nd], &st[(q + 1) * nd]));
        }
        std::vector<uint8_t> prior(states.begin(), states.begin() + std::ptrdiff_t(nd));
        for (size_t k = 1; k < probes; ++k)
            for (size_t d = 0; d < nd; ++d)
                if (states[k * nd + d] != prior[d])
                    prior[d] = DirectLight::kSkyBelow;
        return prior;
    }

    // Point k's sky e9 into e9_all_, and into the chart's cache if it lies on a node edge
    // (only control points do: they are the neighbours' too); whether it was cached.
    bool KeepSky(size_t k, const ProbeKey& key, const float* e9, int n_gauss) {
        std::copy(e9, e9 + 9, &e9_all_[k * 9]);
        if (slot_[k] < n_gauss)
            return false;
        std::array<float, 9> rec;
        std::copy(e9, e9 + 9, rec.begin());
        sky_cache_.insert_or_assign(key, rec);
        return true;
    }

    // Back to Gauss and control order, then to field values.
    void ToGaussAndControl(int n_gauss, int n_ctrl, bool control) {
        pts_.resize(size_t(n_gauss));
        albedo_.resize(size_t(n_gauss));
        e9_.assign(size_t(n_gauss) * 9, 0.f);
        cpts_.assign(size_t(n_ctrl), ReceiverPoint{});
        calb_.assign(size_t(n_ctrl), Vec3f{});
        ce9_.assign(size_t(n_ctrl) * 9, 0.f);
        for (size_t k = 0; k < slot_.size(); ++k) {
            const int idx = slot_[k];
            const float* src = &e9_all_[k * 9];
            if (idx < n_gauss) {
                pts_[size_t(idx)] = all_pts_[k];
                albedo_[size_t(idx)] = all_albedo_[k];
                std::copy(src, src + 9, &e9_[size_t(idx) * 9]);
            } else {
                const size_t c = size_t(idx - n_gauss);
                cpts_[c] = all_pts_[k];
                calb_[c] = all_albedo_[k];
                std::copy(src, src + 9, &ce9_[c * 9]);
            }
        }
        const bool radiosity = solver_.opt_.settings.radiosity;
        ToFieldValues(pts_, albedo_, e9_, radiosity, &gauss_vals);
        if (control)
            ToFieldValues(cpts_, calb_, ce9_, radiosity, &ctrl_vals);
    }

    const Solver& solver_;
    const SolveChart& sc_;
    const int ng_, gc_, finest_, max_level_;
    DirectLight& direct_;
    ProbeCache probe_cache_;  // this chart's probes (node corners are shared)
    std::unordered_map<ProbeKey, std::array<float, 9>, ProbeKeyHash> sky_cache_;
    // The sky's probes on node edges: their directions' states (DirectLight::EvaluateSky).
    std::unordered_map<ProbeKey, std::vector<uint8_t>, ProbeKeyHash> sky_states_;
    std::vector<int> slot_;
    std::vector<ProbeKey> keys_;
    std::vector<ReceiverPoint> all_pts_, pts_, cpts_, edge_pts_;
    std::vector<Vec3f> all_albedo_, albedo_, calb_;
    std::vector<float> e9_all_, e9_, ce9_;
};

// --multi-emitter simplify: the lights' extremal boundaries on this chart, a sampler with
// (M+3)^2 Gauss points for the closed form (no rays), one with (M+2)^2 for the combined
// light where some light is in penumbra, and scratch states.
struct Solver::SimplifiedFit {
    const ExtremalBoundaries& eb;
    DirectSampler& fine;
    DirectSampler& medium;
    uint32_t chart;
    std::vector<uint8_t> known{};
    size_t closed = 0, washed = 0, marked = 0, single = 0;  // nodes tested each way
    NodeTest last = NodeTest::kCap;                // SimplifiedNode's test of its last node
    std::unordered_map<size_t, NodeTest> tests{};  // per node, for --multi-emitter-debug
};

void Solver::RefineDirect(uint32_t chart) {
    const SolveChart& sc = charts_[chart];
    const GeometryPin pin = sc.geometry.Pin();
    const int order = fields_[chart].order();
    // A node's polynomial holds (M+1)^2 values per block: a node narrower than M+1 texels
    // describes more than the light map can store, so refinement stops there.
    const int max_level = std::max(0, TexelLevel(sc) - (order >= 3 ? 2 : order >= 1 ? 1 : 0));
    // The lights' and the sky's rays start an eighth of a light-map texel off the surface
    // (never closer than the proxy allows), from visibility points moved onto the real
    // surface first (DirectLight::OnSurface, up to four texels under it). With rays leaving
    // from under the surface, half a texel was needed; it lifted rays out of creases and folds
    // narrower than that, which the reference sees dark (bench/RESULTS.md, "Issue 14
    // (session 7)").
    const float half_texel = RayOffset(chart);
    DirectLight direct(scene_, opt_.settings, vis_,
                       std::max(opt_.ray_offset, half_texel * kDirectOffset), opt_.scene_size,
                       half_texel * DirectLight::kOriginReach);
    // The fixed levels (min_level, sky_level) are meant for a chart as large as the scene: a
    // chart 2^k times smaller starts k levels higher, so that node counts follow world size
    // (lucy's 449 small charts made a million nodes at M0 otherwise).
    const int size_levels =
        std::min(0, int(std::ceil(std::log2(std::max(sc.scale, 1e-30) /
                                            std::max(double(opt_.scene_size), 1e-30)))));
    // Lower orders need finer nodes for the same smooth field (E turns with the surface):
    // a constant over a node covering 20 degrees of a sphere is off by 2%, which an albedo
    // of 0.9 amplifies ninefold. Nodes above min_level are split without a test.
    const int min_level = std::max(0, opt_.min_level +
                                          (order == 0   ? 3
                                           : order == 1 ? 2
                                                        : 0) +
                                          size_levels);

    DirectSampler sampler(*this, sc, order, max_level, direct);
    const double cpu_start = ThreadCpuSeconds();
    // With one polygon light there is nothing to merge (seed 002 simplifies where several
    // sources overlap): simplify is full, without the boundary pass.
    if (opt_.settings.multi_emitter_simplify && direct.light_count() >= 2) {
        // Extremal boundaries first (a few rays per sample): they choose each node's test
        // (multi_emitter.h). A node's samples are still traced, so a shadow the pass
        // missed between its samples shows wherever a node's sample falls in it.
        const int finest = sc.geometry.finest_level();
        const ExtremalBoundaries eb(
            direct,
            [&](float u, float v) {
                auto smp = SampleBilinear(sc.geometry, finest, u, v);
                return PointAt(sc, finest, u, v, smp);
            },
            std::min(max_level, min_level + 1),
            std::max(min_level + 1, max_level - kBoundaryLevelsAboveCap));
        const double cpu_boundary = ThreadCpuSeconds() - cpu_start;
        DirectSampler fine(*this, sc, std::min(order + 2, kMaxGauss - 1), max_level, direct,
                           order + 2);
        fine.use_probes = false;
        DirectSampler medium(*this, sc, std::min(order + 1, kMaxGauss - 1), max_level, direct);
        SimplifiedFit simplified{eb, fine, medium, chart};
        FitDirectLights(chart, sampler, min_level, max_level, &simplified);
        // C0 at T-vertices: finer leaves take the coarser (simplified) leaf's values along
        // their common side, leaves of one size their mean (slave_nodes.h).
        const SlaveNodeStats slaves = TieSlaveNodes(
            &fields_[chart], float(opt_.settings.tolerance), float(reference_ * 0.02));
        fields_[chart].Pull();
        spdlog::debug("chart {}: multi-emitter: {} boundary samples ({:.4f} CPU s); nodes "
                      "tested closed-form {}, one light {}, light-penumbra kept {}, refined {}; "
                      "{} leaves with T-vertices (largest change {:.4f}, {} jumps kept); fit {:.4f} CPU s",
                      chart, eb.sample_points(), cpu_boundary, simplified.closed, simplified.single,
                      simplified.washed, simplified.marked, slaves.slaves, slaves.largest_change,
                      slaves.kept_jumps,
                      ThreadCpuSeconds() - cpu_start - cpu_boundary);
        if (!opt_.multi_emitter_debug.empty())
            WriteMultiEmitterPng(fmt::format("{}/chart-{}.png", opt_.multi_emitter_debug, chart),
                                 eb, fields_[chart], simplified.tests);
    } else {
        FitDirectLights(chart, sampler, min_level, max_level, nullptr);
        spdlog::debug("chart {}: direct light fit {:.4f} CPU s", chart,
                      ThreadCpuSeconds() - cpu_start);
    }
    spdlog::debug("chart {}: direct light refined to {} nodes (depth cap {})", chart,
                  fields_[chart].node_count(), max_level);
    if (direct.has_sky())
        GatherSky(chart, direct, std::min(max_level, std::max(0, opt_.sky_level + size_levels)),
                  max_level);
    RefineForBounces(chart, max_level);
}

// One node under --multi-emitter simplify (seed 002, section 5): its fit into coeffs, and
// the error to refine it by (0: keep it). At most one light reaching the node: as in full.
// Light-light (every light lit or in umbra by the extremal boundaries): the fit at the
// (M+1)^2 Gauss points is tested in L2 by the (M+3)^2 rule and at full's control grid
// against the lights' closed form (no ray), which also catches a shadow the boundary pass
// missed. Light-penumbra (some light in penumbra, two or more reaching): the combined
// light at (M+2)^2 Gauss points, the node's polynomial its L2 projection (the simple
// biquadratic at M2), kept when it misses no sample by more than the tolerance. Both
// tests are relative to the combined light's largest value over the node, so one light's
// shadow that the others wash out passes (docs/method.md, "Several sources").
float Solver::SimplifiedNode(const QuadNode& node, bool control, DirectSampler& sampler,
                             SimplifiedFit& sf, std::vector<float>& coeffs) {
    const ChartField& field = fields_[sf.chart];
    const int order = field.order(), blocks = field.blocks(), ng = order + 1;
    const float tol = float(opt_.settings.tolerance), floor = float(reference_ * 0.02);
    sf.eb.Known(node, &sf.known);
    const bool all_known =
        std::find(sf.known.begin(), sf.known.end(), uint8_t(0)) == sf.known.end();
    const auto reaching =
        std::count_if(sf.known.begin(), sf.known.end(), [](uint8_t k) { return k != 3; });
    if (control && reaching <= 1) {
        // One light reaching the node (lit or in penumbra): nothing washes its shadow out and
        // there is no second source to merge with, so the node is tested as in full (the
        // control grid, max norm; the same rays and values as full).
        ++sf.single;
        sf.last = NodeTest::kSingle;
        sampler.Evaluate(node, true);
        ProjectGauss(order, ng, sampler.gauss_vals.data(), blocks, coeffs.data());
        const float scale =
            std::max({MaxAbs(sampler.gauss_vals), MaxAbs(sampler.ctrl_vals), floor});
        const float err =
            ControlGridError(order, order + 2, coeffs.data(), blocks, sampler.ctrl_vals.data());
        return err > tol * scale ? err : 0;
    }
    if (!control || all_known) {
        sampler.Evaluate(node, false);
        ProjectGauss(order, ng, sampler.gauss_vals.data(), blocks, coeffs.data());
        sf.last = control ? NodeTest::kLightLight : NodeTest::kCap;
        if (!control)
            return 0;
        ++sf.closed;
        sf.fine.known = sf.known;
        sf.fine.Evaluate(node, true);
        // In L2 by the (M+3)^2 rule, and at full's control grid (its edges and corners,
        // where an L2 norm hides an overshoot: Veach's plates, bench/RESULTS.md, "Issue 15
        // (session 7)"), both against the closed form.
        const float err = std::max(
            GaussL2Error(order, sf.fine.order() + 1, coeffs.data(), blocks,
                         sf.fine.gauss_vals.data()),
            ControlGridError(order, order + 2, coeffs.data(), blocks, sf.fine.ctrl_vals.data()));
        const float scale = std::max({MaxAbs(sampler.gauss_vals), MaxAbs(sf.fine.gauss_vals),
                                      MaxAbs(sf.fine.ctrl_vals), floor});
        return err > tol * scale ? err : 0;
    }
    sf.last = NodeTest::kLightPenumbra;
    sf.medium.Evaluate(node, false);
    const std::vector<float>& values = sf.medium.gauss_vals;
    const int nm = sf.medium.order() + 1;
    ProjectGauss(order, nm, values.data(), blocks, coeffs.data());
    const float err = GaussResidualMax(order, nm, coeffs.data(), blocks, values.data());
    if (err > tol * std::max(MaxAbs(values), floor)) {
        ++sf.marked;
        return err;
    }
    ++sf.washed;
    return 0;
}

// Every node gets its fit when it is made; nodes whose fit misses the control points wait
// in a queue ordered by integrated error (error x area), largest first, ties by node index
// (deterministic). When the chart's node budget runs out, the worst places have been
// refined and every node still holds its own fit: the budget degrades the whole chart
// evenly instead of leaving the last quadrants of a depth-first walk at the root's
// resolution.
void Solver::FitDirectLights(uint32_t chart, DirectSampler& sampler, int min_level, int max_level,
                             SimplifiedFit* simplified) {
    ChartField& field = fields_[chart];
    const int order = field.order(), blocks = field.blocks();
    const int ng = order + 1, gc = order + 2;
    std::vector<float> coeffs(size_t(field.stride()));
    struct Candidate {
        float priority;
        size_t node;
        bool operator<(const Candidate& o) const {
            return priority != o.priority ? priority < o.priority : node > o.node;
        }
    };
    std::priority_queue<Candidate> queue;
    std::vector<size_t> stack;
    auto fit = [&](size_t n) {
        const QuadNode node = field.node(n);
        if (int(node.level) < std::min(min_level, max_level)) {
            stack.push_back(n);
            return;
        }
        const bool control = int(node.level) < max_level;
        if (simplified) {
            const float err = SimplifiedNode(node, control, sampler, *simplified, coeffs);
            if (!opt_.multi_emitter_debug.empty())
                simplified->tests[n] = simplified->last;
            std::copy(coeffs.begin(), coeffs.end(), field.value(n));
            std::copy(coeffs.begin(), coeffs.end(), field.unshot(n));
            if (err > 0)
                queue.push({err * std::ldexp(1.f, -2 * int(node.level)), n});
            return;
        }
        sampler.Evaluate(node, control);
        float scale = MaxAbs(sampler.gauss_vals);
        ProjectGauss(order, ng, sampler.gauss_vals.data(), blocks, coeffs.data());
        std::copy(coeffs.begin(), coeffs.end(), field.value(n));
        std::copy(coeffs.begin(), coeffs.end(), field.unshot(n));
        if (!control) {
            // At the cap, a shadow edge inside the node (one ray per point of the control
            // grid's size to each light's centre): split below it, ranked as if the node
            // missed by its largest value.
            if (int(node.level) < max_level + kEdgeLevelsBelowCap &&
                sampler.ShadowEdgeOnGrid(node, gc))
                queue.push({std::max(scale, float(reference_ * 0.02)) *
                                std::ldexp(1.f, -2 * int(node.level)),
                            n});
            return;
        }
        scale = std::max({scale, MaxAbs(sampler.ctrl_vals), float(reference_ * 0.02)});
        float err = ControlGridError(order, gc, coeffs.data(), blocks, sampler.ctrl_vals.data());
        if (err <= float(opt_.settings.tolerance) * scale && sampler.MissedShadowEdge(node))
            err = scale;  // ranked as if the node missed by its largest value
        if (err > float(opt_.settings.tolerance) * scale)
            queue.push({err * std::ldexp(1.f, -2 * int(node.level)), n});
    };
    fit(0);
    while (!stack.empty()) {
        const size_t n = stack.back();
        stack.pop_back();
        const int32_t first = field.Subdivide(n);
        for (int c = 3; c >= 0; --c)
            fit(size_t(first + c));
    }
    // light_probes_inherit: a node one level above the depth cap passes what its probes
    // agreed on to its children's new probes (its other points took it already), as the
    // sky's children do (GatherSky). Only there: the children, at the cap, split no further
    // but by fresh rays (kEdgeLevelsBelowCap), so an agreement is never passed on twice;
    // passed down from every coherent level, lucy lost 0.25 points (bench/RESULTS.md,
    // "Issue 13 (session 19)").
    const bool inherit = opt_.settings.light_probes_inherit && !simplified;
    while (!queue.empty() && field.node_count() + 4 <= NodeBudget(charts_[chart])) {
        const size_t n = queue.top().node;
        queue.pop();
        sampler.light_inherited.clear();
        if (inherit && int(field.node(n).level) + 1 == max_level)
            sampler.light_inherited = sampler.LightProbeAgreement(field.node(n));
        const int32_t first = field.Subdivide(n);
        for (int c = 0; c < 4; ++c)
            fit(size_t(first + c));
        CHECK(stack.empty());
    }
    sampler.light_inherited.clear();
    field.Pull();
}

// The sky is gathered at sky_level and pushed down, like indirect light; leaves above
// sky_level are split down to it first (within the node budget). Gathered at the leaves
// the lights left, it was sampled at min_level where no light refined (the side away from
// the key, creases, undersides), and 3 x 3 points per node missed where its visibility
// turns: the bunny under the sky alone had RMS 9.6 %, mean -3.3 % (bench/RESULTS.md,
// "Issue 14 (session 6)"). Below sky_level a node is split, up to sky_extra_levels deeper,
// where its fit misses the sky at its control grid by more than the tolerance (scale as in
// FitDirectLights) and by more than sky_fit_floor directions' shares of E: a point's sky
// steps by one share as a fixed direction passes from seen to occluded, so a smaller miss
// is mostly the directions' own steps, which a finer node follows but does not correct.
// A split node's children trace only the directions its four corner probes disagreed on
// (the others as they found them): a direction every corner saw, or every corner found
// occluded, was already taken so at the node's other points, and its fit missed for the
// directions that change across it. This is what makes the deeper sky cheap: below the
// parent, rays go only where the parent's visibility turns. Below the default's depth the
// floor is sky_deep_floor, doubled per level (deep_steps).
void Solver::GatherSky(uint32_t chart, DirectLight& direct, int sky_level, int max_level) {
    ChartField& field = fields_[chart];
    const int order = field.order(), blocks = field.blocks(), ng = order + 1, gc = order + 2;
    const int deepest = std::min(max_level, sky_level + opt_.settings.sky_extra_levels);
    const float tol = float(opt_.settings.tolerance), floor = float(reference_ * 0.02);
    const float steps = float(opt_.settings.sky_fit_floor) * direct.SkyDirectionShare();
    // Nodes kSkyDefaultDepth or more levels below sky_level split only on a miss of
    // sky_deep_floor shares (a few nodes whose fit is far off), twice that one level deeper
    // and so on: the points are spread by area, so a node's part of their squared error is
    // its miss squared times its area, and a node half as wide must miss twice as much to
    // matter as much. (A floor the same at every deep level, session 15's, spent about twice the
    // added leaves for nearly the same gain on lucy and the bunny: bench/RESULTS.md,
    // "Issue 14 (session 16)".)
    auto deep_steps = [&](int below) {
        return std::max(steps, std::ldexp(float(opt_.settings.sky_deep_floor), below) *
                                   direct.SkyDirectionShare());
    };
    DirectSampler sampler(*this, charts_[chart], order, max_level, direct);
    sampler.parts = DirectLight::kSky;
    sampler.use_probes = true;  // small nodes: directions shared with the probes (SkyShared)
    std::vector<float> coeffs(size_t(field.stride()));
    const size_t nodes_before = field.node_count();
    // Nodes to visit, each with the directions its tested parent's probes agreed on.
    std::vector<std::pair<size_t, std::vector<uint8_t>>> stack;
    stack.emplace_back(0, std::vector<uint8_t>{});
    while (!stack.empty()) {
        const size_t n = stack.back().first;
        sampler.sky_inherited = std::move(stack.back().second);
        stack.pop_back();
        const bool room = field.node_count() + 4 <= NodeBudget(charts_[chart]);
        if (field.node(n).leaf() && int(field.node(n).level) < sky_level && room)
            field.Subdivide(n);
        const QuadNode node = field.node(n);
        bool split = !node.leaf() && int(node.level) < sky_level;
        std::vector<uint8_t> inherit;
        if (!split) {
            const bool test = int(node.level) < deepest && (!node.leaf() || room);
            sampler.Evaluate(node, test);
            ProjectGauss(order, ng, sampler.gauss_vals.data(), blocks, coeffs.data());
            if (test) {
                const float scale = std::max(
                    {MaxAbs(sampler.gauss_vals), MaxAbs(sampler.ctrl_vals), floor});
                const int below = int(node.level) - (sky_level + kSkyDefaultDepth);
                split =
                    ControlGridError(order, gc, coeffs.data(), blocks, sampler.ctrl_vals.data()) >
                    std::max(tol * scale, below >= 0 ? deep_steps(below) : steps);
                if (split && node.leaf())
                    field.Subdivide(n);
                if (split)
                    inherit = sampler.sky_prior;
            }
        }
        if (split) {
            const int32_t first = field.node(n).first_child;
            for (int c = 3; c >= 0; --c)
                stack.emplace_back(size_t(first + c), inherit);
            continue;
        }
        float* pend = field.pending(n);
        for (int k = 0; k < field.stride(); ++k)
            pend[k] += coeffs[size_t(k)];
    }
    field.PushPending();
    spdlog::debug("chart {}: sky from level {} to {} (cap {}): {} nodes added", chart, sky_level,
                  deepest, max_level, field.node_count() - nodes_before);
}

}  // namespace mebake::solve
