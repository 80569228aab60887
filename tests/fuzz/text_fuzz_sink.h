// Shared by the mesh reader fuzzers: a sink that touches every delivered value and
// traps on any break of the streaming contract (io/mesh_stream.h), so the fuzzer finds
// contract bugs as well as crashes. Input errors (mebake::Error) are the expected outcome
// for most inputs and are swallowed.
#pragma once

#include "core/error.h"
#include "io/byte_stream.h"
#include "io/mesh_stream.h"

#include <cstdint>
#include <cstdlib>

namespace mebake::io {

class FuzzSink : public MeshSink {
public:
    void Begin(const MeshHeader& h) override {
        Require(!begun_);
        begun_ = true;
        header_ = h;
    }
    void Vertices(const VertexBatch& b) override {
        Require(begun_ && !ended_ && b.first == vertices_ && b.size() > 0);
        Require(b.normal.size() == (header_.has_normals ? b.size() : 0));
        Require(b.color.size() == (header_.has_colors ? b.size() : 0));
        Require(b.alpha.size() == (header_.has_alpha ? b.size() : 0));
        Require(b.uv.size() == (header_.has_uvs ? b.size() : 0));
        for (const auto& p : b.position)
            sum_ += double(p.x) + p.y + p.z;
        for (const auto& c : b.color)
            Require(c.x >= 0 && c.x <= 1 && c.y >= 0 && c.y <= 1 && c.z >= 0 && c.z <= 1);
        for (float a : b.alpha)
            Require(a >= 0 && a <= 1);
        vertices_ += b.size();
    }
    void Faces(const FaceBatch& b) override {
        Require(begun_ && !ended_ && b.first == faces_ && b.count() > 0);
        Require(b.material.empty() || b.material.size() == b.count());
        uint64_t corners = 0;
        for (uint32_t n : b.size) {
            Require(n >= 3);
            corners += n;
        }
        Require(corners == b.index.size());
        // OBJ, OFF and STL deliver a face's vertices before the face.
        for (uint64_t i : b.index)
            Require(i < vertices_);
        for (uint32_t m : b.material)
            max_material_ = m > max_material_ ? m : max_material_;
        faces_ += b.count();
    }
    void End(const MeshSummary& s) override {
        Require(begun_ && !ended_);
        ended_ = true;
        Require(s.vertex_count == vertices_ && s.face_count == faces_);
        Require(faces_ == 0 || s.materials.empty() || max_material_ < s.materials.size());
    }

    double sum() const { return sum_; }

private:
    static void Require(bool ok) {
        if (!ok)
            __builtin_trap();
    }

    MeshHeader header_;
    bool begun_ = false, ended_ = false;
    uint64_t vertices_ = 0, faces_ = 0;
    uint32_t max_material_ = 0;
    double sum_ = 0;
};

// Runs `reader` over the bytes with small batches (so flushing paths run too).
template <typename Reader>
void FuzzRead(Reader reader, const uint8_t* data, size_t size) {
    auto in = InputStream::FromMemory({data, size}, "fuzz");
    FuzzSink sink;
    ReadOptions opt;
    opt.batch_vertices = 7;
    opt.batch_faces = 5;
    try {
        reader(*in, sink, opt);
    } catch (const Error&) {
    }
    volatile double keep = sink.sum();
    (void)keep;
}

}  // namespace mebake::io
