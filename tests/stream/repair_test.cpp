#include "stream/repair.h"

#include "core/error.h"
#include "stream/hole_fill.h"
#include "stream/topology.h"

#include "scan_mesh.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <optional>
#include <string>

namespace mebake::stream {
namespace {

using Tri = std::array<uint32_t, 3>;

TriMesh Make(std::vector<Vec3f> positions, std::vector<Tri> triangles) {
    TriMesh m;
    m.position = std::move(positions);
    m.triangles = std::move(triangles);
    for (size_t v = 0; v < m.position.size(); ++v)
        m.vertex_id.push_back(100 + v);
    for (size_t f = 0; f < m.triangles.size(); ++f) {
        m.face_id.push_back(1000 + f);
        m.material.push_back(uint32_t(f % 3));
    }
    return m;
}

// (n+1) x (n+1) vertices on the unit square, 2 n^2 triangles, counter-clockwise seen from +z.
TriMesh Grid(int n) {
    std::vector<Vec3f> p;
    std::vector<Tri> t;
    for (int j = 0; j <= n; ++j)
        for (int i = 0; i <= n; ++i)
            p.push_back({float(i) / n, float(j) / n, 0.f});
    auto id = [&](int i, int j) {
        return uint32_t(j * (n + 1) + i);
    };
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            t.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
            t.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
        }
    return Make(p, t);
}

// Closed UV sphere, outward orientation.
TriMesh Sphere(int stacks, int slices) {
    std::vector<Vec3f> p{{0, 0, 1}};
    for (int s = 1; s < stacks; ++s) {
        const double th = M_PI * s / stacks;
        for (int k = 0; k < slices; ++k) {
            const double ph = 2 * M_PI * k / slices;
            p.push_back({float(std::sin(th) * std::cos(ph)), float(std::sin(th) * std::sin(ph)),
                         float(std::cos(th))});
        }
    }
    p.push_back({0, 0, -1});
    const uint32_t south = uint32_t(p.size() - 1);
    auto id = [&](int s, int k) {
        return uint32_t(1 + (s - 1) * slices + (k % slices));
    };
    std::vector<Tri> t;
    for (int k = 0; k < slices; ++k)
        t.push_back({0, id(1, k), id(1, k + 1)});
    for (int s = 1; s + 1 < stacks; ++s)
        for (int k = 0; k < slices; ++k) {
            t.push_back({id(s, k), id(s + 1, k), id(s + 1, k + 1)});
            t.push_back({id(s, k), id(s + 1, k + 1), id(s, k + 1)});
        }
    for (int k = 0; k < slices; ++k)
        t.push_back({id(stacks - 1, k), south, id(stacks - 1, k + 1)});
    return Make(p, t);
}

// Removes the faces around vertex v: makes a hole whose border is v's link.
void Puncture(TriMesh& m, uint32_t v) {
    TriMesh out = m;
    out.triangles.clear();
    out.face_id.clear();
    out.material.clear();
    for (size_t f = 0; f < m.triangles.size(); ++f) {
        const Tri& t = m.triangles[f];
        if (t[0] == v || t[1] == v || t[2] == v)
            continue;
        out.triangles.push_back(t);
        out.face_id.push_back(m.face_id[f]);
        out.material.push_back(m.material[f]);
    }
    m = out;
}

RepairReport DoRepair(TriMesh& m, const RepairOptions& o = {}, std::vector<uint8_t> cut = {}) {
    return Repair(m, cut, o);
}

void ExpectOrientedManifold(const TriMesh& m) {
    const TopologyReport t = AnalyzeTopology(m);
    EXPECT_EQ(t.nonmanifold_edges, 0u);
    EXPECT_EQ(t.nonmanifold_vertices, 0u);
    EXPECT_EQ(t.inconsistent_edges, 0u);
    EXPECT_EQ(t.degenerate_faces, 0u);
}

TEST(Repair, CleanMeshIsUnchanged) {
    TriMesh m = Sphere(8, 12);
    const TriMesh before = m;
    const RepairReport r = DoRepair(m);
    EXPECT_EQ(m.position, before.position);
    EXPECT_EQ(m.triangles, before.triangles);
    EXPECT_EQ(m.face_id, before.face_id);
    EXPECT_EQ(r.orientation_flips, 0u);
    EXPECT_EQ(r.boundary_loops, 0u);
    EXPECT_EQ(AnalyzeTopology(m).euler, 2);
}

TEST(Repair, WeldsExactDuplicatesKeepingSmallestGlobalId) {
    // Two triangles sharing an edge, each with its own copies of the shared vertices.
    TriMesh m = Make({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}},
                     {{0, 1, 2}, {3, 4, 5}});
    m.vertex_id = {10, 21, 32, 11, 40, 12};  // the copies 3 and 5 have the smaller ids
    const RepairReport r = DoRepair(m);
    EXPECT_EQ(r.welded_vertices, 2u);
    ASSERT_EQ(m.vertex_count(), 4u);
    EXPECT_EQ(m.vertex_id, (std::vector<uint64_t>{10, 11, 40, 12}));
    const TopologyReport t = AnalyzeTopology(m);
    EXPECT_EQ(t.edges, 5u);
    EXPECT_EQ(t.boundary_loops, 1u);
    EXPECT_EQ(t.euler, 1);
}

