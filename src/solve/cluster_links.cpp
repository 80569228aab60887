// Cluster links for the indirect pass (hierarchical radiosity with clustering: Smits et al.
// 1994, Sillion 1995; face clusters with vector irradiance: Willmott 1999, Gobbetti 2003;
// docs/method.md, Cluster links).
//
// Without them, every receiver chart refines its own links to every shooter: at least one
// link of (M+1)^2 x 4 rays per (shooter, receiver) pair and batch, a cost that grows with
// the square of the chart count. Here a shooter walks the cluster tree (cluster_tree.h)
// from the root. A cluster far from the shooter, against its own size and against the
// chart-level rule every receiver would apply at its root (node size / distance <=
// receiver_tau, emitter size / distance <= emitter_tau), gets one link: its visibility
// is estimated by a few rays between stratified points of its charts and the shooter's
// texels. All rays agreeing, or an irradiance bound (shooter power / pi d^2) times the
// visibility uncertainty below the tolerance, accepts the link; partial visibility opens
// the cluster into its children, down to single charts, which then refine their links
// chart by chart as before (Solver::Gatherer::Shoot).
//
// An accepted link costs no further rays: vector irradiance at a point does not depend on
// the receiver's normal, so each chart of the cluster evaluates the shooter's texels
// through the exact kernel (transfer.h) at its own root Gauss points, with its own normals
// and horizon, weighted by the cluster's visibility (Gatherer::ShootCluster). Links are
// rebuilt for every group of shooters from the tree and the emitters alone, so nothing
// needs to be checkpointed, and each shooter's decisions are its own: the result is the
// same for any thread count.
#include "core/check.h"
#include "solve/rays.h"
#include "solve/solver.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace mebake::solve {

// The tree over the charts' root spheres, and each chart's visibility samples: its level-1
// texels (centre, normal, ray origin off the surface).
void Solver::BuildClusters() {
    const uint32_t nc = uint32_t(charts_.size());
    std::vector<ChartBound> bounds(nc);
    cluster_samples_.clear();
    cluster_sample_first_.assign(size_t(nc) + 1, 0);
    for (uint32_t c = 0; c < nc; ++c) {
        const SolveChart& sc = charts_[c];
        const GeometryPin pin = sc.geometry.Pin();
        const auto& root = sc.geometry.At(0, 0, 0);
        bounds[c] = {root.position, root.radius, sc.scale};
        const int level = std::min(1, sc.geometry.finest_level());
        const float eps = RayOffset(c);
        cluster_sample_first_[c] = uint32_t(cluster_samples_.size());
        for (const auto& g : sc.geometry.levels[size_t(level)])
            if (g.area > 0)
                cluster_samples_.push_back({g.position, g.normal, g.vis_point + g.normal * eps});
    }
    cluster_sample_first_[nc] = uint32_t(cluster_samples_.size());
    clusters_ = ClusterTree(bounds);
}

