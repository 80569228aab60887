// Brick repair (Master-Element paper, seeds/000, section 3.1 step 1: "scanned meshes are
// often punctured by tiny holes ... a simple method to clean the geometry").
//
//  1 weld      sort by position (exact), or single-linkage clustering on an epsilon grid;
//              the member with the smallest global vertex_id represents its cluster.
//  2 drop      triangles with an invalid index or non-finite vertex, a repeated index after
//              welding, zero area, or the same vertex set as an earlier triangle.
//  3 manifold  on flat arrays: pair the faces of every edge (the faces of an edge shared by
//              more than two are paired greedily, preferring opposite directions), orient each
//              component by BFS over the pairs (an inconsistent pair is cut, which is how a
//              Moebius band becomes orientable; the majority orientation wins), then give
//              every fan of faces around a vertex its own vertex. A fan can still hold two
//              faces on one edge that are not paired (a fold that wraps around both ends of
//              the edge, common in badly decimated meshes): such a face gets its own copy of
//              one end of the edge, and the pass repeats until nothing changes (a round that
//              does not finish gives at least one corner a vertex of its own; there are 3F
//              corners, so it terminates).
//  4 OpenMesh  the result is loaded face by face into an OpenMesh half-edge mesh; a face it
//              refuses is detached as a last resort (counted, never seen on test data), so
//              the output is always an oriented 2-manifold with boundary.
//  5 holes     boundary loops are walked on the half-edge mesh; a loop is filled (hole_fill.h)
//              unless it touches a vertex on the brick cut, is too large, or is a seam left
//              by step 3 (it passes twice through copies of one input vertex).
#include "stream/repair.h"

#include "core/check.h"
#include "core/error.h"
#include "stream/hole_fill.h"
#include "stream/topology.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wshadow"
#pragma GCC diagnostic ignored "-Wunused-parameter"
#pragma GCC diagnostic ignored "-Wdeprecated-copy"
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#pragma GCC diagnostic pop

namespace mebake::stream {
namespace {

using Tri = std::array<uint32_t, 3>;
using OmMesh = OpenMesh::TriMesh_ArrayKernelT<>;
constexpr int kMaxHoleEdgesLimit = 1024;

void ValidateOptions(const RepairOptions& o) {
    if (!(o.weld_epsilon >= 0) || !std::isfinite(o.weld_epsilon))
        UsageError("repair: weld epsilon must be finite and >= 0, got {}", o.weld_epsilon);
    if (!(o.min_area_ratio >= 0) || !(o.min_area_ratio < 1))
        UsageError("repair: min area ratio must be in [0, 1), got {}", o.min_area_ratio);
    if (o.max_hole_edges < 3 || o.max_hole_edges > kMaxHoleEdgesLimit)
        UsageError("repair: max hole edges must be in [3, {}], got {}", kMaxHoleEdgesLimit,
                   o.max_hole_edges);
    if (!(o.max_hole_relative_diameter >= 0) || !std::isfinite(o.max_hole_relative_diameter))
        UsageError("repair: max hole relative diameter must be finite and >= 0, got {}",
                   o.max_hole_relative_diameter);
}

Vec3d ToD(const Vec3f& p) {
    return Vec3d(p);
}

bool Finite(const Vec3f& p) {
    return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
}

// rep[v] for every input vertex: its cluster's representative, or kNoIndex if the position
// is not finite.
std::vector<uint32_t> Weld(const TriMesh& mesh, double epsilon, size_t* welded) {
    const size_t nv = mesh.vertex_count();
    std::vector<uint32_t> by_id;  // finite vertices by (vertex_id, index)
    by_id.reserve(nv);
    for (uint32_t v = 0; v < nv; ++v)
        if (Finite(mesh.position[v]))
            by_id.push_back(v);
    std::sort(by_id.begin(), by_id.end(), [&](uint32_t a, uint32_t b) {
        return mesh.vertex_id[a] != mesh.vertex_id[b] ? mesh.vertex_id[a] < mesh.vertex_id[b]
                                                      : a < b;
    });
    std::vector<uint32_t> rank(nv, kNoIndex);
    for (uint32_t i = 0; i < by_id.size(); ++i)
        rank[by_id[i]] = i;
    DisjointSets sets(by_id.size());

    // Exact duplicates: sort ranks by position.
    std::vector<uint32_t> order(by_id.size());
    std::iota(order.begin(), order.end(), 0u);
    auto pos = [&](uint32_t r) {
        return mesh.position[by_id[r]];
    };
    std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
        const Vec3f pa = pos(a), pb = pos(b);
        if (pa.x != pb.x)
            return pa.x < pb.x;
        if (pa.y != pb.y)
            return pa.y < pb.y;
        if (pa.z != pb.z)
            return pa.z < pb.z;
        return a < b;
    });
    for (size_t i = 1; i < order.size(); ++i)
        if (pos(order[i]) == pos(order[i - 1]))
            sets.Union(order[i], order[i - 1]);

