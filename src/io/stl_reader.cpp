// Streaming STL reader, binary and ASCII (3D Systems, "StereoLithography Interface
// Specification", 1988). STL stores unshared triangles: each facet becomes 3 new vertices
// and one triangle; welding coincident vertices is ingest's job. Facet normals are read
// past (they are often stale or zero) and the 16-bit attribute word is ignored.
//
// Binary: an 80-byte header, a uint32 facet count n, n 50-byte records. When the
// stream's size is known the file must be exactly 84 + 50 n bytes; on a pipe the records
// are read until n are met (truncation and trailing bytes are errors).
// ASCII vs binary: a file is ASCII when it starts with "solid" and its first KiB is
// text; many binary exporters also begin the header with "solid", but their size
// matches 84 + 50 n and their records hold control bytes, either of which means binary.
// ASCII keywords are matched case-insensitively and may be split across lines; several
// solids in one file are read one after another.
#include "core/error.h"
#include "io/batch_emitter.h"
#include "io/mesh_format.h"
#include "io/text_parse.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <string>
#include <string_view>

namespace mebake::io {

namespace {

static_assert(std::endian::native == std::endian::little, "STL reader assumes little endian");

constexpr size_t kHeaderBytes = 84;
constexpr size_t kRecordBytes = 50;
constexpr size_t kSniffBytes = 1024;

bool IsTextByte(uint8_t c) {
    return c >= 0x20 || c == '\t' || c == '\n' || c == '\r' || c == '\f' || c == '\v';
}

bool LooksAscii(InputStream& in) {
    auto head = in.Peek(kSniffBytes);
    size_t i = 0;
    while (i < head.size() && (head[i] == '\n' || IsTextSpace(char(head[i]))))
        ++i;
    std::string_view start(reinterpret_cast<const char*>(head.data()) + i,
                           std::min<size_t>(5, head.size() - i));
    if (!EqualsNoCase(start, "solid"))
        return false;
    if (head.size() >= kHeaderBytes && in.size_hint() > in.offset()) {
        uint32_t n = 0;
        std::memcpy(&n, head.data() + 80, 4);
        if (in.size_hint() - in.offset() == kHeaderBytes + kRecordBytes * uint64_t(n))
            return false;
    }
    return std::all_of(head.begin(), head.begin() + std::min(head.size(), kSniffBytes), IsTextByte);
}

class StlSink {
public:
    StlSink(MeshSink& sink, const ReadOptions& opt)
        : sink_(sink),
          batch_vertices_(std::max<size_t>(opt.batch_vertices, 3)),
          batch_faces_(std::max<size_t>(opt.batch_faces, 1)) {}

    void Begin(const MeshHeader& header) { emit_.Begin(header); }

    void Facet(const Vec3f& a, const Vec3f& b, const Vec3f& c) {
        uint64_t v = vertex_count_;
        verts_.position.push_back(a);
        verts_.position.push_back(b);
        verts_.position.push_back(c);
        vertex_count_ += 3;
        faces_.size.push_back(3);
        faces_.index.insert(faces_.index.end(), {v, v + 1, v + 2});
        ++face_count_;
        if (faces_.count() >= batch_faces_) {
            FlushFaces();
        } else if (verts_.size() + 3 > batch_vertices_) {
            FlushVertices();
        }
    }

    void End(uint64_t bytes_read) {
        FlushFaces();
        MeshSummary summary;
        summary.vertex_count = vertex_count_;
        summary.face_count = face_count_;
        summary.bytes_read = bytes_read;
        sink_.End(summary);
    }

    uint64_t face_count() const { return face_count_; }

private:
    void FlushVertices() { emit_.FlushVertices(verts_); }
    // A facet's vertices always go out before the facet itself.
    void FlushFaces() { emit_.FlushFaces(verts_, faces_); }