TEST(Repair, WeldsWithinEpsilonOnly) {
    const std::vector<Vec3f> p{{0, 0, 0},     {1, 0, 0}, {0, 1, 0},
                               {1, 1e-6f, 0}, {1, 1, 0}, {0, 1, 2e-6f}};
    TriMesh exact = Make(p, {{0, 1, 2}, {3, 4, 5}});
    EXPECT_EQ(DoRepair(exact).welded_vertices, 0u);
    EXPECT_EQ(exact.vertex_count(), 6u);

    TriMesh near = Make(p, {{0, 1, 2}, {3, 4, 5}});
    RepairOptions o;
    o.weld_epsilon = 1e-5;
    EXPECT_EQ(DoRepair(near, o).welded_vertices, 2u);
    EXPECT_EQ(near.vertex_count(), 4u);
    EXPECT_EQ(AnalyzeTopology(near).edges, 5u);
}

TEST(Repair, DropsDegenerateAndZeroAreaTriangles) {
    TriMesh m = Make({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {2, 0, 0}, {0, 0, 0}},
                     {{0, 1, 2}, {0, 0, 1}, {0, 1, 3}, {4, 1, 2}});
    const RepairReport r = DoRepair(m);
    // {4,1,2} welds onto {0,1,2}: a duplicate. {0,0,1} repeats an index. {0,1,3} is flat.
    EXPECT_EQ(r.degenerate_triangles, 1u);
    EXPECT_EQ(r.zero_area_triangles, 1u);
    EXPECT_EQ(r.duplicate_triangles, 1u);
    ASSERT_EQ(m.triangle_count(), 1u);
    EXPECT_EQ(m.face_id[0], 1000u);
    EXPECT_EQ(m.vertex_count(), 3u);  // vertex 3 is no longer used
    EXPECT_EQ(r.unreferenced_vertices, 1u);
}

TEST(Repair, DropsDuplicateTrianglesInEitherOrientation) {
    TriMesh m = Make({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}},
                     {{0, 1, 2}, {1, 3, 2}, {2, 1, 0}, {1, 2, 0}, {3, 2, 1}});
    const RepairReport r = DoRepair(m);
    EXPECT_EQ(r.duplicate_triangles, 3u);
    EXPECT_EQ(m.triangles, (std::vector<Tri>{{0, 1, 2}, {1, 3, 2}}));
    EXPECT_EQ(m.face_id, (std::vector<uint64_t>{1000, 1001}));
}

TEST(Repair, DropsInvalidTriangles) {
    TriMesh m = Make({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {NAN, 0, 0}, {1, 1, 0}},
                     {{0, 1, 2}, {1, 3, 2}, {1, 4, 7}, {1, 4, 2}});
    const RepairReport r = DoRepair(m);
    EXPECT_EQ(r.invalid_triangles, 2u);
    EXPECT_EQ(m.triangle_count(), 2u);
    EXPECT_EQ(r.unreferenced_vertices, 1u);
    ExpectOrientedManifold(m);
}

