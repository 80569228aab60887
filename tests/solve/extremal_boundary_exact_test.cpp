// Exact extremal boundaries from EV events (seed 002, 4.1) and the penumbral estimate of
// section 5.4, on analytic scenes: the paper's Fig. 7 box (two rectangles, one square
// occluder), a tilted square under a triangle light, and the Cornell box's two blocks under
// four ceiling lights (McGuire's coordinates). Checks the exact classes against the closed
// form (Fig. 7) and against brute-force visibility of the light, the sampled pass of the
// solver against the exact classes, and prints the shape of the paper's Table 1 (time of
// the extremal boundary against the complete EV structure) and the estimate's errors.
#include "solve/extremal_boundary_exact.h"

#include "solve/basis.h"
#include "solve/direct.h"
#include "solve/extremal_boundary.h"
#include "solve/multi_emitter.h"
#include "solve/penumbra_estimate.h"
#include "solve/polygon_light.h"
#include "solve/visibility.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <tuple>

namespace mebake::solve {
namespace {

const ReceiverPlane kFloor{{0, 0, 0}, {1, 0, 0}, {0, 0, -1}};  // y = 0, lit side +y; t = -z

std::vector<Vec3d> Rect(double cx, double y, double cz, double h) {
    return {{cx - h, y, cz - h}, {cx + h, y, cz - h}, {cx + h, y, cz + h}, {cx - h, y, cz + h}};
}

ConvexOccluder Polygon(std::vector<Vec3d> v) {
    ConvexOccluder o;
    o.vertices = std::move(v);
    o.faces.push_back({});
    for (int k = 0; k < int(o.vertices.size()); ++k)
        o.faces[0].push_back(k);
    return o;
}

// A block standing on the floor: its top face's corners at height h.
ConvexOccluder Block(std::vector<Vec3d> top) {
    ConvexOccluder o;
    o.vertices = top;
    for (const auto& v : top)
        o.vertices.push_back({v.x, 0, v.z});
    o.faces = {{0, 1, 2, 3}, {4, 5, 6, 7}, {0, 1, 5, 4}, {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}};
    return o;
}

// A convex occluder as outward face planes (a single polygon: its plane and edges).
struct Planes {
    bool polygon;
    std::vector<std::pair<Vec3d, Vec3d>> faces;  // (point, outward normal)
    std::vector<Vec3d> loop;
};
Planes ToPlanes(const ConvexOccluder& o) {
    Planes p{o.faces.size() == 1, {}, o.vertices};
    Vec3d centre{};
    for (const auto& v : o.vertices)
        centre += v;
    centre = centre / double(o.vertices.size());
    for (const auto& f : o.faces) {
        std::vector<Vec3d> loop;
        for (int v : f)
            loop.push_back(o.vertices[size_t(v)]);
        Vec3d n = PolygonNormal(loop);
        if (Dot(n, loop[0] - centre) < 0)
            n = -n;
        p.faces.push_back({loop[0], n});
    }
    return p;
}

// Does the segment x -> l meet the convex occluder? (Cyrus-Beck against its face planes; a
// single polygon: the crossing of its plane inside it.)
bool Blocks(const Planes& o, const Vec3d& x, const Vec3d& l) {
    if (o.polygon) {
        const Vec3d n = o.faces[0].second, q = o.faces[0].first;
        const double a = Dot(n, x - q), b = Dot(n, l - q);
        if ((a > 0) == (b > 0))
            return false;
        const Vec3d p = x + (l - x) * (a / (a - b));
        int sign = 0;
        for (size_t k = 0; k < o.loop.size(); ++k) {
            const double c =
                Dot(Cross(o.loop[(k + 1) % o.loop.size()] - o.loop[k], p - o.loop[k]), n);
            const int sk = c > 0 ? 1 : -1;
            if (sign != 0 && sk != sign)
                return false;
            sign = sk;
        }
        return true;
    }
    double t0 = 0, t1 = 1;
    for (const auto& [q, n] : o.faces) {
        const double num = Dot(n, q - x), den = Dot(n, l - x);
        if (den == 0) {
            if (num < 0)
                return false;
            continue;
        }
        const double t = num / den;
        if (den < 0)
            t0 = std::max(t0, t);
        else
            t1 = std::min(t1, t);
        if (t0 > t1)
            return false;
    }
    return true;
}

// Brute force: the light sampled on a 24 x 24 grid per fan triangle (its vertices
// included); lit if no sample is hidden, umbra if all are.
ExtremalBoundaries::Class BruteClass(std::span<const Vec3d> light, std::span<const Planes> occ,
                                     const Vec3d& x) {
    int seen = 0, hidden = 0;
    const int g = 24;
    for (size_t t = 0; t + 2 < light.size(); ++t)
        for (int b = 0; b <= g; ++b)
            for (int a = 0; a + b <= g; ++a) {
                const Vec3d l = light[0] + (light[t + 1] - light[0]) * (a / double(g)) +
                                (light[t + 2] - light[0]) * (b / double(g));
                bool blocked = false;
                for (const auto& o : occ)
                    blocked = blocked || Blocks(o, x, l);
                (blocked ? hidden : seen)++;
            }
    return hidden == 0 ? ExtremalBoundaries::kLit
           : seen == 0 ? ExtremalBoundaries::kUmbra
                       : ExtremalBoundaries::kPenumbra;
}

// Exact class on the Fig. 7 floor (the test of multi_emitter_test.cpp, closed form).
ExtremalBoundaries::Class Fig7Class(double x, double z, double cx) {
    const double sx0 = -0.8 - x, sx1 = 0.8 - x, sz0 = -0.8 - z, sz1 = 0.8 - z;
    const double lx0 = cx - 0.5, lx1 = cx + 0.5, lz0 = -0.5, lz1 = 0.5;
    const double ox = std::min(sx1, lx1) - std::max(sx0, lx0);
    const double oz = std::min(sz1, lz1) - std::max(sz0, lz0);
    if (ox <= 0 || oz <= 0)
        return ExtremalBoundaries::kLit;
    if (sx0 <= lx0 && sx1 >= lx1 && sz0 <= lz0 && sz1 >= lz1)
        return ExtremalBoundaries::kUmbra;
    return ExtremalBoundaries::kPenumbra;
}

struct Analytic {
    const char* name;
    std::vector<std::vector<Vec3d>> lights;
    std::vector<ConvexOccluder> occluders;
    double x0, x1, z0, z1;  // the floor's extent
};

Analytic Fig7Scene() {
    return {"Fig. 7 box",
            {Rect(-0.6, 2, 0, 0.5), Rect(0.9, 2, 0, 0.5)},
            {Polygon(Rect(0, 1, 0, 0.4))},
            -3,
            3,
            -3,
            3};
}

Analytic TiltedScene() {
    // A square of side 0.8 turned 30 degrees about y and tilted 25 degrees about x, centred
    // at height 1, under a triangle light at height 2.2 (wound to face down).
    const double c = std::cos(0.5236), s = std::sin(0.5236), ct = std::cos(0.4363),
                 st = std::sin(0.4363);
    std::vector<Vec3d> sq;
    for (auto [a, b] : {std::pair{-0.4, -0.4}, {0.4, -0.4}, {0.4, 0.4}, {-0.4, 0.4}}) {
        const Vec3d p(a, b * st, b * ct);  // tilt about x
        sq.push_back({c * p.x + s * p.z, 1 + p.y, -s * p.x + c * p.z});
    }
    return {"tilted square",
            {{{-0.5, 2.2, -0.4}, {0.6, 2.2, -0.3}, {0.1, 2.2, 0.6}}},
            {Polygon(sq)},
            -3,
            3,
            -3,
            3};
}

Analytic CornellScene() {
    Analytic a{"Cornell box (2 blocks)", {}, {}, -1.01, 1.0, -1.04, 0.99};
    for (double x : {-0.45, 0.45})
        for (double z : {-0.45, 0.45})
            a.lights.push_back(Rect(x, 1.97, z, 0.12));
    a.occluders.push_back(
        Block({{0.53, 0.6, 0.75}, {0.70, 0.6, 0.17}, {0.13, 0.6, 0.00}, {-0.05, 0.6, 0.57}}));
    a.occluders.push_back(
        Block({{-0.53, 1.2, 0.09}, {0.04, 1.2, -0.09}, {-0.14, 1.2, -0.67}, {-0.71, 1.2, -0.49}}));
    return a;
}

TEST(ExactExtremalBoundary, Fig7MatchesTheClosedForm) {
    const Analytic sc = Fig7Scene();
    for (size_t l = 0; l < 2; ++l) {
        const ExactExtremalBoundary eb(sc.lights[l], sc.occluders, kFloor);
        const double cx = l == 0 ? -0.6 : 0.9;
        int wrong = 0, pen = 0, umbra = 0;
        const int n = 300;
        for (int b = 0; b < n; ++b)
            for (int a = 0; a < n; ++a) {
                const double x = -3 + 6 * (a + 0.5) / n, z = -3 + 6 * (b + 0.5) / n;
                const auto c = eb.Classify({x, -z});
                wrong += c != Fig7Class(x, z, cx);
                pen += c == ExtremalBoundaries::kPenumbra;
                umbra += c == ExtremalBoundaries::kUmbra;
            }
        EXPECT_EQ(wrong, 0) << "light " << l;
        EXPECT_GT(pen, 0);
        EXPECT_GT(umbra, 0);
        // Parallel squares: the shadow is a rectangle.
        EXPECT_EQ(eb.maximal(0).size(), 4u);
        EXPECT_EQ(eb.minimal(0).size(), 4u);
    }
}

// The maximal polygon from the separating EV wedges equals the hull of the projections.
TEST(ExactExtremalBoundary, SeparatingWedgesBoundTheSameShadow) {
    for (const Analytic& sc : {Fig7Scene(), TiltedScene(), CornellScene()}) {
        for (const auto& light : sc.lights) {
            const ExactExtremalBoundary eb(light, sc.occluders, kFloor);
            for (size_t k = 0; k < sc.occluders.size(); ++k) {
                size_t wedges = 0;
                const auto poly = SeparatingWedgeShadow(light, sc.occluders[k], kFloor, &wedges);
                EXPECT_GE(wedges, eb.maximal(k).size()) << sc.name;
                // Every corner of each lies on the other (within rounding).
                for (const auto* pair : {&poly, &eb.maximal(k)}) {
                    const auto& other = pair == &poly ? eb.maximal(k) : poly;
                    for (const Vec2d& p : *pair) {
                        double dist = 1e9;
                        for (size_t i = 0; i < other.size(); ++i) {
                            const Vec2d a = other[i], e = other[(i + 1) % other.size()] - a;
                            const double t = std::clamp(Dot(p - a, e) / Dot(e, e), 0.0, 1.0);
                            dist = std::min(dist, Length(p - (a + e * t)));
                        }
                        EXPECT_LT(dist, 1e-9) << sc.name;
                    }
                }
            }
        }
    }
}

// Tilted occluders and blocks: the exact classes against brute-force visibility of the
// light. A point the exact boundary calls lit sees every light sample, one it calls umbra
// sees none; brute force can call a penumbra point lit or umbra only where the hidden or
// visible part of the light falls between its samples (a sliver along the boundaries).
TEST(ExactExtremalBoundary, AgreesWithBruteForceVisibility) {
    for (const Analytic& sc : {TiltedScene(), CornellScene()}) {
        std::vector<Planes> planes;
        for (const auto& o : sc.occluders)
            planes.push_back(ToPlanes(o));
        for (const auto& light : sc.lights) {
            const ExactExtremalBoundary eb(light, sc.occluders, kFloor);
            int contradictions = 0, sliver = 0, points = 0, pen = 0;
            const int n = 60;
            for (int b = 0; b < n; ++b)
                for (int a = 0; a < n; ++a) {
                    const double x = sc.x0 + (sc.x1 - sc.x0) * (a + 0.5) / n;
                    const double z = sc.z0 + (sc.z1 - sc.z0) * (b + 0.5) / n;
                    const auto exact = eb.Classify({x, -z});
                    const auto brute = BruteClass(light, planes, {x, 1e-9, z});
                    ++points;
                    pen += exact == ExtremalBoundaries::kPenumbra;
                    if (exact == brute)
                        continue;
                    if (exact != ExtremalBoundaries::kPenumbra)
                        ++contradictions;  // lit or umbra exactly, yet brute force disagrees
                    else
                        ++sliver;
                }
            EXPECT_EQ(contradictions, 0) << sc.name;
            EXPECT_GT(pen, 0) << sc.name;
            EXPECT_LT(sliver, points / 50) << sc.name;
        }
    }
}

// The solver's sampled pass (3 x 3 samples per node, classification rays, levels 3-7) for
// one light against the exact classes, on the 6 x 6 floor: the area of each region class
// and the area of lit and umbra regions holding points (7 x 7 per region) of another exact
// class, all of it and the part that is lit in umbra or umbra in lit.
struct SampledCheck {
    double area[5] = {}, wrong = 0, gross = 0;
};
SampledCheck SampledAgainstExact(const Analytic& sc, size_t light) {
    Scene scene;
    PolygonLight pl;
    pl.vertices = sc.lights[light];
    pl.radiance = {1, 1, 1};
    scene.lights.push_back(pl);
    VisibilityScene vis;
    for (const auto& o : sc.occluders) {
        std::vector<float> xyz;
        std::vector<uint32_t> tris;
        for (const auto& v : o.vertices)
            xyz.insert(xyz.end(), {float(v.x), float(v.y), float(v.z)});
        for (const auto& f : o.faces)
            for (size_t k = 1; k + 1 < f.size(); ++k)
                tris.insert(tris.end(), {uint32_t(f[0]), uint32_t(f[k]), uint32_t(f[k + 1])});
        vis.AddTriangles(xyz, tris, "occluder");
    }
    vis.Commit();
    DirectLight direct(scene, SolverSettings{}, vis, 1e-5f, 8.5f);
    const ExactExtremalBoundary exact(sc.lights[light], sc.occluders, kFloor);
    const ExtremalBoundaries sampled(
        direct,
        [](float u, float v) {
            const Vec3f p(6 * u - 3, 0, 3 - 6 * v), n(0, 1, 0);
            return ReceiverPoint{p, n, p, n};
        },
        3, 7);
    SampledCheck c;
    for (const auto& r : sampled.regions(0)) {
        const double size = 1.0 / double(1u << r.level);
        c.area[r.cls] += size * size;
        if (r.cls == ExtremalBoundaries::kPenumbra)
            continue;
        for (int b = 0; b < 7; ++b)
            for (int a = 0; a < 7; ++a) {
                const double u = (r.i + (a + 0.5) / 7) * size, v = (r.j + (b + 0.5) / 7) * size;
                const auto e = exact.Classify({6 * u - 3, 6 * v - 3});
                if (e != r.cls)
                    c.wrong += size * size / 49;
                if (e != r.cls && e != ExtremalBoundaries::kPenumbra)
                    c.gross += size * size / 49;
            }
    }
    return c;
}

TEST(ExactExtremalBoundary, SampledPassAgainstTheExactReference) {
    // Fig. 7: the shadow is larger than the sampling step; the classes hold everywhere.
    const Analytic fig7 = Fig7Scene();
    for (size_t l = 0; l < 2; ++l) {
        const SampledCheck c = SampledAgainstExact(fig7, l);
        EXPECT_NEAR(c.area[2] + c.area[3] + c.area[4], 1.0, 1e-9);
        EXPECT_GT(c.area[2], 0.8) << "light " << l;
        EXPECT_GT(c.area[4], 0.0) << "light " << l;
        EXPECT_LT(c.wrong, 1e-4) << "light " << l;
    }
    // The tilted square under a triangle light.
    const SampledCheck c = SampledAgainstExact(TiltedScene(), 0);
    std::printf("sampled pass vs exact EV boundary (tilted square): lit %.4f, umbra %.4f, "
                "penumbra %.4f of the chart; penumbra inside lit or umbra regions %.2e, lit "
                "inside umbra or umbra inside lit %.2e\n",
                c.area[2], c.area[3], c.area[4], c.wrong - c.gross, c.gross);
    EXPECT_GT(c.area[3], 0.0);
    EXPECT_EQ(c.gross, 0.0);
    // The classification rays see the light's vertices and centre only: where the occluder
    // hides a sliver of the light between them the point is called lit (docs/method.md;
    // measured 1.3e-2 of the chart, a tenth of the penumbra).
    EXPECT_GT(c.wrong, 0.0);
    EXPECT_LT(c.wrong, 0.25 * c.area[4]);
}

// The shape of the paper's Table 1: time of the extremal boundary (maximal and minimal
// polygons from EV events) against the complete EV structure (every wedge traced and every
// crossing of the traces found), summed over the lights; thread CPU time, median of 21.
TEST(ExactExtremalBoundary, Table1BoundaryAgainstCompleteStructure) {
    for (const Analytic& sc : {Fig7Scene(), CornellScene()}) {
        auto time = [&](auto&& f) {  // thread CPU seconds per call
            std::vector<double> t;
            for (int r = 0; r < 21; ++r) {
                const double a = ThreadCpuSeconds();
                for (int k = 0; k < 200; ++k)
                    f();
                t.push_back((ThreadCpuSeconds() - a) / 200);
            }
            std::nth_element(t.begin(), t.begin() + 10, t.end());
            return t[10];
        };
        size_t wedges = 0, crossings = 0, boundary_edges = 0;
        for (const auto& l : sc.lights) {
            const DiscontinuityStructure d = CompleteDiscontinuities(l, sc.occluders, kFloor);
            wedges += d.wedges;
            crossings += d.crossings;
            const ExactExtremalBoundary eb(l, sc.occluders, kFloor);
            for (size_t k = 0; k < eb.occluder_count(); ++k)
                boundary_edges += eb.maximal(k).size() + eb.minimal(k).size();
        }
        const double t_boundary = time([&] {
            for (const auto& l : sc.lights)
                ExactExtremalBoundary eb(l, sc.occluders, kFloor);
        });
        const double t_complete = time([&] {
            for (const auto& l : sc.lights)
                CompleteDiscontinuities(l, sc.occluders, kFloor);
        });
        std::printf("Table 1 | %s | %zu lights, %zu occluders | extremal boundary %.1f CPU us (%zu "
                    "edges) | complete EV structure %.1f CPU us (%zu wedges, %zu crossings) | "
                    "complete / boundary %.2f\n",
                    sc.name, sc.lights.size(), sc.occluders.size(), 1e6 * t_boundary,
                    boundary_edges, 1e6 * t_complete, wedges, crossings, t_complete / t_boundary);
        EXPECT_GT(wedges, boundary_edges);
        EXPECT_GT(crossings, 0u);
    }
}

// Section 5.4's estimate against the exact backprojected value at penumbra points, relative
// to the unoccluded irradiance there; the straight line from 0 to the unoccluded value at
// the maximal boundary is the baseline it must beat.
TEST(PenumbraEstimate, HermiteAgainstTheExactValue) {
    const Vec3d up(0, 1, 0);
    for (const Analytic& sc : {Fig7Scene(), TiltedScene(), CornellScene()}) {
        std::vector<double> herr, lerr;
        int missing = 0;
        for (const auto& light : sc.lights) {
            const ExactExtremalBoundary eb(light, sc.occluders, kFloor);
            const int n = 120;
            for (int b = 0; b < n; ++b)
                for (int a = 0; a < n; ++a) {
                    const double x = sc.x0 + (sc.x1 - sc.x0) * (a + 0.5) / n;
                    const double z = sc.z0 + (sc.z1 - sc.z0) * (b + 0.5) / n;
                    const Vec2d st{x, -z};
                    // Penumbra of exactly one occluder (the estimate is per occluder).
                    size_t k = 0, in = 0;
                    for (size_t o = 0; o < eb.occluder_count(); ++o)
                        if (InsideConvex(eb.maximal(o), st))
                            k = o, ++in;
                    if (in != 1 || eb.Classify(st) != ExtremalBoundaries::kPenumbra)
                        continue;
                    const Vec3d p = kFloor.At(st);
                    const double unocc = IrradianceClipped(light, 1.0, p, up);
                    if (unocc <= 0)
                        continue;
                    const double exact = BackprojectedIrradiance(light, sc.occluders[k], p, up);
                    const PenumbraEstimate e =
                        EstimatePenumbra(eb, k, light, sc.occluders[k], kFloor, st);
                    if (!e.ok) {
                        ++missing;
                        continue;
                    }
                    herr.push_back(std::abs(e.hermite - exact) / unocc);
                    lerr.push_back(std::abs(e.linear - exact) / unocc);
                }
        }
        ASSERT_GT(herr.size(), 100u) << sc.name;
        auto stats = [](std::vector<double> v) {
            std::sort(v.begin(), v.end());
            double mean = 0;
            for (double x : v)
                mean += x / double(v.size());
            return std::array<double, 3>{mean, v[v.size() * 95 / 100], v.back()};
        };
        const auto h = stats(herr), l = stats(lerr);
        std::printf("Section 5.4 | %s | %zu penumbra points (%d without umbra) | Hermite mean "
                    "%.4f p95 %.4f max %.4f | linear mean %.4f p95 %.4f max %.4f (of the "
                    "unoccluded value)\n",
                    sc.name, herr.size(), missing, h[0], h[1], h[2], l[0], l[1], l[2]);
        EXPECT_LT(h[0], l[0]) << sc.name;
    }
}

// The estimate as the medium-quality values of the light-penumbra test (seed 002, 5.2): on
// the Fig. 7 floor, nodes of 1/16 to 1/64 of the side where light 0 is in penumbra somewhere,
// the combined light (light 0 at its estimate or its exact value, plus light 1 at
// `second` times, exact) at the 4 x 4 Gauss points, the biquadratic projection kept when it
// misses no point by more than the tolerance x the largest value (refine_direct.cpp's
// test), at the solver's tolerance 0.02 and at 0.002. Counts the nodes the estimate keeps though
// the exact values would split them.
TEST(PenumbraEstimate, AsTheLightPenumbraTestsMediumValues) {
    const Analytic sc = Fig7Scene();
    const Vec3d up(0, 1, 0);
    const ExactExtremalBoundary eb(sc.lights[0], sc.occluders, kFloor);
    for (auto [second, n, tol] : {std::tuple{1.0, 8, 0.02f},
                                  {1.0, 16, 0.002f},
                                  {1.0, 32, 0.002f},
                                  {8.0, 8, 0.02f},
                                  {8.0, 16, 0.002f},
                                  {8.0, 32, 0.002f}}) {
        int nodes = 0, agree = 0, false_keep = 0, false_split = 0, kept = 0;
        const int g = 4;
        const float tolerance = tol;  // a lambda may not capture a structured binding (clang 14)
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) {
                float exact[g * g], est[g * g];
                bool pen = false;
                for (int p = 0; p < g * g; ++p) {
                    double s, t, w;
                    GaussPoint2D(g, p, &s, &t, &w);
                    const Vec2d st{-3 + 6 * (i + s) / n, -3 + 6 * (j + t) / n};
                    const Vec3d x = kFloor.At(st);
                    const double other = second * IrradianceClipped(sc.lights[1], 1.0, x, up);
                    const auto c = eb.Classify(st);
                    const double e0 = BackprojectedIrradiance(sc.lights[0], sc.occluders[0], x, up);
                    double v0 = e0;
                    if (c == ExtremalBoundaries::kPenumbra) {
                        pen = true;
                        v0 = EstimatePenumbra(eb, 0, sc.lights[0], sc.occluders[0], kFloor, st)
                                 .hermite;
                    }
                    exact[p] = float(e0 + other);
                    est[p] = float(v0 + other);
                }
                if (!pen)
                    continue;
                ++nodes;
                auto keep = [&](const float* v) {
                    float coeffs[9], peak = 0;
                    ProjectGauss(2, g, v, 1, coeffs);
                    for (int p = 0; p < g * g; ++p)
                        peak = std::max(peak, std::abs(v[p]));
                    return GaussResidualMax(2, g, coeffs, 1, v) <= tolerance * peak;
                };
                const bool ke = keep(exact), ks = keep(est);
                agree += ke == ks;
                kept += ke;
                false_keep += ks && !ke;
                false_split += !ks && ke;
            }
        std::printf("Section 5.4 as medium values | Fig. 7, second light x%g, nodes 1/%d, "
                    "tolerance %g | %d penumbra nodes, %d kept by exact values: decision as with "
                    "exact values %d, kept wrongly %d, split needlessly %d\n",
                    second, n, double(tol), nodes, kept, agree, false_keep, false_split);
        EXPECT_GT(nodes, 10);
        // Where the second light dominates, the estimate never keeps a node the exact values
        // would split (with equal lights at 0.002 it does: not good enough there).
        if (second > 1) {
            EXPECT_EQ(false_keep, 0);
        }
    }
}

}  // namespace
}  // namespace mebake::solve
