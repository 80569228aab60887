// Streaming Wavefront OBJ reader: one pass, line by line, memory bounded by the batch
// sizes (not the file), after the OBJ spec in "Object Files (.obj)", Wavefront Advanced
// Visualizer manual, Appendix B1.
//
// Rules where the format leaves a choice:
//  - Vertex colours ("v x y z r g b", floats) are on when the FIRST vertex has them
//    (header.has_colors). Later vertices without colours then get white (1,1,1); if the
//    first vertex had none, colours on later vertices are ignored. Colours are clamped
//    to [0,1]. "v x y z w" ignores the rational weight w.
//  - vt/vn are per corner in OBJ, not per vertex: they are validated and counted
//    (MeshSummary::corner_uv_count / corner_normal_count) but not delivered.
//  - Every polygon carries a material (FaceBatch::material). Polygons before the first
//    usemtl use the material named "" (empty), which is then listed in
//    MeshSummary::materials like any other; a file without usemtl has materials == {""}.
//  - Indices are checked against what was read so far: a forward reference, index 0 or
//    a relative index reaching before the first element is an input error.
//  - g names (several per line) and o names go to MeshSummary::groups in order of first
//    use; mtllib file names to mtllibs. s is ignored. l, p and unknown statements are
//    skipped and listed once in header.skipped, which is complete up to the first
//    delivered batch (Begin() cannot wait longer); later ones are only logged.
//  - Leading '#' lines become header.comments; '#' after a statement is a comment too.
//    A line ending in '\' continues on the next line.
#include "core/error.h"
#include "io/batch_emitter.h"
#include "io/mesh_format.h"
#include "io/text_parse.h"

#include <algorithm>
#include <spdlog/spdlog.h>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

namespace mebake::io {

namespace {

constexpr size_t kMaxCorners = size_t(1) << 16;     // per polygon
constexpr size_t kMaxNames = size_t(1) << 20;       // distinct materials / groups
constexpr size_t kMaxNameBytes = size_t(64) << 20;  // their total length, per kind
constexpr size_t kMaxSkippedKinds = 64;             // distinct unknown keywords listed
constexpr size_t kMaxLeadingComments = 1024;
constexpr size_t kMaxCommentBytes = size_t(64) << 10;

// Names in order of first use, with their index.
class NameTable {
public:
    explicit NameTable(std::vector<std::string>& names) : names_(names) {}
    // Index of `name`, adding it if new; -1 when full.
    int64_t Intern(std::string_view name) {
        auto it = index_.find(std::string(name));
        if (it != index_.end())
            return it->second;
        if (names_.size() >= kMaxNames || bytes_ + name.size() > kMaxNameBytes)
            return -1;
        bytes_ += name.size();
        uint32_t id = uint32_t(names_.size());
        names_.emplace_back(name);
        index_.emplace(names_.back(), id);
        return id;
    }

private:
    std::vector<std::string>& names_;
    size_t bytes_ = 0;
    std::unordered_map<std::string, uint32_t> index_;
};

const char* Plural(std::string_view what) {
    return what == "vertex" ? "vertices" : what == "vt" ? "vt lines" : "vn lines";
}

bool IsKeywordChar(char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_';
}

class ObjReader {
public:
    ObjReader(InputStream& in, MeshSink& sink, const ReadOptions& opt)
        : lines_(in),
          sink_(sink),
          batch_vertices_(std::max<size_t>(opt.batch_vertices, 1)),
          batch_faces_(std::max<size_t>(opt.batch_faces, 1)),
          batch_corners_(std::max(batch_faces_ * 4, kMaxCorners)),
          materials_(summary_.materials),
          groups_(summary_.groups),
          mtllibs_(summary_.mtllibs) {
        header_.source = in.name();
        header_.format = MeshFormat::Obj;
        header_.encoding = "ascii";
    }

    void Run() {
        std::string_view line;
        while (NextStatement(line))
            Statement(line);
        if (vertex_count_ == 0) {
            FileLoc at{lines_.stream().name(), lines_.offset()};
            if (lines_.offset() == 0)
                InputError(at, "empty file; expected OBJ text");
            InputError(at, "no vertices; expected OBJ 'v x y z' lines");
        }
        FlushFaces();
        summary_.vertex_count = vertex_count_;
        summary_.face_count = face_count_;
        summary_.bytes_read = lines_.offset();
        sink_.End(summary_);
    }

private:
    template <typename... Args>
    [[noreturn]] void Fail(fmt::format_string<Args...> f, Args&&... args) {
        InputError(lines_.Loc(), f, std::forward<Args>(args)...);
    }