    if (epsilon > 0) {
        // One point per exact cluster, binned on a grid of cell size epsilon; each point is
        // compared with the points of the 27 cells around it.
        struct Cell {
            int64_t x, y, z;
            uint32_t r;
        };
        std::vector<Cell> cells;
        const double limit = 1e15;
        auto coord = [&](float c) {
            return int64_t(std::floor(std::clamp(double(c) / epsilon, -limit, limit)));
        };
        for (size_t i = 0; i < order.size(); ++i) {
            if (i > 0 && pos(order[i]) == pos(order[i - 1]))
                continue;
            const Vec3f p = pos(order[i]);
            cells.push_back({coord(p.x), coord(p.y), coord(p.z), order[i]});
        }
        auto less = [](const Cell& a, const Cell& b) {
            if (a.x != b.x)
                return a.x < b.x;
            if (a.y != b.y)
                return a.y < b.y;
            if (a.z != b.z)
                return a.z < b.z;
            return a.r < b.r;
        };
        std::sort(cells.begin(), cells.end(), less);
        const double eps2 = epsilon * epsilon;
        for (const Cell& c : cells) {
            const Vec3d p = ToD(pos(c.r));
            for (int64_t dx = -1; dx <= 1; ++dx)
                for (int64_t dy = -1; dy <= 1; ++dy) {
                    const Cell lo{c.x + dx, c.y + dy, c.z - 1, 0};
                    auto it = std::lower_bound(cells.begin(), cells.end(), lo, less);
                    for (; it != cells.end() && it->x == lo.x && it->y == lo.y && it->z <= c.z + 1;
                         ++it) {
                        if (it->r <= c.r)
                            continue;  // each pair once
                        const Vec3d d = ToD(pos(it->r)) - p;
                        if (Dot(d, d) <= eps2)
                            sets.Union(c.r, it->r);
                    }
                }
        }
    }

    std::vector<uint32_t> rep(nv, kNoIndex);
    *welded = 0;
    for (uint32_t v = 0; v < nv; ++v) {
        if (rank[v] == kNoIndex)
            continue;
        rep[v] = by_id[sets.Find(rank[v])];
        if (rep[v] != v)
            ++*welded;
    }
    return rep;
}

bool ZeroArea(const Vec3d& a, const Vec3d& b, const Vec3d& c, double ratio) {
    const double twice_area = Length(Cross(b - a, c - a));
    const double longest = std::max({Dot(b - a, b - a), Dot(c - b, c - b), Dot(a - c, a - c)});
    return !(twice_area > ratio * longest);
}

uint32_t From(const std::vector<Tri>& tris, uint32_t h) {
    return tris[h / 3][h % 3];
}

// The half-edge of face f between vertices a and b (either direction).
uint32_t HalfedgeOf(const std::vector<Tri>& tris, uint32_t f, uint32_t a, uint32_t b) {
    const Tri& t = tris[f];
    for (uint32_t k = 0; k < 3; ++k) {
        const uint32_t u = t[k], w = t[(k + 1) % 3];
        if ((u == a && w == b) || (u == b && w == a))
            return 3 * f + k;
    }
    return kNoIndex;
}

