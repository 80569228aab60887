// The gathers' deferred link rays (solver.cpp, Gatherer::Resolve): the same fields, byte for
// byte, as tracing link by link, with link probes and without, whatever the batch size.
#include "patch_fixture.h"
#include "solve/rays.h"
#include "solve/solver.h"

#include <gtest/gtest.h>

#include <cstring>
#include <vector>

namespace mebake::solve {
namespace {

struct LitBoxRun {
    std::vector<float> coeffs;  // every chart's node values, in node order
    uint64_t link_rays = 0;
};

LitBoxRun SolveLitBox(size_t defer_pairs, int link_probes) {
    testing::LitBox box(5, 32, true);  // the block casts shadows: partial links
    SolveOptions opt;
    opt.settings.max_bounces = 4;
    opt.link_probes = link_probes;
    opt.link_defer_pairs = defer_pairs;
    Solver solver(box.scene, box.charts, box.vis, opt);
    solver.Run();
    LitBoxRun r;
    for (const ChartField& f : solver.fields())
        for (size_t n = 0; n < f.node_count(); ++n)
            r.coeffs.insert(r.coeffs.end(), f.value(n), f.value(n) + f.stride());
    const SolveStats st = solver.stats();
    r.link_rays = st.rays_by_kind[size_t(RayKind::kLink)];
    return r;
}

TEST(DeferredLinks, SameBytesAsLinkByLink) {
    for (int probes : {8, 0}) {
        const LitBoxRun one = SolveLitBox(1, probes);  // resolved after every link
        EXPECT_GT(one.link_rays, 0u);
        for (size_t defer : {size_t(37), SolveOptions{}.link_defer_pairs}) {
            const LitBoxRun many = SolveLitBox(defer, probes);
            ASSERT_EQ(many.coeffs.size(), one.coeffs.size()) << probes << " " << defer;
            EXPECT_EQ(std::memcmp(many.coeffs.data(), one.coeffs.data(),
                                  one.coeffs.size() * sizeof(float)),
                      0)
                << "probes " << probes << ", " << defer << " pairs";
            EXPECT_EQ(many.link_rays, one.link_rays);
        }
    }
}

}  // namespace
}  // namespace mebake::solve
