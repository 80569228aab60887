#include "stream/tile.h"

#include <cmath>
#include <cstring>

#include "core/error.h"
#include "io/chunk_file.h"

namespace mebake::stream {

using io::Tag;

namespace {
constexpr uint32_t kKind = Tag("TILE");

template <typename T>
std::vector<T> ReadExact(const io::ChunkReader& r, uint32_t tag, size_t count) {
    auto v = r.ReadArray<T>(tag);
    if (v.size() != count)
        CorruptError({r.path()}, "chunk {} has {} elements, expected {}", io::TagName(tag), v.size(),
                     count);
    return v;
}
}  // namespace

void WriteTile(const std::string& path, const ChartTile& t) {
    io::ChunkWriter w(path, kKind, kTileVersion);
    ChartMeta meta = t.meta;
    meta.geometry_resolution = t.geometry.resolution;  // derived from what is written
    w.Add(Tag("META"), 0, {reinterpret_cast<const uint8_t*>(&meta), sizeof(ChartMeta)}, false);
    w.AddArray(Tag("VPOS"), 0, t.position);
    w.AddArray(Tag("VNRM"), 0, t.normal);
    w.AddArray(Tag("VUV "), 0, t.uv);
    if (!t.color.empty()) w.AddArray(Tag("VCOL"), 0, t.color);
    w.AddArray(Tag("VGID"), 0, t.vertex_id);
    w.AddArray(Tag("TRIS"), 0, t.triangles);
    w.AddArray(Tag("FGID"), 0, t.face_id);
    w.AddArray(Tag("FMAT"), 0, t.material);
    w.AddArray(Tag("GCST"), 0, t.grid.cell_start);
    w.AddArray(Tag("GCTR"), 0, t.grid.cell_tris);
    w.AddArray(Tag("GNST"), 0, t.grid.near_start);
    w.AddArray(Tag("GNTR"), 0, t.grid.near_tris);
    w.AddArray(Tag("GOUT"), 0, t.grid.outline_tris);
    w.AddArray(Tag("GEO0"), 0, t.geometry.levels.back());
    // Derived from the mesh written, so it can never disagree with it.
    const TriangleOctree octree = BuildTriangleOctree(
        t.position, std::span<const std::array<uint32_t, 3>>(t.triangles), kTileOctree);
    w.AddArray(Tag("OCND"), 0, octree.nodes);
    w.AddArray(Tag("OCTR"), 0, octree.order);
    w.Finish();
}

ChartTile ReadTile(const std::string& path, TileParts parts) {
    io::ChunkReader r(path, kKind, 1, kTileVersion);
    if (r.version() < kTileVersion)
        CorruptError({path, 8},
                     "tile format version {} predates the tiles' octrees (version {}): ingest the "
                     "scan again",
                     r.version(), kTileVersion);
    ChartTile t;
    auto meta = r.Read(Tag("META"));
    if (meta.size() != sizeof(ChartMeta)) CorruptError({path}, "META chunk has the wrong size");
    std::memcpy(&t.meta, meta.data(), sizeof(ChartMeta));
    const auto& m = t.meta;
    auto pow2 = [](uint32_t x) { return x != 0 && (x & (x - 1)) == 0 && x <= 65536; };
    if (!pow2(m.resolution) || !pow2(m.geometry_resolution) || !std::isfinite(m.scale) ||
        m.scale <= 0 || (m.emitter_resolution != 0 && !pow2(m.emitter_resolution)))
        CorruptError({path},
                     "META chunk is inconsistent (resolution {}, geometry {}, scale {}, emitter {})",
                     m.resolution, m.geometry_resolution, m.scale, m.emitter_resolution);
    if (parts != TileParts::Mesh) {
        const uint32_t g = m.geometry_resolution;
        t.geometry.resolution = g;
        int levels = 0;
        while ((1u << levels) < g) ++levels;
        t.geometry.levels.resize(size_t(levels) + 1);
        t.geometry.levels.back() = ReadExact<GeometryTexel>(r, Tag("GEO0"), size_t(g) * g);
        t.geometry.BuildPyramid();
    }
    if (parts == TileParts::GeometryImage) return t;
    const size_t nv = m.vertex_count, nt = m.triangle_count;
    t.position = ReadExact<Vec3f>(r, Tag("VPOS"), nv);
    t.normal = ReadExact<Vec3f>(r, Tag("VNRM"), nv);
    t.uv = ReadExact<Vec2f>(r, Tag("VUV "), nv);
    if (r.Has(Tag("VCOL"))) t.color = ReadExact<Vec3f>(r, Tag("VCOL"), nv);
    t.vertex_id = ReadExact<uint64_t>(r, Tag("VGID"), nv);
    t.triangles = ReadExact<std::array<uint32_t, 3>>(r, Tag("TRIS"), nt);
    t.face_id = ReadExact<uint64_t>(r, Tag("FGID"), nt);
    t.material = ReadExact<uint32_t>(r, Tag("FMAT"), nt);
    for (const auto& tri : t.triangles)
        for (uint32_t v : tri)
            if (v >= nv) CorruptError({path}, "TRIS names vertex {} of {}", v, nv);
    auto& g = t.grid;
    g.resolution = int(m.grid_resolution);
    const size_t cells = size_t(m.grid_resolution) * m.grid_resolution;
    g.uv = t.uv;
    g.triangles = t.triangles;
    g.cell_start = ReadExact<uint32_t>(r, Tag("GCST"), cells + 1);
    g.cell_tris = r.ReadArray<uint32_t>(Tag("GCTR"));
    g.near_start = ReadExact<uint32_t>(r, Tag("GNST"), cells + 1);
    g.near_tris = r.ReadArray<uint32_t>(Tag("GNTR"));
    g.outline_tris = r.ReadArray<uint32_t>(Tag("GOUT"));
    if (g.cell_start.back() != g.cell_tris.size() || g.near_start.back() != g.near_tris.size())
        CorruptError({path}, "grid arrays are inconsistent");
    for (uint32_t x : g.cell_tris)
        if (x >= nt) CorruptError({path}, "grid names triangle {} of {}", x, nt);
    for (uint32_t x : g.near_tris)
        if (x >= nt) CorruptError({path}, "grid names triangle {} of {}", x, nt);
    t.octree.nodes = r.ReadArray<OctreeNode>(Tag("OCND"));
    t.octree.order = r.ReadArray<uint32_t>(Tag("OCTR"));
    CheckTriangleOctree(t.octree, nt, path.c_str());
    return t;
}

}  // namespace mebake::stream