// Gives face f three fresh vertices (copies of its own).
void Isolate(std::vector<Tri>& tris, std::vector<uint32_t>& vsrc, uint32_t f) {
    for (uint32_t& v : tris[f]) {
        vsrc.push_back(vsrc[v]);
        v = uint32_t(vsrc.size() - 1);
    }
}

// Step 3. tris index into vsrc (current vertex -> source input vertex); copies are appended
// to vsrc. On return tris is an oriented 2-manifold with boundary.
void MakeManifold(std::vector<Tri>& tris, std::vector<uint32_t>& vsrc, RepairReport& report) {
    const uint32_t nf = uint32_t(tris.size());
    for (bool first_round = true;; first_round = false) {
        // Pair the faces of every edge.
        const EdgeGroups groups = BuildEdgeGroups(tris);
        std::vector<uint32_t> join(size_t(nf) * 3, kNoIndex);
        for (size_t g = 0; g < groups.group_count(); ++g) {
            const uint32_t* hs = &groups.halfedge[groups.start[g]];
            const size_t size = groups.group_size(g);
            if (size < 2)
                continue;
            if (size > 2 && first_round)
                ++report.nonmanifold_edges;
            for (size_t i = 0; i < size; ++i) {
                if (join[hs[i]] != kNoIndex)
                    continue;
                size_t pick = size;
                for (size_t j = i + 1; j < size; ++j) {
                    if (join[hs[j]] != kNoIndex)
                        continue;
                    if (pick == size)
                        pick = j;
                    if (From(tris, hs[j]) != From(tris, hs[i])) {  // opposite direction
                        pick = j;
                        break;
                    }
                }
                if (pick == size)
                    break;
                join[hs[i]] = hs[pick];
                join[hs[pick]] = hs[i];
            }
        }

        // Orientation: BFS over pairs; an inconsistent pair is cut.
        std::vector<uint8_t> flip(nf, 0), visited(nf, 0);
        std::vector<uint32_t> component;
        for (uint32_t seed = 0; seed < nf; ++seed) {
            if (visited[seed])
                continue;
            component.assign(1, seed);
            visited[seed] = 1;
            size_t flipped = 0;
            for (size_t head = 0; head < component.size(); ++head) {
                const uint32_t f = component[head];
                for (uint32_t k = 0; k < 3; ++k) {
                    const uint32_t h = 3 * f + k, o = join[h];
                    if (o == kNoIndex)
                        continue;
                    const uint32_t g = o / 3;
                    const uint8_t want = flip[f] ^ uint8_t(From(tris, h) == From(tris, o));
                    if (!visited[g]) {
                        visited[g] = 1;
                        flip[g] = want;
                        flipped += want;
                        component.push_back(g);
                    } else if (flip[g] != want) {
                        join[h] = join[o] = kNoIndex;
                        ++report.orientation_cuts;
                    }
                }
            }
            if (2 * flipped > component.size()) {
                for (uint32_t f : component)
                    flip[f] ^= 1;
                flipped = component.size() - flipped;
            }
            report.orientation_flips += flipped;
        }
        // Joined pairs as (face, face, a, b), then apply the flips.
        struct Pair {
            uint32_t f, g, a, b;
        };
        std::vector<Pair> pairs;
        for (uint32_t h = 0; h < 3 * nf; ++h) {
            const uint32_t o = join[h];
            if (o == kNoIndex || o < h)
                continue;
            pairs.push_back({h / 3, o / 3, From(tris, h), tris[h / 3][(h % 3 + 1) % 3]});
        }
        for (uint32_t f = 0; f < nf; ++f)
            if (flip[f])
                std::swap(tris[f][1], tris[f][2]);

        // Fans: corners joined across paired edges; each fan gets its own vertex.
        DisjointSets corners(size_t(nf) * 3);
        std::vector<uint32_t> join2(size_t(nf) * 3, kNoIndex);
        for (const Pair& p : pairs) {
            corners.Union(CornerAt(tris[p.f], p.f, p.a), CornerAt(tris[p.g], p.g, p.a));
            corners.Union(CornerAt(tris[p.f], p.f, p.b), CornerAt(tris[p.g], p.g, p.b));
            const uint32_t hf = HalfedgeOf(tris, p.f, p.a, p.b);
            const uint32_t hg = HalfedgeOf(tris, p.g, p.a, p.b);
            join2[hf] = hg;
            join2[hg] = hf;
        }
        std::vector<uint8_t> claimed(vsrc.size(), 0);
        std::vector<uint32_t> fan_vertex(size_t(nf) * 3, kNoIndex);
        for (uint32_t c = 0; c < 3 * nf; ++c) {
            if (corners.Find(c) != c)
                continue;
            const uint32_t v = tris[c / 3][c % 3];
            if (!claimed[v]) {
                claimed[v] = 1;
                fan_vertex[c] = v;
            } else {
                vsrc.push_back(vsrc[v]);
                fan_vertex[c] = uint32_t(vsrc.size() - 1);
                ++report.split_vertices;
            }
        }
        for (uint32_t c = 0; c < 3 * nf; ++c)
            tris[c / 3][c % 3] = fan_vertex[corners.Find(c)];

        // Check: every edge has one face, or two paired faces of opposite direction.
        // Anything else (rare pathological fans) loses its extra faces, and we go again.
        const EdgeGroups check = BuildEdgeGroups(tris);
        std::vector<uint32_t> detach;
        for (size_t g = 0; g < check.group_count(); ++g) {
            const size_t size = check.group_size(g);
            if (size < 2)
                continue;
            const uint32_t* hs = &check.halfedge[check.start[g]];
            if (size == 2 && join2[hs[0]] == hs[1] && From(tris, hs[0]) != From(tris, hs[1]))
                continue;
            uint32_t keep0 = hs[0], keep1 = kNoIndex;
            for (size_t i = 0; i < size && keep1 == kNoIndex; ++i) {
                const uint32_t o = join2[hs[i]];
                if (o == kNoIndex || From(tris, hs[i]) == From(tris, o))
                    continue;
                if (std::find(hs, hs + size, o) != hs + size) {
                    keep0 = hs[i];
                    keep1 = o;
                }
            }
            // Detach the others at one end of the edge (the smaller vertex index).
            const uint32_t end = std::min(From(tris, hs[0]), tris[hs[0] / 3][(hs[0] % 3 + 1) % 3]);
            for (size_t i = 0; i < size; ++i)
                if (hs[i] != keep0 && hs[i] != keep1)
                    detach.push_back(CornerAt(tris[hs[i] / 3], hs[i] / 3, end));
        }
        if (detach.empty())
            return;
        std::sort(detach.begin(), detach.end());
        detach.erase(std::unique(detach.begin(), detach.end()), detach.end());
        for (uint32_t c : detach) {
            vsrc.push_back(vsrc[tris[c / 3][c % 3]]);
            tris[c / 3][c % 3] = uint32_t(vsrc.size() - 1);
        }
        report.detached_corners += detach.size();
    }
}