    MeshSink& sink_;
    BatchEmitter emit_{sink_};
    size_t batch_vertices_, batch_faces_;
    VertexBatch verts_;
    FaceBatch faces_;
    uint64_t vertex_count_ = 0, face_count_ = 0;
};

MeshHeader StlHeader(const InputStream& in, const char* encoding) {
    MeshHeader h;
    h.source = in.name();
    h.format = MeshFormat::Stl;
    h.encoding = encoding;
    return h;
}

void ReadBinaryStl(InputStream& in, MeshSink& sink, const ReadOptions& opt) {
    const uint64_t start = in.offset();
    const uint64_t total = in.size_hint() > start ? in.size_hint() - start : 0;
    uint8_t head[kHeaderBytes];
    size_t got = in.Read(head, kHeaderBytes);
    if (got == 0)
        InputError({in.name(), start}, "empty file; expected an STL mesh");
    if (got < kHeaderBytes) {
        InputError({in.name(), start + got},
                   "file ends after {} bytes; expected a binary STL 80-byte header and a "
                   "uint32 facet count",
                   got);
    }
    uint32_t n = 0;
    std::memcpy(&n, head + 80, 4);
    const uint64_t expected = kHeaderBytes + kRecordBytes * uint64_t(n);
    if (total != 0 && total != expected) {
        InputError({in.name(), start + 80},
                   "binary STL header says {} facets ({} bytes) but the file has {} bytes; "
                   "expected 84 + 50 * facets bytes (truncated or not a binary STL?)",
                   n, expected, total);
    }

    MeshHeader header = StlHeader(in, "binary_little_endian");
    header.vertex_count = 3 * uint64_t(n);
    header.face_count = n;
    std::string_view text(reinterpret_cast<const char*>(head), 80);
    text = TrimText(text.substr(0, text.find('\0')));
    if (!text.empty() && std::all_of(text.begin(), text.end(), [](char c) {
            return static_cast<unsigned char>(c) >= 0x20 && c != 0x7f;
        }))
        header.comments.emplace_back(text);

    StlSink out(sink, opt);
    out.Begin(header);
    uint64_t done = 0;
    while (done < n) {
        auto avail = in.Peek(InputStream::kMaxPeek / kRecordBytes * kRecordBytes);
        uint64_t k = std::min<uint64_t>(avail.size() / kRecordBytes, n - done);
        if (k == 0) {
            InputError({in.name(), in.offset()},
                       "binary STL ends after {} of {} facets; expected {} more bytes", done, n,
                       (n - done) * kRecordBytes - avail.size());
        }
        for (uint64_t r = 0; r < k; ++r) {
            const uint8_t* rec = avail.data() + r * kRecordBytes;
            float f[9];
            std::memcpy(f, rec + 12, sizeof(f));  // skip the facet normal
            for (float x : f) {
                if (!std::isfinite(x)) {
                    InputError({in.name(), in.offset() + r * kRecordBytes + 12},
                               "facet {} has a non-finite vertex coordinate; expected finite "
                               "floats",
                               done + r);
                }
            }
            out.Facet({f[0], f[1], f[2]}, {f[3], f[4], f[5]}, {f[6], f[7], f[8]});
        }
        in.Skip(size_t(k * kRecordBytes));
        done += k;
    }
    if (!in.AtEnd()) {
        InputError({in.name(), in.offset()},
                   "bytes after the {} facets the binary STL header announced", n);
    }
    out.End(in.offset() - start);
}

// Whitespace-separated tokens across lines, for ASCII STL.
class StlTokens {
public:
    explicit StlTokens(InputStream& in) : lines_(in) {}

