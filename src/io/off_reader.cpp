// Streaming OFF reader (Geomview Object File Format, "OFF" in the Geomview manual,
// section 4.2.2): a keyword line [ST][C][N]OFF, a counts line "nv nf [ne]", nv vertex
// lines, nf polygon lines "n i0 ... i(n-1) [colour]". One pass, memory bounded by the
// batch sizes; header counts are validated against the data but never used to size
// anything.
//
// Rules where the format leaves a choice:
//  - Vertex lines are "x y z [nx ny nz] [r g b [a]] [s t]" as the keyword announces.
//    A colour written only with integers is 0..255, else 0..1 floats (both clamped);
//    a C vertex without a colour gets white. header.has_alpha / colors_are_float follow
//    the first vertex; a later vertex lacking alpha gets 1.
//  - Per-face colours are read past and ignored. Counts may share the keyword line
//    ("OFF 8 6 12"); the keyword may be missing when the file starts with the counts.
//  - '#' starts a comment anywhere; comments before the counts go to header.comments.
//  - 4OFF, nOFF and binary OFF are rejected as unsupported.
#include "core/error.h"
#include "io/batch_emitter.h"
#include "io/mesh_format.h"
#include "io/text_parse.h"

#include <algorithm>
#include <string>
#include <string_view>

namespace mebake::io {

namespace {

constexpr size_t kMaxCorners = size_t(1) << 16;
constexpr size_t kMaxLeadingComments = 1024;
constexpr size_t kMaxCommentBytes = size_t(64) << 10;

bool IsIntegerToken(std::string_view tok) {
    return tok.find_first_of(".eEnN") == std::string_view::npos;
}

class OffReader {
public:
    OffReader(InputStream& in, MeshSink& sink, const ReadOptions& opt)
        : lines_(in),
          sink_(sink),
          batch_vertices_(std::max<size_t>(opt.batch_vertices, 1)),
          batch_faces_(std::max<size_t>(opt.batch_faces, 1)),
          batch_corners_(std::max(batch_faces_ * 4, kMaxCorners)) {
        header_.source = in.name();
        header_.format = MeshFormat::Off;
        header_.encoding = "ascii";
    }

    void Run() {
        ReadHeader();
        for (uint64_t i = 0; i < vertex_total_; ++i)
            Vertex(NextData("vertex", i));
        FlushVertices();
        for (uint64_t i = 0; i < face_total_; ++i)
            Face(NextData("face", i));
        FlushFaces();
        summary_.vertex_count = vertex_total_;
        summary_.face_count = face_total_;
        summary_.bytes_read = lines_.offset();
        sink_.End(summary_);
    }

private:
    template <typename... Args>
    [[noreturn]] void Fail(fmt::format_string<Args...> f, Args&&... args) {
        InputError(lines_.Loc(), f, std::forward<Args>(args)...);
    }

    // The next line with data, comment stripped; collects leading comments if asked.
    bool NextLine(std::string_view& rest, bool collect_comments) {
        std::string_view line;
        while (lines_.Next(line)) {
            std::string_view t = TrimText(line);
            if (!t.empty() && t.front() == '#') {
                std::string_view text = TrimText(t.substr(1));
                if (collect_comments && header_.comments.size() < kMaxLeadingComments &&
                    comment_bytes_ + text.size() <= kMaxCommentBytes) {
                    comment_bytes_ += text.size();
                    header_.comments.emplace_back(text);
                }
                continue;
            }
            t = TrimText(StripComment(t));
            if (t.empty())
                continue;
            rest = t;
            return true;
        }
        return false;
    }

    std::string_view NextData(const char* what, uint64_t i) {
        std::string_view rest;
        if (!NextLine(rest, false)) {
            InputError({lines_.stream().name(), lines_.offset()},
                       "file ends after {} of {} {} announced by the header", i,
                       what[0] == 'v' ? vertex_total_ : face_total_,
                       what[0] == 'v' ? "vertices" : "faces");
        }
        return rest;
    }