// Drops unreferenced vertices; keeps the order (input vertices first, then copies).
void Compact(std::vector<Tri>& tris, std::vector<uint32_t>& vsrc) {
    std::vector<uint32_t> remap(vsrc.size(), kNoIndex);
    for (const Tri& t : tris)
        for (uint32_t v : t)
            remap[v] = 0;
    uint32_t next = 0;
    for (size_t v = 0; v < vsrc.size(); ++v)
        if (remap[v] == 0) {
            remap[v] = next;
            vsrc[next++] = vsrc[v];
        }
    vsrc.resize(next);
    for (Tri& t : tris)
        for (uint32_t& v : t)
            v = remap[v];
}

struct Box {
    Vec3d lo{std::numeric_limits<double>::max(), std::numeric_limits<double>::max(),
             std::numeric_limits<double>::max()};
    Vec3d hi{-std::numeric_limits<double>::max(), -std::numeric_limits<double>::max(),
             -std::numeric_limits<double>::max()};
    void Add(const Vec3d& p) {
        lo = Min(lo, p);
        hi = Max(hi, p);
    }
    double Diagonal() const { return Length(hi - lo); }
};

}  // namespace

RepairReport Repair(TriMesh& mesh, const std::vector<uint8_t>& vertex_on_cut,
                    const RepairOptions& options) {
    ValidateOptions(options);
    const size_t nv_in = mesh.vertex_count();
    const size_t nf_in = mesh.triangle_count();
    CHECK_EQ(mesh.vertex_id.size(), nv_in);
    CHECK_EQ(mesh.face_id.size(), nf_in);
    CHECK(mesh.albedo.empty() || mesh.albedo.size() == nv_in);
    CHECK(mesh.material.empty() || mesh.material.size() == nf_in);
    CHECK(vertex_on_cut.empty() || vertex_on_cut.size() == nv_in);
    CHECK_LT(nv_in, size_t(kNoIndex) / 2);
    CHECK_LT(nf_in, size_t(kNoIndex) / 4);

    RepairReport report;
    report.input_vertices = nv_in;
    report.input_triangles = nf_in;

    // 1. Weld.
    const std::vector<uint32_t> rep = Weld(mesh, options.weld_epsilon, &report.welded_vertices);
    std::vector<uint8_t> rep_on_cut(nv_in, 0);
    if (!vertex_on_cut.empty())
        for (size_t v = 0; v < nv_in; ++v)
            if (vertex_on_cut[v] && rep[v] != kNoIndex)
                rep_on_cut[rep[v]] = 1;

    // 2. Drop invalid, degenerate, zero-area and duplicate triangles.
    std::vector<Tri> tris;
    std::vector<uint32_t> src_face;  // kept triangle -> input triangle
    tris.reserve(nf_in);
    src_face.reserve(nf_in);
    for (uint32_t f = 0; f < nf_in; ++f) {
        Tri t = mesh.triangles[f];
        bool valid = true;
        for (uint32_t& v : t) {
            valid = valid && v < nv_in && rep[v] != kNoIndex;
            if (valid)
                v = rep[v];
        }
        if (!valid) {
            ++report.invalid_triangles;
            continue;
        }
        if (t[0] == t[1] || t[1] == t[2] || t[2] == t[0]) {
            ++report.degenerate_triangles;
            continue;
        }
        if (ZeroArea(ToD(mesh.position[t[0]]), ToD(mesh.position[t[1]]), ToD(mesh.position[t[2]]),
                     options.min_area_ratio)) {
            ++report.zero_area_triangles;
            continue;
        }
        tris.push_back(t);
        src_face.push_back(f);
    }
    {
        std::vector<Tri> sorted(tris);
        for (Tri& t : sorted)
            std::sort(t.begin(), t.end());
        std::vector<uint32_t> order(tris.size());
        std::iota(order.begin(), order.end(), 0u);
        std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
            return sorted[a] != sorted[b] ? sorted[a] < sorted[b] : a < b;
        });
        std::vector<uint8_t> drop(tris.size(), 0);
        for (size_t i = 1; i < order.size(); ++i)
            if (sorted[order[i]] == sorted[order[i - 1]])
                drop[order[i]] = 1;
        size_t kept = 0;
        for (size_t i = 0; i < tris.size(); ++i) {
            if (drop[i])
                continue;
            tris[kept] = tris[i];
            src_face[kept++] = src_face[i];
        }
        report.duplicate_triangles = tris.size() - kept;
        tris.resize(kept);
        src_face.resize(kept);
    }

    // 3-4. Manifold and oriented, confirmed by OpenMesh.
    std::vector<uint32_t> vsrc(nv_in);  // current vertex -> input vertex
    std::iota(vsrc.begin(), vsrc.end(), 0u);
    OmMesh om;
    while (true) {
        MakeManifold(tris, vsrc, report);
        Compact(tris, vsrc);
        om.clean();
        // Edges: 3F/2 plus half the border edges, and a brick's border is long, so 3F/2
        // would make the edge arrays grow by doubling (old and new copy at once, the brick
        // pass's peak); 3F bounds them, and reserved pages never written cost no memory.
        om.reserve(vsrc.size(), tris.size() * 3 + 16, tris.size() + 16);
        for (uint32_t s : vsrc) {
            const Vec3f& p = mesh.position[s];
            om.add_vertex(OmMesh::Point(p.x, p.y, p.z));
        }
        std::vector<uint32_t> refused;
        for (uint32_t f = 0; f < tris.size(); ++f) {
            const Tri& t = tris[f];
            const auto fh =
                om.add_face(OmMesh::VertexHandle(int(t[0])), OmMesh::VertexHandle(int(t[1])),
                            OmMesh::VertexHandle(int(t[2])));
            if (!fh.is_valid())
                refused.push_back(f);
        }
        if (refused.empty())
            break;
        for (uint32_t f : refused)
            Isolate(tris, vsrc, f);
        report.isolated_triangles += refused.size();
    }
    const size_t nv = vsrc.size();
    size_t referenced_inputs = 0;
    {
        std::vector<uint8_t> seen(nv_in, 0);
        for (uint32_t s : vsrc)
            if (!seen[s]) {
                seen[s] = 1;
                ++referenced_inputs;
            }
    }
    report.unreferenced_vertices = nv_in - report.welded_vertices - referenced_inputs;

    // 5. Holes.
    std::vector<Tri> fill_tris;
    std::vector<uint32_t> fill_material;
    {
        DisjointSets comp(nv);
        for (const Tri& t : tris) {
            comp.Union(t[0], t[1]);
            comp.Union(t[0], t[2]);
        }
        std::vector<Box> comp_box(nv);
        for (uint32_t v = 0; v < nv; ++v)
            comp_box[comp.Find(v)].Add(ToD(mesh.position[vsrc[v]]));

        om.request_face_status();
        om.request_edge_status();
        om.request_halfedge_status();
        om.request_vertex_status();
        std::vector<uint8_t> walked(om.n_halfedges(), 0);
        std::vector<uint32_t> loop, seam;
        std::vector<Vec3d> loop_pos;
        std::vector<Tri> local;
        const size_t n_halfedges = om.n_halfedges();  // hole faces add no new boundary
        for (size_t hi = 0; hi < n_halfedges; ++hi) {
            const OmMesh::HalfedgeHandle h0{int(hi)};
            if (walked[hi] || !om.is_boundary(h0))
                continue;
            loop.clear();
            for (auto h = h0;;) {
                walked[size_t(h.idx())] = 1;
                loop.push_back(uint32_t(om.from_vertex_handle(h).idx()));
                h = om.next_halfedge_handle(h);
                if (h == h0 || loop.size() > om.n_halfedges())
                    break;
            }
            ++report.boundary_loops;
            if (!options.fill_holes)
                continue;
            bool on_cut = false;
            Box box;
            for (uint32_t v : loop) {
                on_cut = on_cut || rep_on_cut[vsrc[v]];
                box.Add(ToD(mesh.position[vsrc[v]]));
            }
            if (on_cut) {
                ++report.holes_on_cut;
                continue;
            }
            // Two copies of one input vertex on the loop: a seam left by a non-manifold
            // split, zero-width, not a hole.
            seam.clear();
            for (uint32_t v : loop)
                seam.push_back(vsrc[v]);
            std::sort(seam.begin(), seam.end());
            if (std::adjacent_find(seam.begin(), seam.end()) != seam.end()) {
                ++report.seams;
                continue;
            }
            const double comp_diag = comp_box[comp.Find(loop[0])].Diagonal();
            if (loop.size() > size_t(options.max_hole_edges) ||
                !(box.Diagonal() <= options.max_hole_relative_diameter * comp_diag)) {
                ++report.holes_too_large;
                continue;
            }
            // The border of a lone triangle: filling it would glue a reversed copy on.
            if (loop.size() == 3) {
                const auto f0 = om.face_handle(om.opposite_halfedge_handle(h0));
                const auto h1 = om.next_halfedge_handle(h0);
                const auto f1 = om.face_handle(om.opposite_halfedge_handle(h1));
                const auto f2 =
                    om.face_handle(om.opposite_halfedge_handle(om.next_halfedge_handle(h1)));
                if (f0 == f1 && f1 == f2) {
                    ++report.holes_unfillable;
                    continue;
                }
            }
            loop_pos.clear();
            for (uint32_t v : loop)
                loop_pos.push_back(ToD(mesh.position[vsrc[v]]));
            auto chord_allowed = [&](uint32_t i, uint32_t j) {
                return !om.find_halfedge(OmMesh::VertexHandle(int(loop[i])),
                                         OmMesh::VertexHandle(int(loop[j])))
                            .is_valid();
            };
            local.clear();
            if (!TriangulateHole(loop_pos, chord_allowed, options.min_area_ratio, &local)) {
                ++report.holes_unfillable;
                continue;
            }
            std::vector<OmMesh::FaceHandle> added;
            for (const Tri& t : local) {
                const auto fh = om.add_face(OmMesh::VertexHandle(int(loop[t[0]])),
                                            OmMesh::VertexHandle(int(loop[t[1]])),
                                            OmMesh::VertexHandle(int(loop[t[2]])));
                if (!fh.is_valid())
                    break;
                added.push_back(fh);
            }
            if (added.size() != local.size()) {
                for (auto fh : added)
                    om.delete_face(fh, false);
                ++report.holes_unfillable;
                continue;
            }
            const auto neighbour = om.face_handle(om.opposite_halfedge_handle(h0));
            const uint32_t material =
                mesh.material.empty() ? 0 : mesh.material[src_face[size_t(neighbour.idx())]];
            for (const Tri& t : local) {
                fill_tris.push_back({loop[t[0]], loop[t[1]], loop[t[2]]});
                fill_material.push_back(material);
            }
            ++report.holes_filled;
            report.hole_triangles += local.size();
        }
    }

    // Output.
    TriMesh out;
    out.position.resize(nv);
    out.vertex_id.resize(nv);
    if (!mesh.albedo.empty())
        out.albedo.resize(nv);
    report.vertex_on_cut.assign(nv, 0);
    for (uint32_t v = 0; v < nv; ++v) {
        const uint32_t s = vsrc[v];
        out.position[v] = mesh.position[s];
        out.vertex_id[v] = mesh.vertex_id[s];
        if (!mesh.albedo.empty())
            out.albedo[v] = mesh.albedo[s];
        report.vertex_on_cut[v] = rep_on_cut[s];
    }
    out.triangles = std::move(tris);
    out.face_id.resize(out.triangles.size());
    if (!mesh.material.empty())
        out.material.resize(out.triangles.size());
    for (size_t f = 0; f < out.triangles.size(); ++f) {
        out.face_id[f] = mesh.face_id[src_face[f]];
        if (!mesh.material.empty())
            out.material[f] = mesh.material[src_face[f]];
    }
    out.triangles.insert(out.triangles.end(), fill_tris.begin(), fill_tris.end());
    out.face_id.resize(out.triangles.size(), kNoId);
    if (!mesh.material.empty())
        out.material.insert(out.material.end(), fill_material.begin(), fill_material.end());
    mesh = std::move(out);

    report.output_vertices = mesh.vertex_count();
    report.output_triangles = mesh.triangle_count();
    report.output_boundary_loops = report.boundary_loops - report.holes_filled;
    return report;
}

}  // namespace mebake::stream
