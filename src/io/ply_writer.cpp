// Streaming PLY writer (Turk 1994, "The PLY Polygon File Format"): ascii or binary
// little/big-endian, with the normals, colours and uvs the input has and the options
// allow. Output layout:
//   element vertex N: float x y z [float nx ny nz] [uchar|float red green blue [alpha]]
//                     [float s t]
//   element face M:   list uchar int vertex_indices   ("uint" above 2^31-1 vertices)
// Polygons are written as they come (quads stay quads); uvs are named `s t`, the names
// the original PLY tools use. ASCII floats use fmt's shortest round-trip form, so a
// float read back is bit-identical.
//
// A PLY header needs both counts first. When the source header gives them (PLY, OFF) the
// writer streams: header at Begin, vertex records straight through, faces too unless they
// arrive before the last vertex (a PLY whose face element comes first), in which case
// faces are encoded into a spill file and appended at End. When counts are unknown (OBJ,
// tristrips) vertices and faces are both encoded into spill files and the header is
// written at End. Spill files live in WriteOptions::temp_dir, $TMPDIR or /tmp and are
// unlinked as soon as they are created, so nothing is left behind on a crash.
#include "core/check.h"
#include "core/error.h"
#include "io/mesh_format.h"
#include "io/spill_file.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fcntl.h>
#include <fmt/compile.h>
#include <iterator>
#include <memory>
#include <unistd.h>

namespace mebake::io {
namespace {


// A header text line: line breaks in the source would end it early.
std::string OneLine(const std::string& s) {
    std::string r = s;
    for (char& c : r)
        if (c == '\n' || c == '\r')
            c = ' ';
    return r;
}

uint8_t ToUchar(float c) {
    if (!(c > 0.0f))
        return 0;  // also NaN
    if (c >= 1.0f)
        return 255;
    return uint8_t(std::lround(c * 255.0f));
}

class PlyWriter final : public MeshSink {
public:
    PlyWriter(OutputStream& out, const WriteOptions& opt) : out_(out), opt_(opt) {}

    void Begin(const MeshHeader& h) override {
        CHECK(!begun_);
        begun_ = true;
        comments_ = h.comments;
        obj_info_ = h.obj_info;
        normals_ = h.has_normals && opt_.normals;
        colors_ = h.has_colors && opt_.colors;
        alpha_ = colors_ && h.has_alpha;
        uvs_ = h.has_uvs && opt_.uvs;
        swap_ = (opt_.ply_encoding == PlyEncoding::BinaryBigEndian) !=
                (std::endian::native == std::endian::big);
        if (h.vertex_count != kUnknownCount && h.face_count != kUnknownCount) {
            direct_ = true;
            header_vertices_ = h.vertex_count;
            header_faces_ = h.face_count;
            WriteHeader(header_vertices_, header_faces_);
        } else {
            vertex_spill_ = std::make_unique<SpillFile>(opt_.temp_dir, "PLY writer");
        }
    }

    void Vertices(const VertexBatch& b) override {
        const size_t n = b.size();
        CHECK(b.normal.empty() || b.normal.size() == n);
        CHECK(b.color.empty() || b.color.size() == n);
        CHECK(b.alpha.empty() || b.alpha.size() == n);
        CHECK(b.uv.empty() || b.uv.size() == n);
        if (direct_ && vertices_ + n > header_vertices_)
            InputError({out_.name()},
                       "the mesh delivers more vertices than the {} its header declared",
                       header_vertices_);
        scratch_.clear();
        if (opt_.ply_encoding == PlyEncoding::Ascii) {
            EncodeVerticesAscii(b);
        } else {
            EncodeVerticesBinary(b);
        }
        if (direct_) {
            out_.Write(scratch_.data(), scratch_.size());
        } else {
            vertex_spill_->Write(scratch_.data(), scratch_.size());
        }
        vertices_ += n;
    }