    uint64_t Count(std::string_view tok, const char* what) {
        int64_t v = 0;
        if (!ParseTextInt(tok, v) || v < 0)
            Fail("{} count {} is not a non-negative integer", what, QuoteToken(tok));
        return uint64_t(v);
    }

    void ReadHeader() {
        std::string_view rest;
        if (!NextLine(rest, true)) {
            FileLoc at{lines_.stream().name(), lines_.offset()};
            if (lines_.offset() == 0)
                InputError(at, "empty file; expected an OFF header");
            InputError(at, "no OFF header; expected 'OFF' and counts");
        }
        std::string_view probe = rest;
        std::string_view kw = NextToken(probe);
        int64_t dummy = 0;
        if (!ParseTextInt(kw, dummy)) {
            ParseKeyword(kw);
            rest = probe;
            if (auto more = NextToken(probe); more == "BINARY" || more == "binary")
                Fail("binary OFF is not supported; expected ASCII OFF");
            if (TrimText(rest).empty() && !NextLine(rest, true)) {
                InputError({lines_.stream().name(), lines_.offset()},
                           "file ends after the OFF keyword; expected 'nv nf ne' counts");
            }
        }
        std::string_view a = NextToken(rest), b = NextToken(rest), c = NextToken(rest);
        if (b.empty() || !NextToken(rest).empty())
            Fail("expected the counts line 'vertices faces [edges]'");
        vertex_total_ = Count(a, "vertex");
        face_total_ = Count(b, "face");
        if (!c.empty())
            Count(c, "edge");
        header_.vertex_count = vertex_total_;
        header_.face_count = face_total_;
        header_.has_normals = normals_;
        header_.has_colors = colors_;
        header_.has_uvs = uvs_;
    }

    void ParseKeyword(std::string_view kw) {
        std::string_view k = kw;
        if (k.substr(0, 2) == "ST") {
            uvs_ = true;
            k.remove_prefix(2);
        }
        if (k.substr(0, 1) == "C") {
            colors_ = true;
            k.remove_prefix(1);
        }
        if (k.substr(0, 1) == "N") {
            normals_ = true;
            k.remove_prefix(1);
        }
        if (k.substr(0, 1) == "4" || k.substr(0, 1) == "n")
            Fail("{} (4D or n-dimensional OFF) is not supported; expected [ST][C][N]OFF",
                 QuoteToken(kw));
        if (k != "OFF")
            Fail("unexpected {}; expected an OFF keyword such as OFF, COFF, NOFF", QuoteToken(kw));
    }

    float Number(std::string_view tok, const char* what) {
        float v = 0;
        switch (ParseTextFloat(tok, v)) {
        case NumberStatus::Ok:
            return v;
        case NumberStatus::NotFinite:
            Fail("{} {} is not finite; expected a finite number", what, QuoteToken(tok));
        case NumberStatus::OutOfRange:
            Fail("{} {} is out of float range; expected a number", what, QuoteToken(tok));
        case NumberStatus::Malformed:
            break;
        }
        if (tok.empty())
            Fail("missing {}; expected a number", what);
        Fail("malformed number {} in {}; expected a number", QuoteToken(tok), what);
    }

    void Vertex(std::string_view rest) {
        float p[3];
        for (float& x : p)
            x = Number(NextToken(rest), "vertex coordinate");
        verts_.position.push_back({p[0], p[1], p[2]});
        if (normals_) {
            float nrm[3];
            for (float& x : nrm)
                x = Number(NextToken(rest), "vertex normal");
            verts_.normal.push_back({nrm[0], nrm[1], nrm[2]});
        }
        // What is left is [r g b [a]] [s t]; count to tell them apart.
        std::string_view tok[7];
        int n = 0;
        for (auto t = NextToken(rest); !t.empty(); t = NextToken(rest)) {
            if (n == 6)
                Fail("too many numbers on a vertex line for {}", Keyword());
            tok[n++] = t;
        }
        int ncolor = n - (uvs_ ? 2 : 0);
        if (ncolor < 0 || (colors_ ? (ncolor != 0 && ncolor != 3 && ncolor != 4) : ncolor != 0))
            Fail("{} numbers after the coordinates; expected a {} vertex line: {}", n, Keyword(),
                 VertexLayout());
        if (colors_)
            Color(tok, ncolor);
        if (uvs_) {
            verts_.uv.push_back({Number(tok[ncolor], "texture coordinate"),
                                 Number(tok[ncolor + 1], "texture coordinate")});
        }
        ++vertices_read_;
        if (verts_.size() >= batch_vertices_)
            FlushVertices();
    }

