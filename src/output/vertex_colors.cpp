#include "output/vertex_colors.h"

#include "core/check.h"
#include "core/error.h"
#include "core/paged_file.h"
#include "io/mesh_format.h"
#include "stream/spill.h"
#include "stream/trimesh.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <numbers>

namespace mebake::output {

namespace {

// Radiance = B / pi, divided as shading.cpp does so the glossy path agrees to the bit.
constexpr float kPi = float(std::numbers::pi);
constexpr size_t kBatch = size_t(1) << 16;

// Running sum of a vertex's copies.
struct Accum {
    float r = 0, g = 0, b = 0;
    uint32_t count = 0;
};
static_assert(sizeof(Accum) == 16);

using Face = std::array<uint64_t, 3>;

// A DiskArray on an unlinked temporary file.
template <typename T>
std::unique_ptr<DiskArray<T>> TempArray(const std::string& temp_dir, size_t cache_bytes) {
    return std::make_unique<DiskArray<T>>(PagedFile::Temporary{temp_dir, "vertex colours"},
                                          cache_bytes);
}

struct TileColors {
    std::vector<Vec3f> radiosity;  // per tile vertex
};

}  // namespace

VertexColorStats WriteVertexColors(const BakeView& view, const std::string& path,
                                   const VertexColorOptions& opt) {
    const uint64_t nv = view.manifest.vertex_count;
    // A page cache larger than its array buys nothing (its pages are allocated up front):
    // at 64 MiB each, the two arrays made every export ~190 MiB, the smallest scan's too.
    const auto cache = [&](size_t element) {
        return size_t(std::min<uint64_t>(std::max<uint64_t>(nv * element, uint64_t(1) << 20),
                                         opt.cache_bytes));
    };
    const std::string vpath = stream::Spill::VerticesPath(view.dir);
    // Read in order once (pass 2): a few pages are enough.
    DiskArray<Vec3f> positions(vpath, false, std::min(cache(sizeof(Vec3f)), size_t(4) << 20));
    if (positions.size() != nv)
        CorruptError({vpath}, "{} vertices but the manifest says {}", positions.size(), nv);

    // Pass 1: accumulate B per global vertex; spill the real faces.
    auto accum = TempArray<Accum>(opt.temp_dir, cache(sizeof(Accum)));
    {
        std::vector<Accum> zeros(kBatch);
        for (uint64_t v = 0; v < nv; v += kBatch)
            accum->PushMany(zeros.data(), size_t(std::min<uint64_t>(kBatch, nv - v)));
    }
    auto faces = TempArray<Face>(opt.temp_dir, size_t(1) << 20);
    VertexColorStats st;
    st.vertices = nv;
    ForEachTile(
        view, AllCharts(view), stream::TileParts::Mesh,
        [&](uint32_t c, stream::ChartTile& tile) {
            const auto field = view.Field(c);
            ChartShader shader(tile, *field, view.solution.radiosity, view.scene, view.TilePath(c),
                               view.Seams(c));
            TileColors tc;
            tc.radiosity.resize(tile.position.size());
            for (uint32_t v = 0; v < tile.position.size(); ++v)
                tc.radiosity[v] = shader.Radiosity(shader.AtVertex(v));
            return tc;
        },
        [&](uint32_t c, stream::ChartTile& tile, TileColors& tc) {
            for (size_t v = 0; v < tile.vertex_id.size(); ++v) {
                const uint64_t id = tile.vertex_id[v];
                if (id >= nv)
                    continue;  // a vertex repair added
                Accum a = accum->Get(id);
                a.r += tc.radiosity[v].x;
                a.g += tc.radiosity[v].y;
                a.b += tc.radiosity[v].z;
                a.count += 1;
                accum->Set(id, a);
            }
            for (size_t t = 0; t < tile.triangles.size(); ++t) {
                if (tile.face_id[t] == stream::kNoId) {
                    ++st.hole_fill_faces;
                    continue;
                }
                Face f;
                for (int k = 0; k < 3; ++k)
                    f[size_t(k)] = tile.vertex_id[tile.triangles[t][size_t(k)]];
                if (f[0] >= nv || f[1] >= nv || f[2] >= nv)
                    CorruptError({view.TilePath(c)}, "input triangle {} names a vertex beyond {}",
                                 tile.face_id[t], nv);
                faces->Push(f);
            }
        });
    st.faces = faces->size();

    // Pass 2: stream the PLY.
    io::WriteOptions wo;
    wo.ply_encoding = opt.ply_encoding;
    wo.float_colors = opt.float_colors;
    wo.temp_dir = opt.temp_dir;
    auto out = io::OutputStream::Open(path);
    auto sink = io::MakePlyWriter(*out, wo);
    io::MeshHeader h;
    h.source = view.dir;
    h.vertex_count = nv;
    h.face_count = st.faces;
    h.has_colors = true;
    h.colors_are_float = opt.float_colors;
    h.comments = {opt.float_colors
                      ? "mebake baked vertex colours: linear radiance B/pi x 2^exposure"
                      : "mebake baked vertex colours: sRGB of the tone-mapped radiance B/pi"};
    sink->Begin(h);
    io::VertexBatch vb;
    for (uint64_t first = 0; first < nv; first += kBatch) {
        const size_t n = size_t(std::min<uint64_t>(kBatch, nv - first));
        vb.Clear();
        vb.first = first;
        for (size_t k = 0; k < n; ++k) {
            vb.position.push_back(positions.Get(first + k));
            const Accum a = accum->Get(first + k);
            Vec3f radiance{};
            if (a.count > 0) {
                radiance = Vec3f(a.r, a.g, a.b) / float(a.count) / kPi;
                ++st.referenced;
                if (a.count > 1)
                    ++st.shared;
            }
            if (opt.float_colors) {
                vb.color.push_back(radiance * std::exp2(opt.tone.exposure));
            } else {
                uint8_t rgb[3];
                ToneMapPixel(radiance, opt.tone, rgb);
                vb.color.push_back(Vec3f(rgb[0] / 255.f, rgb[1] / 255.f, rgb[2] / 255.f));
            }
        }
        sink->Vertices(vb);
    }
    io::FaceBatch fb;
    for (uint64_t first = 0; first < st.faces; first += kBatch) {
        const size_t n = size_t(std::min<uint64_t>(kBatch, st.faces - first));
        fb.Clear();
        fb.first = first;
        fb.size.assign(n, 3);
        for (size_t k = 0; k < n; ++k) {
            const Face f = faces->Get(first + k);
            fb.index.insert(fb.index.end(), f.begin(), f.end());
        }
        sink->Faces(fb);
    }
    io::MeshSummary summary;
    summary.vertex_count = nv;
    summary.face_count = st.faces;
    sink->End(summary);
    return st;
}

}  // namespace mebake::output