    void Faces(const FaceBatch& b) override {
        // In direct mode a face must wait for the last vertex record to be written.
        const bool spill = !direct_ || face_spill_ != nullptr || vertices_ < header_vertices_;
        if (spill && face_spill_ == nullptr)
            face_spill_ = std::make_unique<SpillFile>(opt_.temp_dir, "PLY writer");
        if (direct_ && faces_ + b.count() > header_faces_)
            InputError({out_.name()},
                       "the mesh delivers more faces than the {} its header declared",
                       header_faces_);
        scratch_.clear();
        const bool ascii = opt_.ply_encoding == PlyEncoding::Ascii;
        size_t at = 0;
        for (size_t f = 0; f < b.count(); ++f) {
            const uint32_t n = b.size[f];
            CHECK_LE(at + n, b.index.size());
            if (n > 255)
                InputError({out_.name()},
                           "face {} has {} corners; PLY output stores at most 255 per face "
                           "(list uchar), triangulate first",
                           faces_ + f, n);
            const uint64_t* idx = b.index.data() + at;
            for (uint32_t j = 0; j < n; ++j) {
                if (idx[j] > UINT32_MAX)
                    InputError({out_.name()},
                               "face {}: vertex index {} does not fit PLY's 32-bit indices",
                               faces_ + f, idx[j]);
                if (direct_ && idx[j] >= header_vertices_)
                    InputError({out_.name()},
                               "face {}: vertex index {} out of range, the mesh has {} vertices",
                               faces_ + f, idx[j], header_vertices_);
                max_index_ = std::max(max_index_, idx[j]);
                any_index_ = true;
            }
            if (ascii) {
                auto o = fmt::appender(scratch_);
                fmt::format_to(o, FMT_COMPILE("{}"), n);
                for (uint32_t j = 0; j < n; ++j)
                    fmt::format_to(o, FMT_COMPILE(" {}"), idx[j]);
                scratch_.push_back('\n');
            } else {
                const size_t base = scratch_.size();
                scratch_.resize(base + 1 + 4 * size_t(n));
                uint8_t* p = reinterpret_cast<uint8_t*>(scratch_.data()) + base;
                *p++ = uint8_t(n);
                for (uint32_t j = 0; j < n; ++j) {
                    uint32_t v = uint32_t(idx[j]);
                    if (swap_)
                        v = __builtin_bswap32(v);
                    std::memcpy(p, &v, 4);
                    p += 4;
                }
            }
            at += n;
        }
        if (spill) {
            face_spill_->Write(scratch_.data(), scratch_.size());
        } else {
            out_.Write(scratch_.data(), scratch_.size());
        }
        faces_ += b.count();
    }

    void End(const MeshSummary& /*summary*/) override {
        CHECK(begun_);
        if (direct_) {
            if (vertices_ != header_vertices_)
                InputError({out_.name()},
                           "the mesh delivered {} vertices but its header declared {}; the PLY "
                           "written would be invalid",
                           vertices_, header_vertices_);
        } else {
            WriteHeader(vertices_, faces_);
            if (vertex_spill_) vertex_spill_->CopyTo(out_);
        }
        if (any_index_ && max_index_ >= vertices_)
            InputError({out_.name()}, "a face names vertex {} but the mesh has only {} vertices",
                       max_index_, vertices_);
        if (face_spill_ != nullptr)
            face_spill_->CopyTo(out_);
        if (direct_ && faces_ != header_faces_)
            InputError({out_.name()},
                       "the mesh delivered {} faces but its header declared {}; the PLY written "
                       "would be invalid",
                       faces_, header_faces_);
        out_.Commit();
    }

private:
    void WriteHeader(uint64_t nv, uint64_t nf) {
        std::string h = "ply\n";
        switch (opt_.ply_encoding) {
        case PlyEncoding::Ascii:
            h += "format ascii 1.0\n";
            break;
        case PlyEncoding::BinaryLittleEndian:
            h += "format binary_little_endian 1.0\n";
            break;
        case PlyEncoding::BinaryBigEndian:
            h += "format binary_big_endian 1.0\n";
            break;
        }
        for (const auto& c : comments_)
            h += fmt::format("comment {}\n", OneLine(c));
        for (const auto& c : obj_info_)
            h += fmt::format("obj_info {}\n", OneLine(c));
        h += fmt::format("element vertex {}\n", nv);
        h += "property float x\nproperty float y\nproperty float z\n";
        if (normals_)
            h += "property float nx\nproperty float ny\nproperty float nz\n";
        if (colors_) {
            const char* t = opt_.float_colors ? "float" : "uchar";
            h += fmt::format("property {0} red\nproperty {0} green\nproperty {0} blue\n", t);
            if (alpha_)
                h += fmt::format("property {} alpha\n", t);
        }
        if (uvs_)
            h += "property float s\nproperty float t\n";
        h += fmt::format("element face {}\n", nf);
        h += fmt::format("property list uchar {} vertex_indices\n",
                         nv > uint64_t(INT32_MAX) ? "uint" : "int");
        h += "end_header\n";
        out_.Write(h);
    }