    void Color(const std::string_view* tok, int n) {
        bool first = vertices_read_ == 0;
        bool ints = n > 0 && std::all_of(tok, tok + n, IsIntegerToken);
        if (first) {
            header_.has_alpha = n == 4;
            header_.colors_are_float = n > 0 && !ints;
        }
        float c[4] = {1, 1, 1, 1};
        for (int i = 0; i < n; ++i) {
            float v = Number(tok[i], "vertex colour");
            if (ints)
                v /= 255.0f;
            c[i] = std::clamp(v, 0.0f, 1.0f);
        }
        verts_.color.push_back({c[0], c[1], c[2]});
        if (header_.has_alpha)
            verts_.alpha.push_back(c[3]);
    }

    void Face(std::string_view rest) {
        int64_t n = 0;
        std::string_view count = NextToken(rest);
        if (!ParseTextInt(count, n))
            Fail("malformed corner count {}; expected 'n i0 i1 ... '", QuoteToken(count));
        if (n < 3)
            Fail("polygon with {} corners; expected at least 3", n);
        if (uint64_t(n) > kMaxCorners)
            Fail("polygon with {} corners; expected at most {}", n, kMaxCorners);
        for (int64_t k = 0; k < n; ++k) {
            std::string_view tok = NextToken(rest);
            int64_t i = 0;
            if (tok.empty())
                Fail("polygon ends after {} of {} indices", k, n);
            if (!ParseTextInt(tok, i))
                Fail("malformed vertex index {}", QuoteToken(tok));
            if (i < 0 || uint64_t(i) >= vertex_total_) {
                Fail("vertex index {} out of range; expected 0..{} (the header's vertex count "
                     "is {})",
                     i, int64_t(vertex_total_) - 1, vertex_total_);
            }
            faces_.index.push_back(uint64_t(i));
        }
        // The rest is an optional face colour, ignored.
        faces_.size.push_back(uint32_t(n));
        if (faces_.count() >= batch_faces_ || faces_.index.size() >= batch_corners_)
            FlushFaces();
    }

    std::string Keyword() const {
        return fmt::format("{}{}{}OFF", uvs_ ? "ST" : "", colors_ ? "C" : "", normals_ ? "N" : "");
    }
    std::string VertexLayout() const {
        return fmt::format("x y z{}{}{}", normals_ ? " nx ny nz" : "",
                           colors_ ? " [r g b [a]]" : "", uvs_ ? " s t" : "");
    }

    void Begin() { emit_.Begin(header_); }
    void FlushVertices() {
        Begin();
        emit_.FlushVertices(verts_);
    }
    void FlushFaces() {
        Begin();
        emit_.FlushFaces(verts_, faces_);
    }

    TextLineReader lines_;
    MeshSink& sink_;
    BatchEmitter emit_{sink_};
    size_t batch_vertices_, batch_faces_, batch_corners_;
    MeshHeader header_;
    MeshSummary summary_;
    VertexBatch verts_;
    FaceBatch faces_;
    uint64_t vertex_total_ = 0, face_total_ = 0;
    uint64_t vertices_read_ = 0;
    size_t comment_bytes_ = 0;
    bool normals_ = false, colors_ = false, uvs_ = false;
};

}  // namespace

void ReadOff(InputStream& in, MeshSink& sink, const ReadOptions& opt) {
    OffReader(in, sink, opt).Run();
}

}  // namespace mebake::io