    // The next line with a statement, continuation lines joined, comments gathered.
    bool NextStatement(std::string_view& line) {
        for (;;) {
            if (!lines_.Next(line))
                return false;
            std::string_view t = TrimText(line);
            if (t.empty())
                continue;
            if (t.front() == '#') {
                if (!seen_statement_)
                    LeadingComment(TrimText(t.substr(1)));
                continue;
            }
            seen_statement_ = true;
            if (t.back() != '\\') {
                line = t;
                return true;
            }
            joined_.assign(t.substr(0, t.size() - 1));
            for (;;) {
                std::string_view next;
                if (!lines_.Next(next))
                    break;
                next = TrimText(next);
                bool more = !next.empty() && next.back() == '\\';
                if (more)
                    next.remove_suffix(1);
                if (joined_.size() + next.size() + 1 > InputStream::kMaxLine)
                    Fail("continued line longer than {} bytes", InputStream::kMaxLine);
                joined_ += ' ';
                joined_.append(next);
                if (!more)
                    break;
            }
            line = joined_;
            return true;
        }
    }

    void LeadingComment(std::string_view text) {
        if (header_.comments.size() >= kMaxLeadingComments)
            return;
        if (comment_bytes_ + text.size() > kMaxCommentBytes)
            return;
        comment_bytes_ += text.size();
        header_.comments.emplace_back(text);
    }

    void Statement(std::string_view line) {
        std::string_view rest = StripComment(line);
        std::string_view kw = NextToken(rest);
        if (kw.empty())
            return;  // "  # comment" after whitespace
        // The hot statements without string compares.
        if (kw.size() == 1 && kw[0] == 'v')
            return Vertex(rest);
        if (kw.size() == 1 && kw[0] == 'f')
            return Face(rest);
        if (kw.size() == 2 && kw[0] == 'v' && kw[1] == 't')
            return CheckNumbers(rest, 1, 3, "vt", summary_.corner_uv_count);
        if (kw.size() == 2 && kw[0] == 'v' && kw[1] == 'n')
            return CheckNumbers(rest, 3, 3, "vn", summary_.corner_normal_count);
        if (kw == "fo")
            return Face(rest);
        if (kw == "usemtl")
            return UseMaterial(TrimText(rest));
        if (kw == "g") {
            for (auto name = NextToken(rest); !name.empty(); name = NextToken(rest))
                Group(name);
            return;
        }
        if (kw == "o") {
            if (auto name = TrimText(rest); !name.empty())
                Group(name);
            return;
        }
        if (kw == "mtllib") {
            for (auto name = NextToken(rest); !name.empty(); name = NextToken(rest)) {
                if (mtllibs_.Intern(name) < 0)
                    Fail("more than {} mtllib names or {} bytes of them", kMaxNames, kMaxNameBytes);
            }
            return;
        }
        if (kw == "s")
            return;
        if (!std::all_of(kw.begin(), kw.end(), IsKeywordChar)) {
            Fail("unexpected {}; expected an OBJ statement such as 'v x y z' or 'f 1 2 3' "
                 "(is this an OBJ file?)",
                 QuoteToken(kw));
        }
        Skipped(kw);
    }

    void Skipped(std::string_view kw) {
        kw = kw.substr(0, 32);
        for (const auto& s : skipped_)
            if (s == kw)
                return;
        if (skipped_.size() >= kMaxSkippedKinds)
            return;
        skipped_.emplace_back(kw);
        if (!emit_.begun()) {
            header_.skipped.emplace_back(kw);
        } else {
            spdlog::debug("{}: skipped OBJ '{}' statements (not used)", lines_.Loc().ToString(),
                          kw);
        }
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
        Fail("malformed number {} in {}; expected a number", QuoteToken(tok), what);
    }

    void Vertex(std::string_view rest) {
        float val[7];
        int n = 0;
        for (auto tok = NextToken(rest); !tok.empty(); tok = NextToken(rest)) {
            if (n == 7)
                Fail("too many numbers in 'v'; expected 'v x y z [w]' or 'v x y z r g b'");
            val[n++] = Number(tok, "'v'");
        }
        if (n != 3 && n != 4 && n != 6)
            Fail("{} numbers in 'v'; expected 'v x y z [w]' or 'v x y z r g b'", n);
        bool colored = n == 6;
        if (vertex_count_ == 0)
            header_.has_colors = colored;
        verts_.position.push_back({val[0], val[1], val[2]});
        if (header_.has_colors) {
            Vec3f c{1, 1, 1};
            if (colored) {
                c = {std::clamp(val[3], 0.0f, 1.0f), std::clamp(val[4], 0.0f, 1.0f),
                     std::clamp(val[5], 0.0f, 1.0f)};
            }
            verts_.color.push_back(c);
        }
        ++vertex_count_;
        if (verts_.size() >= batch_vertices_)
            FlushVertices();
    }

