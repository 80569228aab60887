// Error-driven link refinement (solve/link_refine.h): the irradiance bound with normal
// cones holds for emitter squares near and far, and in a lit box (five charts touching at its edges,
// several bounces) the solve with the rule stays within its tolerance of the purely
// geometric refinement while tracing fewer link rays.
#include "solve/link_refine.h"

#include "core/parallel.h"
#include "patch_fixture.h"
#include "solve/rays.h"
#include "solve/solver.h"
#include "solve/transfer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <numbers>

namespace mebake::solve {
namespace {

// E at x (normal n) from a square of side `side` centred at c with normal m, radiosity 1,
// integrated over 64 x 64 sub-squares with the solver's kernel.
Vec3d SquareIrradiance(const Vec3d& x, const Vec3d& n, const Vec3d& c, const Vec3d& m,
                       double side) {
    const Vec3d ref = std::abs(m.x) < 0.9 ? Vec3d(1, 0, 0) : Vec3d(0, 1, 0);
    const Vec3d tu = Normalize(Cross(ref, m)), tv = Cross(m, tu);
    constexpr int kN = 64;
    const double h = side / kN;
    Vec3d sum{};
    for (int j = 0; j < kN; ++j)
        for (int i = 0; i < kN; ++i) {
            const Vec3d p = c + tu * ((i + 0.5) * h - side / 2) + tv * ((j + 0.5) * h - side / 2);
            Vec3d e;
            if (TexelTransfer(Vec3f(x), Vec3f(n), {Vec3f(p), Vec3f(m), float(h * h)}, h, &e))
                sum += e;
        }
    return sum;
}

struct Rng {
    uint64_t state = 7;
    double operator()() {
        state = state * 6364136223846793005ull + 1442695040888963407ull;
        return double(state >> 11) / double(1ull << 53);
    }
    Vec3d Dir() {
        for (;;) {
            const Vec3d d(2 * (*this)() - 1, 2 * (*this)() - 1, 2 * (*this)() - 1);
            if (Length(d) > 0.1 && Length(d) < 1)
                return Normalize(d);
        }
    }
    // A unit vector within `angle` of the unit vector a.
    Vec3d Tilt(const Vec3d& a, double angle) {
        const Vec3d t = Normalize(Cross(a, Dir()));
        const double b = angle * (*this)();
        return a * std::cos(b) + t * std::sin(b);
    }
};

// The bound with normal cones holds for n . E at a receiver point x inside its sphere, with
// its normal n inside its cone, from a square inside the emitter's sphere and cone: random
// pairs near and far, and nearly coplanar neighbours (where it must be small to be of use).
TEST(LinkRefine, ConeBoundHoldsForCosinesAtBothEnds) {
    Rng rnd;
    int near = 0, small = 0, lit = 0;
    double tight = 0;
    for (int k = 0; k < 600; ++k) {
        const bool flat = k % 2 == 1;  // a gently curved surface: both sides near z = 0
        const double side = 0.5 + rnd();
        const Vec3d up(0, 0, 1);
        const double tr = flat ? 0.2 * rnd() : 1.2 * rnd(), te = flat ? 0.2 * rnd() : 1.2 * rnd();
        const Vec3d ar = flat ? rnd.Tilt(up, 0.1) : rnd.Dir(), ae = flat ? rnd.Tilt(up, 0.1) : rnd.Dir();
        const Vec3d n = rnd.Tilt(ar, tr), m = rnd.Tilt(ae, te);
        const double rr = 0.3 * side * rnd();
        const Vec3d x = rnd.Dir() * (rr * rnd());  // the receiver's sphere is at the origin
        Vec3d c = rnd.Dir() * (4 * rnd() * side);
        if (flat)
            c = Vec3d(c.x, c.y, 0.05 * side * (2 * rnd() - 1)) +
                Normalize(Vec3d(c.x, c.y, 0)) * (0.7 * side);
        const double re = side * std::sqrt(0.5);
        near += Length(c) - rr - re <= 0 ? 1 : 0;
        const double e = Dot(SquareIrradiance(x, n, c, m, side), n);
        const LinkSide recv{Vec3f(0, 0, 0), float(rr), {Vec3f(ar), float(tr) + 1e-6f}};
        const LinkSide emit{Vec3f(c), float(re), {Vec3f(ae), float(te) + 1e-6f}};
        const double bound = ConeLinkBound(1, side * side, recv, emit);  // uniform radiosity 1
        EXPECT_LE(e, bound * (1 + 1e-5) + 1e-9) << "k " << k;
        small += flat && bound < 0.25 ? 1 : 0;
        tight = std::max(tight, e / bound);
        lit += flat && e > 1e-4 ? 1 : 0;
    }
    std::printf("touching %d, flat with bound < 1/4: %d, lit flat %d, largest n.E / bound %.3f\n",
                near, small, lit, tight);
    EXPECT_GT(near, 60);    // touching pairs are tested too
    EXPECT_GT(small, 150);  // and there the bound is far below the half-space's 1
    EXPECT_GT(lit, 20);     // with light to bound
}

// ConeLinkBound by its angles (acos, add, cos), as it was computed before it took the
// angles' sums by the sum formulas of their cosines and sines.
double AngleFormBound(double db_max, double power, const LinkSide& r, const LinkSide& e) {
    const double half_pi = std::numbers::pi / 2;
    auto angle = [](const Vec3f& a, const Vec3f& b) {
        return std::acos(std::clamp(double(Dot(a, b)), -1.0, 1.0));
    };
    auto max_cosine = [&](const Vec3f& dir, double spread, const NormalCone& cone) {
        if (cone.angle >= half_pi)
            return 1.0;
        const double gap = angle(dir, cone.axis) - cone.angle - spread;
        return gap <= 0 ? 1 : gap >= half_pi ? 0 : std::cos(gap);
    };
    double band = 1;
    if (r.cone.angle < half_pi && e.cone.angle < half_pi) {
        // The cones' angles summed in double (the old form rounded their sum to float).
        const double psi = double(r.cone.angle) + e.cone.angle + angle(r.cone.axis, e.cone.axis);
        band = std::min(1.0, 2 * (1 - std::cos(std::min(psi, std::numbers::pi))));
    }
    const Vec3f d = e.center - r.center;
    const double dist = Length(d), gap = dist - r.radius - e.radius;
    if (gap <= 0)
        return db_max * band;
    const Vec3f u = d / float(dist);
    const double alpha = std::asin(std::min(1.0, (double(r.radius) + e.radius) / dist));
    return std::min(db_max * band, power / (std::numbers::pi * gap * gap) *
                                       max_cosine(u, alpha, r.cone) * max_cosine(-u, alpha, e.cone));
}

// ConeLinkBound's sums of angles by their cosines and sines agree with the angles' form to
// rounding, touching and apart, with cones narrow, wide and open (>= pi/2), facing and not.
TEST(LinkRefine, ConeBoundEqualsItsAngleFormToRounding) {
    Rng rnd;
    int apart = 0, partial = 0;
    for (int k = 0; k < 20000; ++k) {
        const float ta = float(2.0 * rnd() * rnd()), tb = float(2.0 * rnd() * rnd());
        const Vec3f aa(rnd.Dir()), ab(rnd.Dir());
        const float ra = float(rnd()), rb = float(rnd());
        const Vec3f cb(rnd.Dir() * (4 * rnd()));
        const LinkSide a{{0, 0, 0}, ra, {aa, ta}}, b{cb, rb, {ab, tb}};
        const double db_max = 0.5 + rnd(), power = 0.1 + 3 * rnd();
        const double gap = Length(cb) - ra - rb;
        const double scale = db_max + (gap > 0 ? power / (std::numbers::pi * gap * gap) : 0);
        const double got = ConeLinkBound(db_max, power, a, b);
        const double want = AngleFormBound(db_max, power, a, b);
        EXPECT_NEAR(got, want, 1e-9 * scale) << "k " << k;
        apart += gap > 0;
        partial += gap > 0 && want > 0 && want < 0.99 * db_max;
    }
    EXPECT_GT(apart, 5000);
    EXPECT_GT(partial, 1000);  // the cosines' bound, not the band's, decides there
}

// ConeAround takes one acos (of the smallest cosine) and ConeLinkBound skips the axes'
// angle where the cones alone make the band 1: both must give the plain formulas (the
// largest of the normals' angles, bit for bit; band = min(1, 2 (1 - cos psi)), to
// rounding: ConeLinkBound sums the angles by their cosines and sines).
TEST(LinkRefine, ConeShortcutsGiveThePlainFormulasBits) {
    Rng rnd;
    for (int k = 0; k < 2000; ++k) {
        const Vec3f axis(rnd.Tilt(Vec3d(0, 0, 1), 3.0));
        std::vector<Vec3f> normals;
        float widest = 0;
        for (int i = 0; i < 1 + k % 30; ++i) {
            const double spread = 0.02 + 2.0 * rnd();
            const Vec3d dir = rnd.Tilt(Vec3d(axis), spread);
            const Vec3f m(dir * (0.5 + rnd()));
            normals.push_back(i % 7 == 6 ? Vec3f(0, 0, 0) : m);
            if (Dot(normals.back(), normals.back()) > 0)
                widest = std::max(widest, float(std::acos(std::clamp(
                                              double(Dot(axis, Normalize(normals.back()))),
                                              -1.0, 1.0))));
        }
        const NormalCone cone = ConeAround(axis, normals.data(), normals.size());
        EXPECT_EQ(cone.angle, widest >= std::numbers::pi / 2 ? float(std::numbers::pi) : widest)
            << "k " << k;
        // Two cones at a distance, touching (the band alone) and apart.
        const float ta = float(0.8 * rnd()), tb = float(0.8 * rnd());
        const Vec3f aa(rnd.Dir()), ab(rnd.Tilt(Vec3d(aa), 1.0));
        const float gap = k % 2 ? 0.f : 3.f;
        const LinkSide a{{0, 0, 0}, 1.f, {aa, ta}}, b{{gap + 2.f, 0, 0}, 1.f, {ab, tb}};
        const double psi = double(ta) + tb + std::acos(std::clamp(double(Dot(aa, ab)), -1.0, 1.0));
        const double band = std::min(1.0, 2 * (1 - std::cos(std::min(psi, std::numbers::pi))));
        if (k % 2)
            EXPECT_NEAR(ConeLinkBound(2, 3, a, b), 2 * band, 1e-12) << "k " << k;
        else
            EXPECT_LE(ConeLinkBound(2, 3, a, b), 2 * band + 1e-12) << "k " << k;
    }
}

// The tight sphere holds every sphere it was built from and is never larger than the
// fallback; for a curved strip (the case it is for) it is much smaller than a sphere
// centred on the strip's middle point.
TEST(LinkRefine, TightSphereHoldsItsPartsAndIsTighter) {
    Rng rnd;
    for (int k = 0; k < 200; ++k) {
        SphereBuilder b;
        std::vector<std::pair<Vec3d, double>> parts;
        const int n = 1 + int(rnd() * 36);
        for (int p = 0; p < n; ++p) {
            // One draw per statement: the same parts whatever order a compiler evaluates
            // operands in; kept as the floats the builder gets.
            const Vec3d dir = rnd.Dir();
            const double dist = 3 * rnd();
            const double radius = rnd() < 0.3 ? 0.0 : rnd();
            const Vec3f pc(dir * dist);
            parts.push_back({Vec3d(pc), double(float(radius))});
            b.Add(pc, float(radius));
        }
        Vec3f c;
        float r;
        b.Get(Vec3f(0, 0, 0), 100.f, &c, &r);
        EXPECT_LE(r, 100.f);
        for (const auto& [pc, pr] : parts)
            EXPECT_LE(Length(pc - Vec3d(c)) + pr, double(r) * (1 + 1e-6)) << "k " << k;
    }
    // A half circle of radius 1 around the origin, its middle point at (0, 1, 0): the
    // sphere centred there needs radius sqrt(2), the tight one about 1.
    SphereBuilder arc;
    for (int a = 0; a <= 32; ++a)
        arc.Add(Vec3f(float(std::cos(a * std::numbers::pi / 32)), float(std::sin(a * std::numbers::pi / 32)), 0), 0);
    Vec3f c;
    float r;
    arc.Get(Vec3f(0, 1, 0), float(std::sqrt(2.0)), &c, &r);
    EXPECT_LT(r, 1.2f);
}

struct BoxRun {
    std::vector<double> e;  // n . E (colour 0) at 16 x 16 points of every chart
    SolveStats stats;
};

BoxRun SolveBox(double link_tolerance, bool block = false,
               int link_probes = SolveOptions{}.link_probes,
               bool split_probes = SolveOptions{}.split_probes,
               size_t link_defer_pairs = SolveOptions{}.link_defer_pairs,
               double link_size_error = SolverSettings{}.link_size_error) {
    testing::LitBox box(5, 32, block);
    SolveOptions opt;
    opt.settings.max_bounces = 8;
    opt.settings.link_size_error = link_size_error;
    opt.link_tolerance = link_tolerance;
    opt.link_probes = link_probes;
    opt.split_probes = split_probes;
    opt.link_defer_pairs = link_defer_pairs;
    Solver solver(box.scene, box.charts, box.vis, opt);
    solver.Run();
    BoxRun r;
    r.stats = solver.stats();
    for (size_t c = 0; c < box.charts.size(); ++c) {
        const Vec3f n = box.charts[c].geometry.At(0, 0, 0).normal;
        for (int j = 0; j < 16; ++j)
            for (int i = 0; i < 16; ++i) {
                float v[9];
                solver.fields()[c].EvalValue((i + 0.5) / 16, (j + 0.5) / 16, v);
                r.e.push_back(n.x * v[0] + n.y * v[1] + n.z * v[2]);
            }
    }
    return r;
}

uint64_t LinkRays(const SolveStats& s) {
    return s.rays_by_kind.size() > size_t(RayKind::kLink) ? s.rays_by_kind[size_t(RayKind::kLink)]
                                                          : 0;
}

// |got - ref| over the box's points as a share of ref's brightest point: its largest and
// mean, printed with both runs' link rays.
struct BoxDiff {
    double top = 0, worst = 0, mean = 0;
};
BoxDiff DiffToBrightest(const BoxRun& ref, const BoxRun& got) {
    EXPECT_EQ(ref.e.size(), got.e.size());
    BoxDiff d;
    for (double v : ref.e)
        d.top = std::max(d.top, v);
    EXPECT_GT(d.top, 0);
    const size_t n = std::min(ref.e.size(), got.e.size());
    double sum = 0;
    for (size_t k = 0; k < n && d.top > 0; ++k) {
        const double x = std::abs(got.e[k] - ref.e[k]) / d.top;
        d.worst = std::max(d.worst, x);
        sum += x;
    }
    d.mean = n ? sum / double(n) : 0;
    std::printf("link rays %llu -> %llu, difference / brightest max %.4f mean %.5f\n",
                (unsigned long long)LinkRays(ref.stats), (unsigned long long)LinkRays(got.stats),
                d.worst, d.mean);
    return d;
}

TEST(LinkRefine, LitBoxWithinToleranceWithFewerLinkRays) {
    const BoxRun ref = SolveBox(0), got = SolveBox(SolveOptions{}.link_tolerance);  // the default
    ASSERT_EQ(ref.e.size(), got.e.size());
    double worst = 0, sum = 0;
    size_t lit = 0;
    for (size_t k = 0; k < ref.e.size(); ++k) {
        if (ref.e[k] <= 0)
            continue;  // the ceiling's strip behind the light's plane
        ++lit;
        const double d = std::abs(got.e[k] - ref.e[k]) / ref.e[k];
        worst = std::max(worst, d);
        sum += d;
    }
    const double mean = sum / double(lit);
    std::printf("link rays %llu -> %llu, relative difference max %.4f mean %.5f\n",
                (unsigned long long)LinkRays(ref.stats), (unsigned long long)LinkRays(got.stats),
                worst, mean);
    EXPECT_GT(lit, ref.e.size() * 3 / 4);
    EXPECT_LT(worst, 0.005);
    EXPECT_LT(mean, 0.001);
    EXPECT_LT(LinkRays(got.stats), LinkRays(ref.stats) * 4 / 5);  // measured: 0.59
}

// SolverSettings::link_size_error: from the second batch on, a link whose spheres are apart
// stops where its point samples' share of the bound, K (size / gap)^2, is within the
// allowance. In the lit box with the table (its shadow and near walls), against the whole
// bound (K = 0): within the tolerance, with fewer link rays.
TEST(LinkRefine, SizeErrorStopsApartLinksSoonerWithinTolerance) {
    const double tol = SolveOptions{}.link_tolerance;
    const int probes = SolveOptions{}.link_probes;
    const bool split = SolveOptions{}.split_probes;
    const size_t defer = SolveOptions{}.link_defer_pairs;
    const BoxRun ref = SolveBox(tol, true, probes, split, defer, 0);
    const BoxRun got = SolveBox(tol, true, probes, split, defer, 0.08);
    const BoxDiff d = DiffToBrightest(ref, got);
    EXPECT_GT(d.worst, 0);  // the rule changed some links
    EXPECT_LT(d.worst, 0.01);
    EXPECT_LT(d.mean, 0.001);
    EXPECT_LT(LinkRays(got.stats), LinkRays(ref.stats));
}

// Link probes (Solver::Gatherer::TraceLink): with a table in the box, links are wholly
// visible, wholly hidden or partial; probing a subset of every link's pairs first (half of
// them for links of fewer than 16) keeps the answer of one ray per pair with fewer rays.
TEST(LinkRefine, ProbesKeepTheAnswerOfEveryPairWithFewerRays) {
    const double tol = SolveOptions{}.link_tolerance;
    const BoxRun ref = SolveBox(tol, true, 0), got = SolveBox(tol, true);
    const BoxDiff d = DiffToBrightest(ref, got);
    size_t dark = 0;
    for (double v : ref.e)
        dark += v < 0.2 * d.top ? 1 : 0;
    EXPECT_GT(dark, 0u);  // the table's shadow
    EXPECT_LT(d.worst, 0.01);
    EXPECT_LT(d.mean, 0.001);
    EXPECT_LT(LinkRays(got.stats), LinkRays(ref.stats) * 2 / 5);  // measured: 0.29
}

// Split probes (Solver::Gatherer::SplitVisibility): a link about to be split whose probes
// agree hands their answer to its whole subtree, which then traces no rays (visible) or is
// dropped (hidden). With the table's shadow in the box, against probes on the evaluated
// links alone.
TEST(LinkRefine, SplitProbesKeepTheShadowWithFewerRays) {
    const double tol = SolveOptions{}.link_tolerance;
    const int probes = SolveOptions{}.link_probes;
    const BoxRun ref = SolveBox(tol, true, probes, false), got = SolveBox(tol, true, probes, true);
    const BoxDiff d = DiffToBrightest(ref, got);
    EXPECT_LT(d.worst, 0.01);
    EXPECT_LT(d.mean, 0.001);
    EXPECT_LT(LinkRays(got.stats), LinkRays(ref.stats) / 2);  // measured: 0.38
}

// The gathers' deferred link rays (solver.cpp, Gatherer::Resolve): the same values, bit
// for bit, as tracing link by link (1 pair), with link probes and without, whatever the
// batch; it fails if a deferred link reads another link's answers.
TEST(LinkRefine, DeferredLinkRaysGiveTheBytesOfLinkByLink) {
    const double tol = SolveOptions{}.link_tolerance;
    for (int probes : {8, 0}) {
        const BoxRun one = SolveBox(tol, true, probes, SolveOptions{}.split_probes, 1);
        EXPECT_GT(LinkRays(one.stats), 0u);
        for (size_t defer : {size_t(37), SolveOptions{}.link_defer_pairs}) {
            const BoxRun many = SolveBox(tol, true, probes, SolveOptions{}.split_probes, defer);
            ASSERT_EQ(many.e.size(), one.e.size());
            EXPECT_EQ(std::memcmp(many.e.data(), one.e.data(), one.e.size() * sizeof(double)), 0)
                << "probes " << probes << ", " << defer << " pairs";
            EXPECT_EQ(LinkRays(many.stats), LinkRays(one.stats));
        }
    }
}

TEST(LinkRefine, BitIdenticalForAnyThreadCount) {
    // With SolverSettings::link_size_error off (the rule before session 18) and at its default.
    for (double size_error : {0.0, 0.08}) {
        auto run = [size_error](int threads) {
            ThreadLimit limit(threads);
            const SolveOptions o;
            return SolveBox(o.link_tolerance, false, o.link_probes, o.split_probes,
                            o.link_defer_pairs, size_error)
                .e;
        };
        const auto a = run(1), b = run(2);
        ASSERT_EQ(a.size(), b.size());
        EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(double)), 0)
            << "link_size_error " << size_error;
    }
}

}  // namespace
}  // namespace mebake::solve
