// Edge groups, twins, vertex fans and boundary loops of a triangle soup (see topology.h).
// Everything is sort-based on flat arrays, so the results never depend on hash order.
#include "stream/topology.h"

#include "core/check.h"

#include <algorithm>

namespace mebake::stream {

EdgeGroups BuildEdgeGroups(const std::vector<std::array<uint32_t, 3>>& triangles) {
    // Half-edges sorted by (min vertex, max vertex, half-edge id): a counting sort on the
    // min vertex (filled in id order, so stable), then an insertion sort of each vertex's
    // few half-edges by max vertex. Linear, and the same order as a comparison sort.
    const size_t n = triangles.size() * 3;
    CHECK_LT(n, size_t(kNoIndex));
    uint32_t vertex_end = 0;
    for (const auto& t : triangles)
        vertex_end = std::max({vertex_end, t[0] + 1, t[1] + 1, t[2] + 1});
    auto ends = [&](uint32_t h) {
        const auto& t = triangles[h / 3];
        const uint32_t a = t[h % 3], b = t[(h % 3 + 1) % 3];
        return std::pair<uint32_t, uint32_t>(std::min(a, b), std::max(a, b));
    };
    std::vector<uint32_t> start(size_t(vertex_end) + 1, 0);
    for (uint32_t h = 0; h < n; ++h)
        ++start[ends(h).first + 1];
    for (size_t v = 0; v < vertex_end; ++v)
        start[v + 1] += start[v];
    EdgeGroups groups;
    groups.halfedge.resize(n);
    std::vector<uint32_t> other(n);  // the max vertex of each sorted half-edge
    {
        std::vector<uint32_t> fill(start.begin(), start.end() - 1);
        for (uint32_t h = 0; h < n; ++h) {
            const auto [a, b] = ends(h);
            other[fill[a]] = b;
            groups.halfedge[fill[a]++] = h;
        }
    }
    for (size_t v = 0; v < vertex_end; ++v) {
        for (uint32_t i = start[v] + 1; i < start[v + 1]; ++i) {
            const uint32_t b = other[i], h = groups.halfedge[i];
            uint32_t j = i;
            for (; j > start[v] && other[j - 1] > b; --j) {
                other[j] = other[j - 1];
                groups.halfedge[j] = groups.halfedge[j - 1];
            }
            other[j] = b;
            groups.halfedge[j] = h;
        }
    }
    groups.start.reserve(n / 2 + 2);
    for (size_t i = 0; i < n; ++i) {
        const bool same = i > 0 && other[i] == other[i - 1] &&
                          ends(groups.halfedge[i]).first == ends(groups.halfedge[i - 1]).first;
        if (!same)
            groups.start.push_back(uint32_t(i));
    }
    groups.start.push_back(uint32_t(n));
    return groups;
}

std::vector<uint32_t> BuildTwins(const std::vector<std::array<uint32_t, 3>>& triangles,
                                 const EdgeGroups& groups) {
    std::vector<uint32_t> twin(triangles.size() * 3, kNoIndex);
    for (size_t g = 0; g < groups.group_count(); ++g) {
        if (groups.group_size(g) != 2)
            continue;
        uint32_t h0 = groups.halfedge[groups.start[g]], h1 = groups.halfedge[groups.start[g] + 1];
        const auto& t = triangles[h0 / 3];
        if (t[h0 % 3] == t[(h0 % 3 + 1) % 3])
            continue;  // zero-length edge
        twin[h0] = h1;
        twin[h1] = h0;
    }
    return twin;
}

VertexFaces BuildVertexFaces(const std::vector<std::array<uint32_t, 3>>& triangles,
                             size_t vertex_count) {
    VertexFaces vf;
    vf.offset.assign(vertex_count + 1, 0);
    auto distinct = [](const std::array<uint32_t, 3>& t, int k) {
        return (k == 0 || t[k] != t[0]) && (k < 2 || t[2] != t[1]);
    };
    for (const auto& t : triangles)
        for (int k = 0; k < 3; ++k) {
            CHECK_LT(t[k], vertex_count);
            if (distinct(t, k))
                ++vf.offset[t[k] + 1];
        }
    for (size_t v = 0; v < vertex_count; ++v)
        vf.offset[v + 1] += vf.offset[v];
    vf.face.resize(vf.offset[vertex_count]);
    std::vector<uint32_t> fill(vf.offset.begin(), vf.offset.end() - 1);
    for (size_t f = 0; f < triangles.size(); ++f)
        for (int k = 0; k < 3; ++k)
            if (distinct(triangles[f], k))
                vf.face[fill[triangles[f][k]]++] = uint32_t(f);
    return vf;
}

TopologyReport AnalyzeTopology(const TriMesh& mesh) {
    const auto& tris = mesh.triangles;
    const size_t nv = mesh.vertex_count();
    TopologyReport r;
    r.faces = tris.size();

    std::vector<uint8_t> used(nv, 0);
    DisjointSets vertex_sets(nv);
    for (const auto& t : tris) {
        for (int k = 0; k < 3; ++k) {
            CHECK_LT(t[k], nv);
            used[t[k]] = 1;
        }
        if (t[0] == t[1] || t[1] == t[2] || t[2] == t[0])
            ++r.degenerate_faces;
        vertex_sets.Union(t[0], t[1]);
        vertex_sets.Union(t[0], t[2]);
    }
    for (size_t v = 0; v < nv; ++v) {
        if (!used[v])
            continue;
        ++r.vertices;
        if (vertex_sets.Find(uint32_t(v)) == v)
            ++r.components;
    }

    // Edges, and the corner unions that define the fans around each vertex.
    const EdgeGroups groups = BuildEdgeGroups(tris);
    DisjointSets corners(tris.size() * 3);
    std::vector<uint32_t> boundary;  // boundary half-edges, increasing
    for (size_t g = 0; g < groups.group_count(); ++g) {
        const uint32_t h0 = groups.halfedge[groups.start[g]];
        const uint32_t f0 = h0 / 3, k0 = h0 % 3;
        const uint32_t a = tris[f0][k0], b = tris[f0][(k0 + 1) % 3];
        if (a == b)
            continue;
        ++r.edges;
        const size_t size = groups.group_size(g);
        if (size == 1) {
            ++r.boundary_edges;
            boundary.push_back(h0);
        } else if (size > 2) {
            ++r.nonmanifold_edges;
        } else {
            const uint32_t h1 = groups.halfedge[groups.start[g] + 1];
            const uint32_t f1 = h1 / 3;
            if (tris[f1][h1 % 3] == a)
                ++r.inconsistent_edges;
            corners.Union(CornerAt(tris[f0], f0, a), CornerAt(tris[f1], f1, a));
            corners.Union(CornerAt(tris[f0], f0, b), CornerAt(tris[f1], f1, b));
        }
    }
    r.euler = int64_t(r.vertices) - int64_t(r.edges) + int64_t(r.faces);

    std::vector<uint32_t> fans(nv, 0);
    for (size_t f = 0; f < tris.size(); ++f) {
        const auto& t = tris[f];
        for (uint32_t k = 0; k < 3; ++k) {
            if (CornerAt(t, uint32_t(f), t[k]) != 3 * f + k)
                continue;  // repeated index
            if (corners.Find(uint32_t(3 * f + k)) == 3 * f + k)
                ++fans[t[k]];
        }
    }
    for (size_t v = 0; v < nv; ++v)
        if (fans[v] > 1)
            ++r.nonmanifold_vertices;

    // Boundary loops: follow boundary half-edges head to tail. In a manifold each vertex has
    // at most one outgoing boundary half-edge; otherwise the first unused one is taken.
    std::vector<uint32_t> out_offset(nv + 1, 0);
    for (uint32_t h : boundary)
        ++out_offset[tris[h / 3][h % 3] + 1];
    for (size_t v = 0; v < nv; ++v)
        out_offset[v + 1] += out_offset[v];
    std::vector<uint32_t> out(boundary.size());
    {
        std::vector<uint32_t> fill(out_offset.begin(), out_offset.end() - 1);
        for (uint32_t i = 0; i < boundary.size(); ++i)
            out[fill[tris[boundary[i] / 3][boundary[i] % 3]]++] = i;
    }
    std::vector<uint8_t> visited(boundary.size(), 0);
    for (uint32_t i = 0; i < boundary.size(); ++i) {
        if (visited[i])
            continue;
        ++r.boundary_loops;
        uint32_t cur = i;
        while (true) {
            visited[cur] = 1;
            const uint32_t h = boundary[cur];
            const uint32_t head = tris[h / 3][(h % 3 + 1) % 3];
            uint32_t next = kNoIndex;
            for (uint32_t j = out_offset[head]; j < out_offset[head + 1]; ++j)
                if (!visited[out[j]]) {
                    next = out[j];
                    break;
                }
            if (next == kNoIndex)
                break;
            cur = next;
        }
    }
    return r;
}

}  // namespace mebake::stream