    void CheckNumbers(std::string_view rest, int min, int max, const char* what, uint64_t& count) {
        int n = 0;
        for (auto tok = NextToken(rest); !tok.empty(); tok = NextToken(rest)) {
            if (n == max)
                Fail("too many numbers in '{}'; expected at most {}", what, max);
            Number(tok, what);
            ++n;
        }
        if (n < min)
            Fail("{} numbers in '{}'; expected at least {}", n, what, min);
        ++count;
    }

    // OBJ index `tok` (1-based, or negative counting back) among `count` elements so far.
    uint64_t Resolve(std::string_view tok, uint64_t count, const char* what) {
        int64_t i = 0;
        if (!ParseTextInt(tok, i))
            Fail("malformed {} index {} in 'f'; expected an integer", what, QuoteToken(tok));
        if (i == 0)
            Fail("{} index 0 in 'f'; OBJ indices start at 1 (negative count back)", what);
        if (i > 0) {
            if (uint64_t(i) > count) {
                Fail("{} index {} in 'f' but only {} {} read so far; expected an index that "
                     "refers to an earlier line",
                     what, i, count, Plural(what));
            }
            return uint64_t(i) - 1;
        }
        uint64_t back = uint64_t(-(i + 1)) + 1;
        if (back > count) {
            Fail("relative {} index {} in 'f' but only {} {} read so far", what, i, count,
                 Plural(what));
        }
        return count - back;
    }

    void Face(std::string_view rest) {
        uint32_t n = 0;
        for (auto tok = NextToken(rest); !tok.empty(); tok = NextToken(rest)) {
            if (n == kMaxCorners)
                Fail("polygon with more than {} corners; expected a smaller polygon", kMaxCorners);
            size_t s1 = tok.find('/');
            faces_.index.push_back(Resolve(tok.substr(0, s1), vertex_count_, "vertex"));
            if (s1 != std::string_view::npos) {
                std::string_view tn = tok.substr(s1 + 1);
                size_t s2 = tn.find('/');
                std::string_view t = tn.substr(0, s2);
                if (!t.empty())
                    Resolve(t, summary_.corner_uv_count, "vt");
                if (s2 != std::string_view::npos) {
                    std::string_view nn = tn.substr(s2 + 1);
                    if (nn.empty() || nn.find('/') != std::string_view::npos)
                        Fail("malformed corner {} in 'f'; expected v, v/t, v//n or v/t/n",
                             QuoteToken(tok));
                    Resolve(nn, summary_.corner_normal_count, "vn");
                } else if (t.empty()) {
                    Fail("malformed corner {} in 'f'; expected v, v/t, v//n or v/t/n",
                         QuoteToken(tok));
                }
            }
            ++n;
        }
        if (n < 3)
            Fail("polygon with {} corners; expected 'f' with at least 3 vertices", n);
        if (current_material_ < 0)
            UseMaterial("");
        faces_.size.push_back(n);
        faces_.material.push_back(uint32_t(current_material_));
        ++face_count_;
        if (faces_.count() >= batch_faces_ || faces_.index.size() >= batch_corners_)
            FlushFaces();
    }

    void UseMaterial(std::string_view name) {
        current_material_ = materials_.Intern(name);
        if (current_material_ < 0)
            Fail("more than {} materials or {} bytes of their names", kMaxNames, kMaxNameBytes);
    }

    void Group(std::string_view name) {
        if (groups_.Intern(name) < 0 && !groups_full_warned_) {
            groups_full_warned_ = true;
            spdlog::warn(
                "{}: more than {} OBJ group names or {} bytes of them; listing only the first",
                lines_.Loc().ToString(), kMaxNames, kMaxNameBytes);
        }
    }

    void Begin() { emit_.Begin(header_); }
    void FlushVertices() {
        Begin();
        emit_.FlushVertices(verts_);
    }
    // Faces only name vertices read so far: the emitter delivers those first.
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
    NameTable materials_, groups_, mtllibs_;
    VertexBatch verts_;
    FaceBatch faces_;
    std::string joined_;
    std::vector<std::string> skipped_;
    uint64_t vertex_count_ = 0, face_count_ = 0;
    int64_t current_material_ = -1;
    size_t comment_bytes_ = 0;
    bool seen_statement_ = false;
    bool groups_full_warned_ = false;
};

}  // namespace

void ReadObj(InputStream& in, MeshSink& sink, const ReadOptions& opt) {
    ObjReader(in, sink, opt).Run();
}

}  // namespace mebake::io