// The fraction of opt_.cluster_rays rays that reach the shooter, between stratified
// (receiver sample, emitter texel) pairs that face each other. *valid is false when no
// pair faces: the cluster's samples cannot tell, and the caller opens it.
float Solver::ClusterVisibility(const ClusterTree::Node& node, const Emitter& em,
                                SegmentBatch* batch, bool* valid) const {
    const int le = std::min(1, int(em.levels.size()) - 1);
    const auto& texels = em.levels[size_t(le)];
    const float eps = RayOffset(em.chart);
    auto faces = [&](const ClusterSample& s, const Emitter::Texel& t) {
        if (t.area <= 0 || t.db_max <= 0)
            return false;
        const Vec3f d = t.pos - s.pos;
        return Dot(d, s.nrm) > 0 && Dot(d, t.nrm) < 0;
    };
    // Two passes over the pairs in a fixed order: count, then take every (m / K)-th. Each
    // sample starts its texels one further than the last, so a stride that is a multiple of
    // the texel count does not send every ray to the same texel.
    const size_t nt = texels.size();
    uint64_t m = 0;
    for (uint32_t c : clusters_.ChartsOf(node))
        for (uint32_t s = cluster_sample_first_[c]; s < cluster_sample_first_[c + 1]; ++s)
            for (const auto& t : texels)
                m += faces(cluster_samples_[s], t) ? 1 : 0;
    *valid = m > 0;
    if (m == 0)
        return 0;
    // At least a few rays per chart: with a fixed count, a shadow border crossing one
    // chart of a large cluster was missed (the occluder test: 50 % errors on two charts).
    const uint64_t k_rays = std::min<uint64_t>(
        m, std::max<uint64_t>(uint64_t(std::max(1, opt_.cluster_rays)),
                              uint64_t(opt_.cluster_rays_per_chart) * node.count));
    batch->Clear();
    uint64_t index = 0, next = 0, taken = 0;
    size_t rotation = 0;
    for (uint32_t c : clusters_.ChartsOf(node)) {
        for (uint32_t s = cluster_sample_first_[c]; s < cluster_sample_first_[c + 1]; ++s) {
            const ClusterSample& cs = cluster_samples_[s];
            ++rotation;
            for (size_t q = 0; q < nt; ++q) {
                const auto& t = texels[(q + rotation) % nt];
                if (!faces(cs, t))
                    continue;
                // The pair nearest the middle of stratum `taken`.
                next = (2 * taken + 1) * m / (2 * k_rays);
                if (index++ != next || taken >= k_rays)
                    continue;
                ++taken;
                batch->AddSegment(cs.org, t.vis + t.nrm * eps);
            }
        }
    }
    batch->Trace(vis_, RayKind::kCluster);
    size_t open = 0;
    for (uint8_t o : batch->occluded)
        open += o ? 0 : 1;
    return float(open) / float(batch->size());
}

// One shooter's walk down the cluster tree: (*links)[c] for every chart c, kOpenLink or
// the visibility of the accepted cluster link above it.
void Solver::LinkClusters(const Emitter& em, std::vector<float>* links, uint64_t* accepted,
                          uint64_t* opened) const {
    links->assign(charts_.size(), kOpenLink);
    *accepted = *opened = 0;
    if (clusters_.empty())
        return;
    const auto& root = em.levels[0][0];
    if (root.area <= 0 || root.db_max <= 0) {
        links->assign(charts_.size(), 0.f);  // nothing to shoot
        return;
    }
    const double power = double(root.db_max) * root.area;
    const double reference = opt_.settings.tolerance * reference_;
    const double negligible = 1e-3 * reference;  // as the chart-level links
    const double tolerance = opt_.cluster_tolerance * reference;
    const double receiver_tau = ReceiverTau();
    // A single chart is cheaper to link exactly when its root link needs no more rays.
    const int ng = opt_.settings.order + 1;
    const bool leaves_exact = ng * ng * 4 <= opt_.cluster_rays;
    const auto& nodes = clusters_.nodes();
    SegmentBatch batch;
    std::vector<int32_t> stack(1, 0);
    while (!stack.empty()) {
        const ClusterTree::Node& node = nodes[size_t(stack.back())];
        stack.pop_back();
        auto open = [&] {
            if (node.leaf()) {
                ++*opened;
            } else {
                stack.push_back(node.child[1]);
                stack.push_back(node.child[0]);
            }
        };
        const double dist = double(Length(node.center - em.center)) - node.radius - em.radius;
        const double bound = dist > 0 ? power / (std::numbers::pi * dist * dist) : 1e300;
        const bool far = dist > 0 && node.radius <= opt_.cluster_tau * dist &&
                         node.max_scale / dist <= receiver_tau &&
                         em.scale / dist <= opt_.emitter_tau;
        if ((!far && bound >= negligible) || (node.leaf() && leaves_exact)) {
            open();
            continue;
        }
        bool valid = false;
        const float v = ClusterVisibility(node, em, &batch, &valid);
        const bool partial = v > 0 && v < 1;
        if (!valid || (partial && bound >= tolerance)) {
            open();
            continue;
        }
        ++*accepted;
        for (uint32_t c : clusters_.ChartsOf(node))
            (*links)[c] = v;
    }
}

}  // namespace mebake::solve