TEST(Repair, SplitsBowTieVertex) {
    // Two triangles touching at vertex 0 only.
    TriMesh m =
        Make({{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {-1, 0, 0}, {-1, -1, 0}}, {{0, 1, 2}, {0, 3, 4}});
    EXPECT_EQ(AnalyzeTopology(m).nonmanifold_vertices, 1u);
    const RepairReport r = DoRepair(m);
    EXPECT_EQ(r.split_vertices, 1u);
    ASSERT_EQ(m.vertex_count(), 6u);
    EXPECT_EQ(m.vertex_id[5], m.vertex_id[0]);  // the copy keeps the global id
    EXPECT_EQ(m.position[5], m.position[0]);
    ExpectOrientedManifold(m);
    EXPECT_EQ(AnalyzeTopology(m).components, 2u);
    EXPECT_EQ(r.holes_filled, 0u);  // lone triangles are never closed into pillows

    TriMesh lone = Make({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, 1, 2}});
    RepairOptions o;
    o.max_hole_relative_diameter = 100;
    const RepairReport rl = DoRepair(lone, o);
    EXPECT_EQ(rl.holes_unfillable, 1u);
    EXPECT_EQ(lone.triangle_count(), 1u);
}

TEST(Repair, SplitsTwoConesTouchingAtTheirApex) {
    // Two closed fans (no boundary at the apex) sharing vertex 0: an hourglass.
    std::vector<Vec3f> p{{0, 0, 0}};
    std::vector<Tri> t;
    for (int side = 0; side < 2; ++side) {
        const float z = side ? -1.f : 1.f;
        const uint32_t base = uint32_t(p.size());
        for (int k = 0; k < 5; ++k)
            p.push_back({float(std::cos(2 * M_PI * k / 5)), float(std::sin(2 * M_PI * k / 5)), z});
        for (uint32_t k = 0; k < 5; ++k)
            t.push_back({0, base + k, base + (k + 1) % 5});
    }
    TriMesh m = Make(p, t);
    RepairOptions o;
    o.fill_holes = false;
    const RepairReport r = DoRepair(m, o);
    EXPECT_EQ(r.split_vertices, 1u);
    ExpectOrientedManifold(m);
    EXPECT_EQ(AnalyzeTopology(m).boundary_loops, 2u);
}

TEST(Repair, SplitsEdgeWithThreeFaces) {
    // A sheet of two triangles on edge (0,1) and a fin on the same edge.
    TriMesh m = Make({{0, 0, 0}, {1, 0, 0}, {0.5f, 1, 0}, {0.5f, -1, 0}, {0.5f, 0, 1}},
                     {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}});
    EXPECT_EQ(AnalyzeTopology(m).nonmanifold_edges, 1u);
    const RepairReport r = DoRepair(m);
    EXPECT_EQ(r.nonmanifold_edges, 1u);
    EXPECT_EQ(m.triangle_count(), 3u);
    ExpectOrientedManifold(m);
    const TopologyReport t = AnalyzeTopology(m);
    EXPECT_EQ(t.components, 2u);  // the fin got its own copies of 0 and 1
    EXPECT_EQ(t.boundary_loops, 2u);
    EXPECT_EQ(r.split_vertices, 2u);
}

TEST(Repair, SplitsEdgeWithFourFacesIntoTwoSheets) {
    // Two sheets crossing along edge (0,1).
    TriMesh m =
        Make({{0, 0, 0}, {1, 0, 0}, {0.5f, 1, 0}, {0.5f, -1, 0}, {0.5f, 0, 1}, {0.5f, 0, -1}},
             {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}, {1, 0, 5}});
    DoRepair(m);
    ExpectOrientedManifold(m);
    EXPECT_EQ(AnalyzeTopology(m).components, 2u);
    EXPECT_EQ(AnalyzeTopology(m).edges, 10u);
}

