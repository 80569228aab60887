// One Southwell batch as a task graph (task_graph.h). Shooters are the charts with power
// within batch_fraction of the largest, in chart order (the first batch shoots every
// chart, so emission, added only to first shots, goes out once), and the lagging charts
// (Solver::LaggingCharts) whatever their power; once the scan's unshot power is below
// stop_fraction, the lagging charts alone. They are built and
// gathered a group of `emitter_group` at a time: all at once, emitters took ~80 KB per
// chart, memory that grew with the chart count rather than the lighting. Light that one
// group delivers may be shot by a later group of the same batch (Southwell shooting allows
// any order); the groups depend on the chart order only, never on the thread count.
//
// Per group g, with shooters s_k and every chart r a receiver, the nodes and their edges:
//
//   Gather(g-1, s_k) ──► Build(g, k) ──► Links(g, k) ──► Join(g) ──► Gather(g, r) ──► Free(g)
//                            │                                        ▲     ▲
//                            └────────► Clear(g, k) ──────────────────┘     │ (r = s_k)
//   Gather(g-1, r) ─────────────────────────────────────────────────────────┘
//   Free(g-1) ──► Build(g+1, k)
//
// Build: the shooter's emitter from its unshot field. Links: its cluster links. Clear: the
// shooter's unshot set to zero, after its emitter holds it and before it gathers again.
// Gather: the receiver's field gathers every emitter of the group in their fixed order.
// Free: the group's emitters and links released; the next group but one waits for it,
// so at most two groups of emitters are alive. Each field is written by a chain of nodes
// that the edges order (Gather(g-1, t), Build(g, k), Clear(g, k), Gather(g, t) for t =
// s_k), and an emitter is read only after it is built, so every value is the one of a
// solve that runs the phases one after the other: the same bits for any thread count.
// Without barriers, the gathers of one group overlap the emitter builds of the next (and
// the page faults of their evicted pyramids and fields).
//
// The graph is built and run kGroupsPerGraph groups at a time: a batch's graph of every
// group held (charts x groups) nodes, 224K at 100M triangles (3672 charts, 58 groups) and
// ~30 MB, memory that grew with the square of the chart count. Each window ends in a
// barrier: only more order between the nodes, so the same values.
#include "solve/solver.h"

#include "core/check.h"
#include "core/task_graph.h"

#include <algorithm>
#include <memory>

namespace mebake::solve {

size_t Solver::ShootBatch(const std::vector<double>& power, double largest, bool first,
                          const std::vector<uint8_t>& lagging, double* shot_power,
                          std::vector<double>* kept) {
    const uint32_t nc = uint32_t(charts_.size());
    std::vector<uint32_t> shooters;
    *shot_power = 0;
    kept->assign(power.begin(), power.end());
    for (uint32_t c = 0; c < nc; ++c)
        if (power[c] > 0 && (first || lagging[c] || power[c] >= opt_.batch_fraction * largest)) {
            shooters.push_back(c);
            *shot_power += power[c];
            (*kept)[c] = 0;
        }
    const size_t group = std::max<size_t>(1, opt_.emitter_group);
    const size_t groups = (shooters.size() + group - 1) / group;
    const uint64_t gathers = nc * groups;
    std::atomic<uint64_t> gathered{0};
    const double unshot =
        stats_.emitted_power > 0 ? stats_.unshot_power / stats_.emitted_power : 0;

    struct Group {
        std::vector<uint32_t> shooters;
        std::vector<Emitter> emitters;
        std::vector<std::vector<float>> links;  // empty without cluster links
        std::vector<uint64_t> accepted, opened;
    };
    constexpr size_t kGroupsPerGraph = 4;
    for (size_t w0 = 0; w0 < groups; w0 += kGroupsPerGraph) {
        const size_t w1 = std::min(groups, w0 + kGroupsPerGraph);
        std::vector<Group> state(w1 - w0);
        TaskGraph graph;
        using Node = TaskGraph::Node;
        std::vector<Node> prev_gather;  // Gather(g-1, r), per chart
        Node prev_free = 0, prev_prev_free = 0;
        for (size_t g = w0; g < w1; ++g) {
            Group& gs = state[g - w0];
            const size_t g0 = g * group, g1 = std::min(shooters.size(), g0 + group);
            gs.shooters.assign(shooters.begin() + ptrdiff_t(g0),
                               shooters.begin() + ptrdiff_t(g1));
            const size_t ns = gs.shooters.size();
            gs.emitters.resize(ns);
            if (opt_.cluster_links) {
                gs.links.resize(ns);
                gs.accepted.resize(ns);
                gs.opened.resize(ns);
            }
            const Node join = graph.Add([] {});
            std::vector<Node> clear(ns);
            for (size_t k = 0; k < ns; ++k) {
                const uint32_t chart = gs.shooters[k];
                const Node build = graph.Add([this, &gs, k, chart, first] {
                    BuildEmitter(chart, first, &gs.emitters[k]);
                });
                if (g > w0)
                    graph.Precede(prev_gather[chart], build);
                if (g > w0 + 1)
                    graph.Precede(prev_prev_free, build);
                Node built = build;
                if (opt_.cluster_links) {
                    built = graph.Add([this, &gs, k] {
                        LinkClusters(gs.emitters[k], &gs.links[k], &gs.accepted[k],
                                     &gs.opened[k]);
                    });
                    graph.Precede(build, built);
                }
                graph.Precede(built, join);
                clear[k] = graph.Add([this, chart] {
                    const RegionPin pin = fields_[chart].Pin();
                    fields_[chart].ClearUnshot();
                });
                graph.Precede(build, clear[k]);
            }
            const Node free = graph.Add([&gs] {
                std::vector<Emitter>().swap(gs.emitters);
                std::vector<std::vector<float>>().swap(gs.links);
            });
            std::vector<Node> gather(nc);
            for (uint32_t r = 0; r < nc; ++r) {
                gather[r] = graph.Add([this, &gs, &gathered, gathers, unshot, r] {
                    Gather(r, gs.emitters, gs.links);
                    if (progress_ && *progress_)
                        (*progress_)({next_batch_, ++gathered, gathers, unshot, 0});
                });
                graph.Precede(join, gather[r]);
                if (g > w0)
                    graph.Precede(prev_gather[r], gather[r]);
                graph.Precede(gather[r], free);
            }
            for (size_t k = 0; k < ns; ++k)
                graph.Precede(clear[k], gather[gs.shooters[k]]);
            prev_gather = std::move(gather);
            prev_prev_free = prev_free;
            prev_free = free;
        }
        graph.Run();
        for (const Group& gs : state)  // integer sums, in group and shooter order
            for (size_t k = 0; k < gs.accepted.size(); ++k) {
                stats_.cluster_links += gs.accepted[k];
                stats_.opened_links += gs.opened[k];
            }
    }
    return shooters.size();
}

}  // namespace mebake::solve