    void PutF32(uint8_t*& p, float f) {
        uint32_t v = std::bit_cast<uint32_t>(f);
        if (swap_)
            v = __builtin_bswap32(v);
        std::memcpy(p, &v, 4);
        p += 4;
    }

    void EncodeVerticesBinary(const VertexBatch& b) {
        const size_t n = b.size();
        const size_t color_bytes = opt_.float_colors ? 4 : 1;
        const size_t rec = 12 + (normals_ ? 12 : 0) +
                           (colors_ ? (alpha_ ? 4 : 3) * color_bytes : 0) + (uvs_ ? 8 : 0);
        scratch_.resize(n * rec);
        uint8_t* p = reinterpret_cast<uint8_t*>(scratch_.data());
        const bool has_n = !b.normal.empty(), has_c = !b.color.empty(), has_a = !b.alpha.empty(),
                   has_uv = !b.uv.empty();
        for (size_t i = 0; i < n; ++i) {
            const Vec3f& v = b.position[i];
            PutF32(p, v.x);
            PutF32(p, v.y);
            PutF32(p, v.z);
            if (normals_) {
                const Vec3f nn = has_n ? b.normal[i] : Vec3f{};
                PutF32(p, nn.x);
                PutF32(p, nn.y);
                PutF32(p, nn.z);
            }
            if (colors_) {
                const Vec3f c = has_c ? b.color[i] : Vec3f{1, 1, 1};
                const float a = has_a ? b.alpha[i] : 1.0f;
                if (opt_.float_colors) {
                    PutF32(p, c.x);
                    PutF32(p, c.y);
                    PutF32(p, c.z);
                    if (alpha_)
                        PutF32(p, a);
                } else {
                    *p++ = ToUchar(c.x);
                    *p++ = ToUchar(c.y);
                    *p++ = ToUchar(c.z);
                    if (alpha_)
                        *p++ = ToUchar(a);
                }
            }
            if (uvs_) {
                const Vec2f t = has_uv ? b.uv[i] : Vec2f{};
                PutF32(p, t.x);
                PutF32(p, t.y);
            }
        }
    }

    void EncodeVerticesAscii(const VertexBatch& b) {
        const size_t n = b.size();
        const bool has_n = !b.normal.empty(), has_c = !b.color.empty(), has_a = !b.alpha.empty(),
                   has_uv = !b.uv.empty();
        auto o = fmt::appender(scratch_);
        for (size_t i = 0; i < n; ++i) {
            const Vec3f& v = b.position[i];
            fmt::format_to(o, FMT_COMPILE("{} {} {}"), v.x, v.y, v.z);
            if (normals_) {
                const Vec3f nn = has_n ? b.normal[i] : Vec3f{};
                fmt::format_to(o, FMT_COMPILE(" {} {} {}"), nn.x, nn.y, nn.z);
            }
            if (colors_) {
                const Vec3f c = has_c ? b.color[i] : Vec3f{1, 1, 1};
                const float a = has_a ? b.alpha[i] : 1.0f;
                if (opt_.float_colors) {
                    fmt::format_to(o, FMT_COMPILE(" {} {} {}"), c.x, c.y, c.z);
                    if (alpha_)
                        fmt::format_to(o, FMT_COMPILE(" {}"), a);
                } else {
                    fmt::format_to(o, FMT_COMPILE(" {} {} {}"), ToUchar(c.x), ToUchar(c.y),
                                   ToUchar(c.z));
                    if (alpha_)
                        fmt::format_to(o, FMT_COMPILE(" {}"), ToUchar(a));
                }
            }
            if (uvs_) {
                const Vec2f t = has_uv ? b.uv[i] : Vec2f{};
                fmt::format_to(o, FMT_COMPILE(" {} {}"), t.x, t.y);
            }
            scratch_.push_back('\n');
        }
    }

    OutputStream& out_;
    WriteOptions opt_;
    std::vector<std::string> comments_, obj_info_;
    bool begun_ = false;
    bool normals_ = false, colors_ = false, alpha_ = false, uvs_ = false, swap_ = false;
    bool direct_ = false;
    uint64_t header_vertices_ = 0, header_faces_ = 0;
    uint64_t vertices_ = 0, faces_ = 0;
    uint64_t max_index_ = 0;
    bool any_index_ = false;
    std::unique_ptr<SpillFile> vertex_spill_, face_spill_;
    fmt::memory_buffer scratch_;
};

}  // namespace

std::unique_ptr<MeshSink> MakePlyWriter(OutputStream& out, const WriteOptions& opt) {
    return std::make_unique<PlyWriter>(out, opt);
}

}  // namespace mebake::io