TEST(Repair, OrientsEachComponentConsistently) {
    TriMesh m = Grid(6);
    const TriMesh reference = m;
    for (size_t f : {3u, 10u, 11u, 40u})
        std::swap(m.triangles[f][1], m.triangles[f][2]);
    EXPECT_EQ(AnalyzeTopology(m).inconsistent_edges, 8u);
    const RepairReport r = DoRepair(m);
    EXPECT_EQ(r.orientation_flips, 4u);  // the minority is flipped back
    EXPECT_EQ(r.orientation_cuts, 0u);
    ExpectOrientedManifold(m);
    for (size_t f = 0; f < m.triangle_count(); ++f) {
        // Same orientation as the reference: the normal points to +z.
        const Vec3f a = m.position[m.triangles[f][0]], b = m.position[m.triangles[f][1]],
                    c = m.position[m.triangles[f][2]];
        EXPECT_GT(Cross(b - a, c - a).z, 0.f) << f;
    }
    EXPECT_EQ(m.triangles.size(), reference.triangles.size());
}

TEST(Repair, CutsMoebiusBandInsteadOfCrashing) {
    const int n = 24;
    std::vector<Vec3f> p;
    for (int i = 0; i < n; ++i) {
        const double u = 2 * M_PI * i / n;
        for (int s = 0; s < 2; ++s) {
            const double w = s ? 0.3 : -0.3;
            p.push_back({float((1 + w * std::cos(u / 2)) * std::cos(u)),
                         float((1 + w * std::cos(u / 2)) * std::sin(u)),
                         float(w * std::sin(u / 2))});
        }
    }
    std::vector<Tri> t;
    for (int i = 0; i < n; ++i) {
        const uint32_t a0 = 2 * i, a1 = 2 * i + 1;
        // The last strip glues with a half twist: bottom meets top.
        const uint32_t b0 = i + 1 < n ? 2 * (i + 1) : 1, b1 = i + 1 < n ? 2 * (i + 1) + 1 : 0;
        t.push_back({a0, b0, b1});
        t.push_back({a0, b1, a1});
    }
    TriMesh m = Make(p, t);
    EXPECT_EQ(AnalyzeTopology(m).inconsistent_edges, 1u);  // the twist
    RepairOptions o;
    o.fill_holes = false;
    const RepairReport r = DoRepair(m, o);
    EXPECT_EQ(r.orientation_cuts, 1u);
    EXPECT_EQ(m.triangle_count(), size_t(2 * n));
    ExpectOrientedManifold(m);
    // Cut open along one edge, the band is a disc.
    const TopologyReport topo = AnalyzeTopology(m);
    EXPECT_EQ(topo.boundary_loops, 1u);
    EXPECT_EQ(topo.euler, 1);
    EXPECT_EQ(topo.components, 1u);
}

TEST(Repair, FillsSmallHoleWithoutNewVertices) {
    TriMesh m = Sphere(24, 32);
    const size_t nf = m.triangle_count();
    Puncture(m, 1 + 11 * 32 + 3);  // a vertex of ring 12: its link has 6 edges
    const size_t removed = nf - m.triangle_count();
    const RepairReport r = DoRepair(m);
    EXPECT_EQ(r.boundary_loops, 1u);
    EXPECT_EQ(r.holes_filled, 1u);
    EXPECT_EQ(r.hole_triangles, 4u);  // a hexagon: n - 2 triangles
    EXPECT_EQ(r.output_boundary_loops, 0u);
    EXPECT_EQ(removed, 6u);
    EXPECT_EQ(m.vertex_count(), Sphere(24, 32).vertex_count() - 1);  // no new vertex
    EXPECT_EQ(m.triangle_count(), nf - 2);
    for (size_t f = nf - removed; f < m.triangle_count(); ++f)
        EXPECT_EQ(m.face_id[f], kNoId);
    ExpectOrientedManifold(m);
    const TopologyReport t = AnalyzeTopology(m);
    EXPECT_EQ(t.boundary_loops, 0u);
    EXPECT_EQ(t.euler, 2);
}

TEST(Repair, DoesNotFillHoleOnBrickCut) {
    TriMesh m = Sphere(24, 32);
    Puncture(m, 1 + 11 * 32 + 3);
    std::vector<uint8_t> cut(m.vertex_count(), 0);
    cut[1 + 10 * 32 + 3] = 1;  // a vertex of the hole's border
    std::vector<uint8_t> far_cut(m.vertex_count(), 0);
    far_cut[0] = 1;  // the north pole: not on the border

    TriMesh a = m;
    const RepairReport ra = DoRepair(a, {}, cut);
    EXPECT_EQ(ra.holes_on_cut, 1u);
    EXPECT_EQ(ra.holes_filled, 0u);
    EXPECT_EQ(AnalyzeTopology(a).boundary_loops, 1u);
    EXPECT_EQ(ra.vertex_on_cut.size(), a.vertex_count());

    TriMesh b = m;
    const RepairReport rb = DoRepair(b, {}, far_cut);
    EXPECT_EQ(rb.holes_filled, 1u);
    EXPECT_EQ(rb.vertex_on_cut[0], 1);
}

