// libFuzzer target for the PLY reader: any bytes must either read into a mesh that keeps
// the streaming contract or throw mebake::Error; never crash, hang or over-allocate.
// A mesh that reads is also written back (binary PLY) and must read back identically.
#include "core/check.h"
#include "core/error.h"
#include "io/byte_stream.h"
#include "io/mesh_format.h"
#include "io/mesh_stream.h"

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace {

using namespace mebake;
using namespace mebake::io;

// Keeps what it is given (bounded by the input size: every element costs bytes) and
// checks the contract on the way.
struct Collect : MeshSink {
    MeshHeader header;
    std::vector<Vec3f> position, normal, color;
    std::vector<float> alpha;
    std::vector<Vec2f> uv;
    std::vector<uint32_t> size;
    std::vector<uint64_t> index;
    bool big_polygon = false;

    void Begin(const MeshHeader& h) override { header = h; }
    void Vertices(const VertexBatch& b) override {
        CHECK_EQ(b.first, position.size());
        CHECK(b.normal.empty() || b.normal.size() == b.size());
        CHECK(b.color.empty() || b.color.size() == b.size());
        CHECK(b.alpha.empty() || b.alpha.size() == b.size());
        CHECK(b.uv.empty() || b.uv.size() == b.size());
        for (const Vec3f& p : b.position)
            CHECK(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z));
        for (const Vec3f& c : b.color)
            for (int k = 0; k < 3; ++k)
                CHECK(c[k] >= 0 && c[k] <= 1);
        for (float a : b.alpha)
            CHECK(a >= 0 && a <= 1);
        position.insert(position.end(), b.position.begin(), b.position.end());
        normal.insert(normal.end(), b.normal.begin(), b.normal.end());
        color.insert(color.end(), b.color.begin(), b.color.end());
        alpha.insert(alpha.end(), b.alpha.begin(), b.alpha.end());
        uv.insert(uv.end(), b.uv.begin(), b.uv.end());
    }
    void Faces(const FaceBatch& b) override {
        CHECK_EQ(b.first, size.size());
        uint64_t corners = 0;
        for (uint32_t n : b.size) {
            CHECK_GE(n, 3u);
            big_polygon |= n > 255;
            corners += n;
        }
        CHECK_EQ(corners, b.index.size());
        for (uint64_t v : b.index)
            CHECK_LT(v, header.vertex_count);
        size.insert(size.end(), b.size.begin(), b.size.end());
        index.insert(index.end(), b.index.begin(), b.index.end());
    }
    void End(const MeshSummary& s) override {
        CHECK_EQ(s.vertex_count, position.size());
        CHECK_EQ(s.face_count, size.size());
    }
};

void Read(std::span<const uint8_t> bytes, Collect& sink) {
    auto in = InputStream::FromMemory(bytes, "fuzz.ply");
    ReadOptions opt;
    opt.batch_vertices = 5;  // many small batches exercise the flush paths
    opt.batch_faces = 4;
    ReadPly(*in, sink, opt);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    Collect mesh;
    try {
        Read({data, size}, mesh);
    } catch (const mebake::Error&) {
        return 0;
    }
    if (mesh.big_polygon)
        return 0;  // the writer stores at most 255 corners per face

    // Write it back and read it again: the same mesh, bit for bit.
    std::vector<uint8_t> out_bytes;
    auto out = OutputStream::ToMemory(&out_bytes);
    WriteOptions wopt;
    wopt.float_colors = true;  // colours of any source type survive exactly
    auto writer = MakePlyWriter(*out, wopt);
    MeshHeader h = mesh.header;
    h.vertex_count = mesh.position.size();
    h.face_count = mesh.size.size();
    writer->Begin(h);
    VertexBatch vb;
    vb.position = mesh.position;
    vb.normal = mesh.normal;
    vb.color = mesh.color;
    vb.alpha = mesh.alpha;
    vb.uv = mesh.uv;
    if (vb.size() > 0)
        writer->Vertices(vb);
    FaceBatch fb;
    fb.size = mesh.size;
    fb.index = mesh.index;
    if (fb.count() > 0)
        writer->Faces(fb);
    writer->End({});

    Collect again;
    Read(out_bytes, again);
    CHECK(again.position == mesh.position);
    CHECK(again.normal == mesh.normal);
    CHECK(again.color == mesh.color);
    CHECK(again.alpha == mesh.alpha);
    CHECK(again.uv == mesh.uv);
    CHECK(again.size == mesh.size);
    CHECK(again.index == mesh.index);
    return 0;
}