    std::string_view Next() {
        for (;;) {
            std::string_view tok = NextToken(rest_);
            if (!tok.empty())
                return tok;
            if (!lines_.Next(rest_))
                return {};
        }
    }
    // The rest of the current line (a solid's name), consumed.
    std::string_view RestOfLine() {
        std::string_view r = TrimText(rest_);
        rest_ = {};
        return r;
    }
    FileLoc Loc() const { return lines_.Loc(); }
    uint64_t offset() const { return lines_.offset(); }

private:
    TextLineReader lines_;
    std::string_view rest_;
};

class AsciiStlReader {
public:
    AsciiStlReader(InputStream& in, MeshSink& sink, const ReadOptions& opt)
        : in_(in), tokens_(in), out_(sink, opt), start_(in.offset()) {}

    void Run() {
        MeshHeader header = StlHeader(in_, "ascii");
        Expect("solid", "at the start of an ASCII STL");
        if (auto name = tokens_.RestOfLine(); !name.empty())
            header.comments.emplace_back(name);
        out_.Begin(header);
        for (;;) {
            std::string_view tok = tokens_.Next();
            if (tok.empty())
                Fail("file ends inside a solid; expected 'facet' or 'endsolid'");
            if (EqualsNoCase(tok, "facet")) {
                Facet();
            } else if (EqualsNoCase(tok, "endsolid")) {
                tokens_.RestOfLine();
                std::string_view next = tokens_.Next();
                if (next.empty())
                    break;
                if (!EqualsNoCase(next, "solid"))
                    Fail("unexpected {} after 'endsolid'; expected the end or 'solid'",
                         QuoteToken(next));
                tokens_.RestOfLine();
            } else {
                Fail("unexpected {}; expected 'facet' or 'endsolid'", QuoteToken(tok));
            }
        }
        out_.End(tokens_.offset() - start_);
    }

private:
    template <typename... Args>
    [[noreturn]] void Fail(fmt::format_string<Args...> f, Args&&... args) {
        InputError(tokens_.Loc(), f, std::forward<Args>(args)...);
    }

    void Expect(const char* word, const char* where) {
        std::string_view tok = tokens_.Next();
        if (tok.empty())
            Fail("file ends; expected '{}' {}", word, where);
        if (!EqualsNoCase(tok, word))
            Fail("unexpected {}; expected '{}' {}", QuoteToken(tok), word, where);
    }

    float Number(const char* what, bool finite) {
        std::string_view tok = tokens_.Next();
        if (tok.empty())
            Fail("file ends; expected a {}", what);
        float v = 0;
        switch (ParseTextFloat(tok, v)) {
        case NumberStatus::Ok:
            return v;
        case NumberStatus::NotFinite:
            if (!finite)
                return 0;
            Fail("{} {} is not finite; expected a finite number", what, QuoteToken(tok));
        case NumberStatus::OutOfRange:
            if (!finite)
                return 0;
            Fail("{} {} is out of float range; expected a number", what, QuoteToken(tok));
        case NumberStatus::Malformed:
            break;
        }
        Fail("malformed number {}; expected a {}", QuoteToken(tok), what);
    }

    void Facet() {
        // Normals are ignored, so a "nan" one (common for slivers) is allowed.
        Expect("normal", "after 'facet'");
        for (int i = 0; i < 3; ++i)
            Number("facet normal component", false);
        Expect("outer", "in a facet");
        Expect("loop", "after 'outer'");
        Vec3f p[3];
        for (auto& v : p) {
            Expect("vertex", "(a facet has 3 vertices)");
            for (int i = 0; i < 3; ++i)
                v[i] = Number("vertex coordinate", true);
        }
        Expect("endloop", "after 3 vertices (STL facets are triangles)");
        Expect("endfacet", "after 'endloop'");
        out_.Facet(p[0], p[1], p[2]);
    }

    InputStream& in_;
    StlTokens tokens_;
    StlSink out_;
    uint64_t start_;
};

}  // namespace

void ReadStl(InputStream& in, MeshSink& sink, const ReadOptions& opt) {
    if (LooksAscii(in)) {
        AsciiStlReader(in, sink, opt).Run();
    } else {
        ReadBinaryStl(in, sink, opt);
    }
}

}  // namespace mebake::io