TEST(Repair, DoesNotFillHoleLargerThanLimit) {
    TriMesh m = Sphere(24, 32);
    Puncture(m, 1 + 11 * 32 + 3);
    RepairOptions o;
    o.max_hole_edges = 5;
    TriMesh a = m;
    const RepairReport r = DoRepair(a, o);
    EXPECT_EQ(r.holes_too_large, 1u);
    EXPECT_EQ(r.holes_filled, 0u);

    o.max_hole_edges = 128;
    o.max_hole_relative_diameter = 0.05;  // the hole spans ~0.3 of a 3.5 diagonal
    TriMesh b = m;
    EXPECT_EQ(DoRepair(b, o).holes_too_large, 1u);
}

TEST(Repair, DoesNotCloseAnOpenPatch) {
    TriMesh m = Grid(4);  // one border loop spanning the whole component
    const RepairReport r = DoRepair(m);
    EXPECT_EQ(r.boundary_loops, 1u);
    EXPECT_EQ(r.holes_too_large, 1u);
    EXPECT_EQ(m.triangle_count(), 32u);
}

TEST(Repair, FillsBothHolesOfATube) {
    // An open cylinder: two small border loops relative to its length.
    const int slices = 8, rings = 20;
    std::vector<Vec3f> p;
    std::vector<Tri> t;
    for (int r = 0; r <= rings; ++r)
        for (int k = 0; k < slices; ++k)
            p.push_back({float(0.2 * std::cos(2 * M_PI * k / slices)),
                         float(0.2 * std::sin(2 * M_PI * k / slices)), float(r) / 4});
    auto id = [&](int r, int k) {
        return uint32_t(r * slices + k % slices);
    };
    for (int r = 0; r < rings; ++r)
        for (int k = 0; k < slices; ++k) {
            t.push_back({id(r, k), id(r, k + 1), id(r + 1, k + 1)});
            t.push_back({id(r, k), id(r + 1, k + 1), id(r + 1, k)});
        }
    TriMesh m = Make(p, t);
    const RepairReport r = DoRepair(m);
    EXPECT_EQ(r.holes_filled, 2u);
    EXPECT_EQ(r.hole_triangles, 12u);
    ExpectOrientedManifold(m);
    EXPECT_EQ(AnalyzeTopology(m).euler, 2);
}

TEST(HoleFill, CutsTheSharpestEarFirstAndTilesAConvexPolygon) {
    // A regular octagon (convex, planar): the triangles must tile it exactly.
    std::vector<Vec3d> loop;
    for (int k = 0; k < 8; ++k)
        loop.push_back({std::cos(2 * M_PI * k / 8), std::sin(2 * M_PI * k / 8), 0});
    std::vector<Tri> tris;
    ASSERT_TRUE(TriangulateHole(
        loop, [](uint32_t, uint32_t) { return true; }, 1e-10, &tris));
    ASSERT_EQ(tris.size(), 6u);
    double area = 0;
    for (const Tri& t : tris) {
        const double z = Cross(loop[t[1]] - loop[t[0]], loop[t[2]] - loop[t[0]]).z;
        EXPECT_GT(z, 0);  // oriented like the loop
        area += z / 2;
    }
    EXPECT_NEAR(area, 2 * std::sqrt(2.0), 1e-12);

    // A square with a spike at vertex 2: the spike's ear has the largest
    // arc / chord ratio and must be a triangle of the result.
    std::vector<Vec3d> spike{{0, 0, 0}, {1, 0, 0}, {1.05, 3, 0}, {1.1, 0, 0},
                             {2, 0, 0}, {2, 1, 0}, {0, 1, 0}};
    tris.clear();
    ASSERT_TRUE(TriangulateHole(
        spike, [](uint32_t, uint32_t) { return true; }, 1e-10, &tris));
    bool found = false;
    for (const Tri& t : tris)
        found |= t == Tri{1, 2, 3} || t == Tri{2, 3, 1} || t == Tri{3, 1, 2};
    EXPECT_TRUE(found);
}

