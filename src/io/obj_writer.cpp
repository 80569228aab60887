// Streaming Wavefront OBJ writer: each batch is formatted as it arrives, so memory does
// not grow with the mesh. Floats are printed shortest-round-trip (fmt "{}", Dragonbox),
// so reading the file back gives the same bits.
//
// What is written: the header comments as '#' lines; "v x y z [r g b]" per vertex, with
// "vt u v" and "vn x y z" lines right after it when the mesh has per-vertex uvs/normals
// (so the k-th v, vt and vn line all belong to vertex k and corners are written
// "i/i/i", "i//i" or "i/i"); polygons as they are, 1-based.
// What is not: materials and groups. FaceBatch::material holds indices whose names only
// arrive with MeshSummary at End(), after the faces have been written, so the writer
// drops them rather than inventing names (a PLY writer drops them too). Alpha is dropped.
// Faces that name a vertex not written yet (only possible from a PLY whose face element
// precedes its vertex element) are spilled to a temporary file and appended at the end,
// since OBJ forbids forward references.
#include "core/check.h"
#include "core/error.h"
#include "io/mesh_format.h"
#include "io/spill_file.h"

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <fcntl.h>
#include <string>
#include <unistd.h>
#include <vector>

namespace mebake::io {

namespace {

constexpr size_t kFlushBytes = size_t(1) << 20;


class ObjWriter final : public MeshSink {
public:
    ObjWriter(OutputStream& out, const WriteOptions& opt) : out_(out), opt_(opt) {}

    void Begin(const MeshHeader& header) override {
        normals_ = opt_.normals && header.has_normals;
        colors_ = opt_.colors && header.has_colors;
        uvs_ = opt_.uvs && header.has_uvs;
        for (const auto& c : header.comments) {
            // A comment must stay one line per '#'.
            size_t at = 0;
            do {
                size_t nl = c.find_first_of("\r\n", at);
                std::string_view part = std::string_view(c).substr(at, nl - at);
                fmt::format_to(std::back_inserter(buf_), "#{}{}\n", part.empty() ? "" : " ", part);
                at = nl == std::string::npos ? nl : nl + 1;
            } while (at != std::string::npos);
        }
    }

    void Vertices(const VertexBatch& b) override {
        CHECK_EQ(b.first, vertices_);
        if (normals_)
            CHECK_EQ(b.normal.size(), b.size());
        if (colors_)
            CHECK_EQ(b.color.size(), b.size());
        if (uvs_)
            CHECK_EQ(b.uv.size(), b.size());
        auto it = std::back_inserter(buf_);
        for (size_t i = 0; i < b.size(); ++i) {
            const Vec3f& p = b.position[i];
            if (colors_) {
                const Vec3f& c = b.color[i];
                fmt::format_to(it, "v {} {} {} {} {} {}\n", p.x, p.y, p.z, c.x, c.y, c.z);
            } else {
                fmt::format_to(it, "v {} {} {}\n", p.x, p.y, p.z);
            }
            if (uvs_)
                fmt::format_to(it, "vt {} {}\n", b.uv[i].x, b.uv[i].y);
            if (normals_) {
                const Vec3f& n = b.normal[i];
                fmt::format_to(it, "vn {} {} {}\n", n.x, n.y, n.z);
            }
            if (buf_.size() >= kFlushBytes)
                FlushToOutput();
        }
        vertices_ += b.size();
        FlushToOutput();
    }

    void Faces(const FaceBatch& b) override {
        CHECK_EQ(b.first, faces_);
        uint64_t max_index = 0;
        for (uint64_t i : b.index)
            max_index = std::max(max_index, i);
        if (!spill_ && !b.index.empty() && max_index >= vertices_) {
            FlushToOutput();
            spill_ = std::make_unique<SpillFile>(opt_.temp_dir, "OBJ writer");
        }
        if (spill_)
            max_spilled_ = std::max(max_spilled_, b.index.empty() ? 0 : max_index);
        auto it = std::back_inserter(buf_);
        size_t at = 0;
        for (uint32_t n : b.size) {
            CHECK_LE(at + n, b.index.size());
            buf_.push_back('f');
            for (uint32_t k = 0; k < n; ++k) {
                uint64_t v = b.index[at + k] + 1;
                if (uvs_ && normals_) {
                    fmt::format_to(it, " {}/{}/{}", v, v, v);
                } else if (normals_) {
                    fmt::format_to(it, " {}//{}", v, v);
                } else if (uvs_) {
                    fmt::format_to(it, " {}/{}", v, v);
                } else {
                    fmt::format_to(it, " {}", v);
                }
            }
            buf_.push_back('\n');
            at += n;
            if (buf_.size() >= kFlushBytes)
                Flush();
        }
        CHECK_EQ(at, b.index.size());
        faces_ += b.count();
        Flush();
    }

    void End(const MeshSummary&) override {
        FlushToOutput();
        if (spill_) {
            CHECK_LT(max_spilled_, vertices_);
            spill_->CopyTo(out_);
            spill_.reset();
        }
        out_.Commit();
    }

private:
    // Face text goes to the spill once spilling has begun, to keep the face order.
    void Flush() {
        if (spill_) {
            spill_->Write(buf_.data(), buf_.size());
            buf_.clear();
        } else {
            FlushToOutput();
        }
    }
    void FlushToOutput() {
        out_.Write(buf_.data(), buf_.size());
        buf_.clear();
    }

    OutputStream& out_;
    WriteOptions opt_;
    fmt::memory_buffer buf_;
    bool normals_ = false, colors_ = false, uvs_ = false;
    uint64_t vertices_ = 0, faces_ = 0;
    std::unique_ptr<SpillFile> spill_;
    uint64_t max_spilled_ = 0;
};

}  // namespace

std::unique_ptr<MeshSink> MakeObjWriter(OutputStream& out, const WriteOptions& opt) {
    return std::make_unique<ObjWriter>(out, opt);
}

}  // namespace mebake::io
