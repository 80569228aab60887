#include "output/export_mesh.h"

#include "core/check.h"
#include "core/error.h"
#include "io/byte_stream.h"
#include "io/mesh_format.h"
#include "output/lightmap.h"
#include "output/texel_stitch.h"

#include <algorithm>
#include <cctype>
#include <filesystem>

namespace mebake::output {

namespace {

// A primitive is split before it reaches this many vertices (uint32 indices).
constexpr uint64_t kPrimitiveVertices = uint64_t(1) << 31;

void CheckCounts(const BakeView& view, uint32_t chart, const stream::ChartTile& tile) {
    const auto& rec = view.manifest.charts[chart];
    if (tile.position.size() != rec.vertices || tile.triangles.size() != rec.triangles)
        CorruptError({view.TilePath(chart)},
                     "{} vertices and {} triangles but the manifest says {} and {}",
                     tile.position.size(), tile.triangles.size(), rec.vertices, rec.triangles);
}

struct Batches {
    io::VertexBatch vertices;
    io::FaceBatch faces;
};

MeshExportStats WriteLinear(const BakeView& view, const Atlas& atlas, const std::string& path,
                            io::MeshFormat format, const MeshExportOptions& opt) {
    MeshExportStats st;
    for (const auto& rec : view.manifest.charts) {
        st.vertices += rec.vertices;
        st.triangles += rec.triangles;
    }
    io::WriteOptions wo;
    wo.ply_encoding = opt.ply_encoding;
    wo.temp_dir = opt.temp_dir;
    auto out = io::OutputStream::Open(path);
    auto sink =
        format == io::MeshFormat::Ply ? io::MakePlyWriter(*out, wo) : io::MakeObjWriter(*out, wo);
    io::MeshHeader h;
    h.source = view.dir;
    h.format = format;
    h.vertex_count = st.vertices;
    h.face_count = st.triangles;
    h.has_normals = true;
    h.has_uvs = true;
    h.comments = {"mebake baked mesh: one vertex per chart corner; uv = light-map atlas "
                  "coordinates, origin bottom-left" +
                  std::string(atlas.pages.size() > 1 ? ", UDIM page 1001 + p" : "")};
    sink->Begin(h);
    uint64_t first_vertex = 0, first_face = 0;
    ForEachTile(
        view, AllCharts(view), stream::TileParts::Mesh,
        [&](uint32_t c, stream::ChartTile& tile) {
            CheckCounts(view, c, tile);
            Batches b;
            b.vertices.position = std::move(tile.position);
            b.vertices.normal = std::move(tile.normal);
            b.vertices.uv.reserve(tile.uv.size());
            for (const Vec2f& uv : tile.uv)
                b.vertices.uv.push_back(BottomLeftUv(atlas, c, uv));
            b.faces.size.assign(tile.triangles.size(), 3);
            b.faces.index.reserve(tile.triangles.size() * 3);
            for (const auto& t : tile.triangles)
                b.faces.index.insert(b.faces.index.end(), t.begin(), t.end());
            return b;
        },
        [&](uint32_t, stream::ChartTile&, Batches& b) {
            b.vertices.first = first_vertex;
            b.faces.first = first_face;
            for (uint64_t& i : b.faces.index)
                i += first_vertex;
            sink->Vertices(b.vertices);
            sink->Faces(b.faces);
            first_vertex += b.vertices.size();
            first_face += b.faces.count();
        });
    CHECK_EQ(first_vertex, st.vertices);
    io::MeshSummary summary;
    summary.vertex_count = first_vertex;
    summary.face_count = first_face;
    sink->End(summary);
    return st;
}

MeshExportStats WriteGlb(const BakeView& view, const Atlas& atlas, const std::string& path,
                         const MeshExportOptions& opt) {
    io::GlbOptions go;
    go.mode = opt.glb_mode;
    go.temp_dir = opt.temp_dir;
    io::GlbWriter glb(go);
    const uint32_t pages = uint32_t(atlas.pages.size());
    if (!opt.light_map_pngs.empty()) {
        CHECK_EQ(opt.light_map_pngs.size(), pages);
        for (uint32_t p = 0; p < pages; ++p)
            CHECK_EQ(glb.AddLightMapMaterial(io::ReadWholeFile(opt.light_map_pngs[p]),
                                             fmt::format("lightmap page {}", p + 1)),
                     p);
    } else {
        const auto stitch = StitchForView(view, atlas, MapContent::Radiosity);
        for (uint32_t p = 0; p < pages; ++p)
            CHECK_EQ(glb.AddLightMapMaterial(
                         EncodeLightMapPng(view, atlas, p, opt.tone, stitch.get()),
                         fmt::format("lightmap page {}", p + 1)),
                     p);
    }
    std::vector<uint32_t> order = AllCharts(view);
    std::stable_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
        return atlas.charts[a].page < atlas.charts[b].page;
    });
    MeshExportStats st;
    uint32_t page = ~0u;
    std::vector<std::array<uint32_t, 3>> tris;
    ForEachTile(
        view, order, stream::TileParts::Mesh,
        [&](uint32_t c, stream::ChartTile& tile) {
            CheckCounts(view, c, tile);
            std::vector<Vec2f> uv;
            uv.reserve(tile.uv.size());
            for (const Vec2f& u : tile.uv)
                uv.push_back(atlas.AtlasUv(c, u));
            return uv;
        },
        [&](uint32_t c, stream::ChartTile& tile, std::vector<Vec2f>& uv) {
            const uint32_t p = atlas.charts[c].page;
            if (p != page || glb.primitive_vertices() + tile.position.size() > kPrimitiveVertices) {
                glb.BeginPrimitive(p);
                page = p;
            }
            const uint32_t base = glb.AddVertices(tile.position, tile.normal, uv);
            tris = tile.triangles;
            for (auto& t : tris)
                for (uint32_t& v : t)
                    v += base;
            glb.AddTriangles(tris);
            st.vertices += tile.position.size();
            st.triangles += tile.triangles.size();
        });
    auto out = io::OutputStream::Open(path);
    glb.Finish(*out);
    return st;
}

}  // namespace

Vec2f BottomLeftUv(const Atlas& atlas, uint32_t chart, Vec2f uv) {
    const Vec2f a = atlas.AtlasUv(chart, uv);
    const uint32_t p = atlas.charts[chart].page;
    if (atlas.pages.size() <= 1)
        return Vec2f(a.x, 1 - a.y);
    return Vec2f(a.x + float(p % 10), (1 - a.y) + float(p / 10));
}

MeshExportStats WriteBakedMesh(const BakeView& view, const Atlas& atlas, const std::string& path,
                               const MeshExportOptions& options) {
    std::string ext = path == "-" ? ".ply" : std::filesystem::path(path).extension().string();
    for (char& ch : ext)
        ch = char(std::tolower(static_cast<unsigned char>(ch)));
    if (ext == ".glb")
        return WriteGlb(view, atlas, path, options);
    if (ext == ".ply")
        return WriteLinear(view, atlas, path, io::MeshFormat::Ply, options);
    if (ext == ".obj")
        return WriteLinear(view, atlas, path, io::MeshFormat::Obj, options);
    UsageError("{}: expected a .glb, .ply or .obj file name", path);
}

}  // namespace mebake::output