TEST(HoleFill, RespectsExistingEdges) {
    std::vector<Vec3d> square{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
    std::vector<Tri> tris;
    // Forbid the diagonal (0,2): the only other one is (1,3).
    ASSERT_TRUE(TriangulateHole(
        square,
        [](uint32_t a, uint32_t b) { return !(std::min(a, b) == 0 && std::max(a, b) == 2); }, 1e-10,
        &tris));
    ASSERT_EQ(tris.size(), 2u);
    for (const Tri& t : tris) {
        const bool has0 = t[0] == 0 || t[1] == 0 || t[2] == 0;
        const bool has2 = t[0] == 2 || t[1] == 2 || t[2] == 2;
        EXPECT_FALSE(has0 && has2);
    }
    tris.clear();
    EXPECT_FALSE(TriangulateHole(
        square, [](uint32_t, uint32_t) { return false; }, 1e-10, &tris));
    EXPECT_TRUE(tris.empty());
    // Collinear: nothing valid.
    std::vector<Vec3d> flat{{0, 0, 0}, {1, 0, 0}, {2, 0, 0}};
    EXPECT_FALSE(TriangulateHole(
        flat, [](uint32_t, uint32_t) { return true; }, 1e-10, &tris));
}

TEST(Repair, RejectsBadOptions) {
    TriMesh m = Grid(2);
    RepairOptions o;
    o.weld_epsilon = -1;
    EXPECT_THROW(DoRepair(m, o), Error);
    o = {};
    o.max_hole_edges = 100000;
    EXPECT_THROW(DoRepair(m, o), Error);
}

TEST(Repair, IsDeterministic) {
    // A messy soup: two spheres overlapping in index space with flips and duplicates.
    TriMesh m = Sphere(20, 28);
    const size_t n = m.triangle_count();
    for (size_t f = 0; f < n; f += 7)
        std::swap(m.triangles[f][0], m.triangles[f][1]);
    for (size_t f = 0; f < n; f += 11) {
        m.triangles.push_back(m.triangles[f]);
        m.face_id.push_back(5000 + f);
        m.material.push_back(0);
    }
    Puncture(m, 40);
    TriMesh a = m, b = m;
    const RepairReport ra = DoRepair(a), rb = DoRepair(b);
    EXPECT_EQ(a.triangles, b.triangles);
    EXPECT_EQ(a.vertex_id, b.vertex_id);
    EXPECT_EQ(ra.orientation_flips, rb.orientation_flips);
    EXPECT_GT(ra.duplicate_triangles, 0u);
    ExpectOrientedManifold(a);
    EXPECT_EQ(AnalyzeTopology(a).euler, 2);
}

TEST(Repair, RandomSoupsBecomeOrientedManifolds) {
    // Garbage in: few vertices, many random triangles, so edges carry many faces and
    // vertices many fans, with random orientations, repeats and flat triangles.
    uint64_t state = 12345;
    auto next = [&]() {
        state = state * 6364136223846793005ull + 1442695040888963407ull;
        return uint32_t(state >> 33);
    };
    for (int trial = 0; trial < 300; ++trial) {
        const uint32_t nv = 4 + next() % 40, nf = 1 + next() % 300;
        std::vector<Vec3f> p;
        for (uint32_t v = 0; v < nv; ++v)
            p.push_back({float(next() % 7), float(next() % 7), float(next() % 3)});
        std::vector<Tri> t;
        for (uint32_t f = 0; f < nf; ++f)
            t.push_back({next() % nv, next() % nv, next() % nv});
        TriMesh m = Make(p, t);
        const RepairReport r = DoRepair(m);
        ExpectOrientedManifold(m);
        EXPECT_EQ(r.isolated_triangles, 0u) << "trial " << trial;
        EXPECT_EQ(r.output_triangles, m.triangle_count());
        EXPECT_EQ(AnalyzeTopology(m).boundary_loops, r.output_boundary_loops) << "trial " << trial;
        for (size_t f = 0; f < m.triangle_count(); ++f) {
            if (m.face_id[f] != kNoId) {
                EXPECT_LT(m.face_id[f], 1000u + nf);
            }
        }
    }
}

TEST(Repair, EmptyMesh) {
    TriMesh m;
    const RepairReport r = DoRepair(m);
    EXPECT_EQ(r.output_triangles, 0u);
    EXPECT_EQ(m.vertex_count(), 0u);
}

// Real data ------------------------------------------------------------------------------

using testing::LoadScan;

std::string Scan(const char* name) {
    return std::string(MEBAKE_SHARED_DATA) + "/scans/" + name;
}

TEST(RepairData, BunnyHolesAreFilled) {
    auto loaded = LoadScan(Scan("bun_zipper.ply"));
    if (!loaded)
        GTEST_SKIP() << "no " << Scan("bun_zipper.ply");
    TriMesh m = *loaded;
    const TopologyReport before = AnalyzeTopology(m);
    EXPECT_EQ(before.boundary_edges, 223u);
    EXPECT_EQ(before.boundary_loops, 5u);
    EXPECT_EQ(before.nonmanifold_edges, 0u);

    const auto t0 = std::chrono::steady_clock::now();
    const RepairReport r = DoRepair(m);
    const double ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    std::printf("bun_zipper repair: %.1f ms, %zu -> %zu triangles, %zu holes filled\n", ms,
                r.input_triangles, r.output_triangles, r.holes_filled);
    EXPECT_EQ(r.unreferenced_vertices, 1113u);
    EXPECT_EQ(r.boundary_loops, 5u);
    EXPECT_EQ(r.holes_filled, 5u);
    EXPECT_EQ(r.hole_triangles, 223u - 2 * 5);
    EXPECT_EQ(r.isolated_triangles, 0u);
    EXPECT_EQ(r.split_vertices, 0u);
    ExpectOrientedManifold(m);
    const TopologyReport after = AnalyzeTopology(m);
    EXPECT_EQ(after.boundary_loops, 0u);
    EXPECT_EQ(after.components, 1u);
    EXPECT_EQ(after.vertices, 35947u - 1113u);  // no vertex added

    // The same with the base marked as a brick cut: nothing is filled.
    TriMesh cut_mesh = *loaded;
    std::vector<uint8_t> cut(cut_mesh.vertex_count(), 0);
    for (size_t v = 0; v < cut.size(); ++v)
        cut[v] = cut_mesh.position[v].y < 0.04f;
    const RepairReport rc = DoRepair(cut_mesh, {}, cut);
    EXPECT_EQ(rc.holes_filled + rc.holes_on_cut, 5u);
    EXPECT_GE(rc.holes_on_cut, 1u);
}

TEST(RepairData, LowResolutionBunniesBecomeManifold) {
    for (const char* name : {"bun_zipper_res2.ply", "bun_zipper_res3.ply", "bun_zipper_res4.ply"}) {
        auto loaded = LoadScan(Scan(name));
        if (!loaded)
            GTEST_SKIP() << "no " << Scan(name);
        TriMesh m = *loaded;
        const TopologyReport before = AnalyzeTopology(m);
        EXPECT_GT(before.nonmanifold_edges, 0u) << name;
        const RepairReport r = DoRepair(m);
        std::printf("%s: dup %zu nm-edges %zu flips %zu cuts %zu splits %zu detached %zu "
                    "loops %zu filled %zu large %zu seams %zu unfillable %zu\n",
                    name, r.duplicate_triangles, r.nonmanifold_edges, r.orientation_flips,
                    r.orientation_cuts, r.split_vertices, r.detached_corners, r.boundary_loops,
                    r.holes_filled, r.holes_too_large, r.seams, r.holes_unfillable);
        ExpectOrientedManifold(m);
        EXPECT_EQ(r.isolated_triangles, 0u) << name;
        EXPECT_GT(r.duplicate_triangles, 0u) << name;
        TriMesh again = *loaded;
        DoRepair(again);
        EXPECT_EQ(again.triangles, m.triangles) << name;
    }
}

}  // namespace
}  // namespace mebake::stream
