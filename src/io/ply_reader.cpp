// Streaming PLY reader (Turk 1994, "The PLY Polygon File Format"): ascii, binary little-
// and big-endian. Vertices (position, normal, colour, uv), face polygons and tristrips
// are delivered in bounded batches; every other property and element is read past.
//
// Speed: binary bodies are decoded straight from the InputStream's buffer. Vertex records
// without lists have a fixed stride and are decoded a window at a time; faces whose only
// property is "list uchar int|uint vertex_indices" (nearly all files) take a tight loop.
// Everything else goes through a per-property path. No count from the file sizes any
// allocation: batches are bounded by ReadOptions and lists by kMaxPolygonCorners.
//
// Tristrips (the "tristrips" element, e.g. igea.ply): each list is a sequence of strips
// separated by -1. Triangle i of a strip is (v[i], v[i+1], v[i+2]) for even i and
// (v[i+1], v[i], v[i+2]) for odd i, so every triangle keeps the strip's winding. Strips
// repeat an index to turn a corner ("swap"); such triangles have a repeated index and are
// not emitted, but they still count for the even/odd alternation.
#include "core/check.h"
#include "core/error.h"
#include "io/mesh_format.h"
#include "io/ply_header.h"

#include <algorithm>
#include <array>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstring>

namespace mebake::io {
namespace {

constexpr uint32_t kMaxPolygonCorners = uint32_t(1) << 16;
constexpr size_t kMaxFixedStride = size_t(1) << 16;  // larger records use the generic path
constexpr size_t kChunkBytes = size_t(1) << 18;      // bytes decoded per fixed-stride step
constexpr size_t kMaxToken = 4096;                   // longest ASCII token accepted

// What a property is for. The value roles (kX .. kV) index the per-record value array.
enum Role : uint8_t {
    kX,
    kY,
    kZ,
    kNX,
    kNY,
    kNZ,
    kR,
    kG,
    kB,
    kA,
    kU,
    kV,
    kSkip,
    kFaceList,
    kStripList
};
constexpr int kNumValueRoles = kSkip;

struct Prop {
    PlyType type;
    PlyType count_type;
    bool is_list;
    Role role;
    uint32_t offset;  // within a fixed-stride record
    const std::string* name;
};

enum class Kind { Vertex, Face, Strips, Other };

struct Plan {
    const PlyElement* decl = nullptr;
    Kind kind = Kind::Other;
    std::vector<Prop> props;
    bool fixed = true;    // no list property: every record has `stride` bytes
    uint64_t stride = 0;  // sum of scalar sizes (when fixed)
    // Vertex elements: what is present, and each value role's property.
    bool normals = false, colors = false, alpha = false, uvs = false;
    int role_prop[kNumValueRoles];
};

constexpr float kFloatMax = 3.402823466e38f;

inline bool IsSpace(uint8_t c) {
    return c == ' ' || (c >= '\t' && c <= '\r');
}

// ---------------------------------------------------------------------------------------
// Planning: which property feeds what.

int FindProp(const PlyElement& e, std::string_view name) {
    for (size_t i = 0; i < e.properties.size(); ++i)
        if (e.properties[i].name == name && !e.properties[i].is_list)
            return int(i);
    return -1;
}

Plan MakePlan(const PlyElement& e, const std::string& file, MeshHeader& mh) {
    Plan plan;
    plan.decl = &e;
    std::fill(std::begin(plan.role_prop), std::end(plan.role_prop), -1);
    if (e.name == "vertex") {
        plan.kind = Kind::Vertex;
    } else if (e.name == "face") {
        plan.kind = Kind::Face;
    } else if (e.name == "tristrips") {
        plan.kind = Kind::Strips;
    }
    FileLoc loc{file, FileLoc::kNone, e.line};
    plan.props.reserve(e.properties.size());
    for (const auto& p : e.properties)
        plan.props.push_back({p.type, p.count_type, p.is_list, kSkip, 0, &p.name});

    auto assign = [&](std::initializer_list<const char*> names, Role first) {
        int idx[4];
        int n = 0;
        for (const char* name : names) {
            idx[n] = FindProp(e, name);
            if (idx[n] < 0)
                return false;
            ++n;
        }
        for (int k = 0; k < n; ++k) {
            plan.props[size_t(idx[k])].role = Role(first + k);
            plan.role_prop[first + k] = idx[k];
        }
        return true;
    };

    if (plan.kind == Kind::Vertex) {
        for (const char* c : {"x", "y", "z"}) {
            for (const auto& p : e.properties)
                if (p.name == c && p.is_list)
                    InputError(loc, "vertex property '{}' is a list, expected a scalar", c);
            if (FindProp(e, c) < 0)
                InputError(loc, "vertex element has no property '{}', expected x, y and z", c);
        }
        assign({"x", "y", "z"}, kX);
        plan.normals = assign({"nx", "ny", "nz"}, kNX);
        plan.colors = assign({"red", "green", "blue"}, kR) ||
                      assign({"diffuse_red", "diffuse_green", "diffuse_blue"}, kR);
        if (plan.colors) {
            plan.alpha = assign({"alpha"}, kA) || assign({"diffuse_alpha"}, kA);
            mh.colors_are_float = !PlyTypeIsInteger(plan.props[size_t(plan.role_prop[kR])].type);
        }
        plan.uvs = assign({"s", "t"}, kU) || assign({"u", "v"}, kU) ||
                   assign({"texture_u", "texture_v"}, kU) || assign({"texture_s", "texture_t"}, kU);
        mh.has_normals = plan.normals;
        mh.has_colors = plan.colors;
        mh.has_alpha = plan.alpha;
        mh.has_uvs = plan.uvs;
    } else if (plan.kind == Kind::Face || plan.kind == Kind::Strips) {
        int found = -1;
        for (size_t i = 0; i < e.properties.size(); ++i) {
            const auto& p = e.properties[i];
            if (p.name != "vertex_indices" && p.name != "vertex_index")
                continue;
            if (found >= 0)
                InputError(loc, "{} element has both vertex_indices and vertex_index", e.name);
            if (!p.is_list)
                InputError(loc, "{}.{} must be a list property, e.g. 'property list uchar int {}'",
                           e.name, p.name, p.name);
            if (!PlyTypeIsInteger(p.type))
                InputError(loc, "{}.{}: index type must be an integer type", e.name, p.name);
            found = int(i);
        }
        if (found < 0)
            InputError(loc, "{} element has no 'vertex_indices' list property", e.name);
        plan.props[size_t(found)].role = plan.kind == Kind::Face ? kFaceList : kStripList;
    }
    for (const auto& p : plan.props) {
        if (p.is_list)
            plan.fixed = false;
        plan.stride += PlyTypeSize(p.type);  // properties are few (header is bounded)
        if (p.role == kSkip && plan.kind != Kind::Other)
            mh.skipped.push_back(e.name + "." + *p.name);
    }
    if (plan.kind == Kind::Other)
        mh.skipped.push_back(e.name);
    uint64_t off = 0;
    for (auto& p : plan.props) {
        p.offset = uint32_t(std::min<uint64_t>(off, UINT32_MAX));
        off += PlyTypeSize(p.type);
    }
    if (plan.stride > kMaxFixedStride)
        plan.fixed = false;
    return plan;
}

// ---------------------------------------------------------------------------------------
// Delivery to the sink, with the checks every path shares.

class Emitter {
public:
    Emitter(MeshSink& sink, const ReadOptions& opt, uint64_t vcount)
        : sink_(sink),
          vertex_count_(vcount),
          batch_vertices_(std::max<size_t>(opt.batch_vertices, 1)),
          batch_faces_(std::max<size_t>(opt.batch_faces, 1)),
          batch_corners_(batch_faces_ > (size_t(1) << 40) ? batch_faces_ : batch_faces_ * 4) {}

    // Sizes the batches once so they do not grow by reallocation, which costs more than
    // the decoding on small files. Bounded by the options and kMaxReserve, never by what
    // the header claims.
    void Reserve(uint64_t vertices, uint64_t faces, bool normals, bool colors, bool alpha,
                 bool uvs) {
        constexpr uint64_t kMaxReserve = uint64_t(1) << 20;
        const size_t nv = size_t(std::min<uint64_t>({vertices, batch_vertices_, kMaxReserve}));
        const size_t nf = size_t(std::min<uint64_t>({faces, batch_faces_, kMaxReserve}));
        vb.position.reserve(nv);
        if (normals)
            vb.normal.reserve(nv);
        if (colors)
            vb.color.reserve(nv);
        if (alpha)
            vb.alpha.reserve(nv);
        if (uvs)
            vb.uv.reserve(nv);
        fb.size.reserve(nf);
        fb.index.reserve(3 * nf + 2);
    }

    VertexBatch vb;
    FaceBatch fb;

    size_t VertexRoom() const { return batch_vertices_ - vb.size(); }
    size_t FaceRoom() const { return batch_faces_ - fb.count(); }
    void VerticesAdded() {
        if (vb.size() >= batch_vertices_)
            FlushVertices();
    }
    void FlushVertices() {
        if (vb.size() == 0)
            return;
        vb.first = vertices_;
        sink_.Vertices(vb);
        vertices_ += vb.size();
        vb.Clear();
    }
    void FaceAdded() {
        if (fb.count() >= batch_faces_ || fb.index.size() >= batch_corners_)
            FlushFaces();
    }
    void FlushFaces() {
        if (fb.count() == 0)
            return;
        fb.first = faces_;
        sink_.Faces(fb);
        faces_ += fb.count();
        fb.Clear();
    }
    uint64_t vertex_count() const { return vertex_count_; }
    uint64_t vertices_delivered() const { return vertices_; }
    uint64_t faces_delivered() const { return faces_; }
    uint64_t next_face() const { return faces_ + fb.count(); }

    [[noreturn]] void BadIndex(const FileLoc& loc, const char* what, uint64_t face,
                               int64_t v) const {
        if (v < 0)
            InputError(loc, "{} {}: negative vertex index {}", what, face, v);
        InputError(loc, "{} {}: vertex index {} out of range, the header declares {} vertices",
                   what, face, v, vertex_count_);
    }

private:
    MeshSink& sink_;
    uint64_t vertex_count_;
    size_t batch_vertices_, batch_faces_, batch_corners_;
    uint64_t vertices_ = 0, faces_ = 0;
};

// Adds one triangle per strip index, as documented at the top.
struct StripState {
    uint64_t a = 0, b = 0;
    uint64_t n = 0;  // indices in the current strip so far

    void Add(uint64_t v, Emitter& em) {
        if (n >= 2) {
            uint64_t p = (n & 1) ? b : a;
            uint64_t q = (n & 1) ? a : b;
            if (p != q && q != v && p != v) {
                em.fb.size.push_back(3);
                em.fb.index.push_back(p);  // not insert({..}): its temporary stalls
                em.fb.index.push_back(q);
                em.fb.index.push_back(v);
                em.FaceAdded();
            }
        }
        a = b;
        b = v;
        ++n;
    }
};

// Converts one vertex's values (as doubles, in role order) and appends it; checks that
// all are finite. Integer colours map to [0,1] by their type's maximum, float colours
// are clamped to [0,1]. Messages name the record's byte offset, or its line for ASCII.
void AppendVertex(const double* v, const Plan& plan, Emitter& em, const std::string& file,
                  uint64_t offset, uint64_t line) {
    auto finite = [&](int role) {
        float f = float(v[role]);
        if (!(std::fabs(f) <= kFloatMax)) [[unlikely]]
            InputError({file, offset, line}, "vertex {}: {} = {} is not a finite float",
                       em.vertices_delivered() + em.vb.size(),
                       *plan.props[size_t(plan.role_prop[role])].name, v[role]);
        return f;
    };
    auto unit = [&](int role) {
        PlyType t = plan.props[size_t(plan.role_prop[role])].type;
        float f = finite(role);
        if (PlyTypeIsInteger(t))
            f = float(v[role] / PlyTypeMax(t));
        return std::clamp(f, 0.0f, 1.0f);
    };
    em.vb.position.push_back({finite(kX), finite(kY), finite(kZ)});
    if (plan.normals)
        em.vb.normal.push_back({finite(kNX), finite(kNY), finite(kNZ)});
    if (plan.colors)
        em.vb.color.push_back({unit(kR), unit(kG), unit(kB)});
    if (plan.alpha)
        em.vb.alpha.push_back(unit(kA));
    if (plan.uvs)
        em.vb.uv.push_back({finite(kU), finite(kV)});
    em.VerticesAdded();
}

[[noreturn]] void BadCorners(const FileLoc& loc, const char* what, uint64_t face, int64_t n) {
    if (n < 0)
        InputError(loc, "{} {}: negative list count {}", what, face, n);
    if (n < 3)
        InputError(loc, "{} {}: a polygon needs at least 3 corners, the list has {}", what, face,
                   n);
    InputError(loc, "{} {}: list of {} corners, at most {} are supported", what, face, n,
               kMaxPolygonCorners);
}

// ---------------------------------------------------------------------------------------
// Binary bodies.

// A window onto the InputStream's buffer; bytes are consumed from the stream lazily.
class Window {
public:
    explicit Window(InputStream& in) : in_(in) {}

    // n contiguous bytes at the returned pointer (n <= InputStream::kMaxPeek).
    const uint8_t* Need(size_t n) {
        if (size_t(end_ - p_) < n) [[unlikely]]
            Refill(n);
        return p_;
    }
    size_t Available() const { return size_t(end_ - p_); }
    const uint8_t* Pos() const { return p_; }
    void Advance(size_t n) { p_ += n; }
    uint64_t Offset() const { return in_.offset() + uint64_t(p_ - base_); }
    void Sync() {
        in_.Skip(size_t(p_ - base_));
        base_ = p_;
    }
    void SkipBytes(uint64_t n) {
        while (n > 0) {
            if (p_ == end_)
                Refill(1);
            size_t k = size_t(std::min<uint64_t>(n, Available()));
            p_ += k;
            n -= k;
        }
    }
    const std::string& file() const { return in_.name(); }

    // For the end-of-data message.
    const PlyElement* element = nullptr;
    uint64_t record = 0;

private:
    [[gnu::noinline]] void Refill(size_t n) {
        CHECK_LE(n, InputStream::kMaxPeek);
        Sync();
        auto s = in_.Peek(std::max(n, size_t(1) << 16));
        base_ = p_ = s.data();
        end_ = p_ + s.size();
        if (s.size() < n)
            Truncated(n - s.size());
    }
    [[noreturn]] void Truncated(size_t missing) const {
        uint64_t at = in_.offset() + uint64_t(end_ - base_);
        if (element)
            InputError({in_.name(), at},
                       "unexpected end of data in element '{}' record {} of {} declared in the "
                       "header ({} more bytes needed)",
                       element->name, record, element->count, missing);
        InputError({in_.name(), at}, "unexpected end of data");
    }

    InputStream& in_;
    const uint8_t* base_ = nullptr;
    const uint8_t* p_ = nullptr;
    const uint8_t* end_ = nullptr;
};

template <bool kSwap>
inline uint16_t LoadU16(const uint8_t* p) {
    uint16_t v;
    std::memcpy(&v, p, 2);
    if constexpr (kSwap)
        v = __builtin_bswap16(v);
    return v;
}
template <bool kSwap>
inline uint32_t LoadU32(const uint8_t* p) {
    uint32_t v;
    std::memcpy(&v, p, 4);
    if constexpr (kSwap)
        v = __builtin_bswap32(v);
    return v;
}
template <bool kSwap>
inline uint64_t LoadU64(const uint8_t* p) {
    uint64_t v;
    std::memcpy(&v, p, 8);
    if constexpr (kSwap)
        v = __builtin_bswap64(v);
    return v;
}
template <bool kSwap>
inline float LoadF32(const uint8_t* p) {
    return std::bit_cast<float>(LoadU32<kSwap>(p));
}

template <bool kSwap>
double LoadDouble(const uint8_t* p, PlyType t) {
    switch (t) {
    case PlyType::Int8:
        return double(int8_t(p[0]));
    case PlyType::UInt8:
        return double(p[0]);
    case PlyType::Int16:
        return double(int16_t(LoadU16<kSwap>(p)));
    case PlyType::UInt16:
        return double(LoadU16<kSwap>(p));
    case PlyType::Int32:
        return double(int32_t(LoadU32<kSwap>(p)));
    case PlyType::UInt32:
        return double(LoadU32<kSwap>(p));
    case PlyType::Float32:
        return double(LoadF32<kSwap>(p));
    case PlyType::Float64:
        return std::bit_cast<double>(LoadU64<kSwap>(p));
    }
    return 0;
}

// Integer types only (checked when planning).
template <bool kSwap>
int64_t LoadInt(const uint8_t* p, PlyType t) {
    switch (t) {
    case PlyType::Int8:
        return int8_t(p[0]);
    case PlyType::UInt8:
        return p[0];
    case PlyType::Int16:
        return int16_t(LoadU16<kSwap>(p));
    case PlyType::UInt16:
        return LoadU16<kSwap>(p);
    case PlyType::Int32:
        return int32_t(LoadU32<kSwap>(p));
    case PlyType::UInt32:
        return LoadU32<kSwap>(p);
    default:
        return 0;
    }
}

const float* UcharToUnit() {
    static const auto table = [] {
        std::array<float, 256> t{};
        for (int i = 0; i < 256; ++i)
            t[size_t(i)] = float(i) / 255.0f;
        return t;
    }();
    return table.data();
}

template <bool kSwap>
class BinaryBody {
public:
    BinaryBody(InputStream& in, Emitter& em) : w_(in), em_(em) {}

    void Read(const Plan& plan) {
        w_.element = plan.decl;
        switch (plan.kind) {
        case Kind::Vertex:
            if (plan.fixed) {
                FixedVertices(plan);
            } else {
                GenericRecords(plan);
            }
            em_.FlushVertices();
            break;
        case Kind::Face:
            if (IsSimpleFace(plan)) {
                if (plan.props[0].type == PlyType::Int32) {
                    SimpleFaces<true>(plan);
                } else {
                    SimpleFaces<false>(plan);
                }
            } else {
                GenericRecords(plan);
            }
            em_.FlushFaces();
            break;
        case Kind::Strips:
            GenericRecords(plan);
            em_.FlushFaces();
            break;
        case Kind::Other:
            if (plan.fixed) {
                uint64_t bytes;
                if (__builtin_mul_overflow(plan.decl->count, plan.stride, &bytes))
                    InputError({w_.file(), w_.Offset()},
                               "element '{}' declares {} records of {} bytes, more than any file "
                               "holds",
                               plan.decl->name, plan.decl->count, plan.stride);
                w_.SkipBytes(bytes);
            } else {
                GenericRecords(plan);
            }
            break;
        }
        w_.element = nullptr;
    }
    void Sync() { w_.Sync(); }

private:
    static bool IsSimpleFace(const Plan& plan) {
        return plan.props.size() == 1 && plan.props[0].count_type == PlyType::UInt8 &&
               (plan.props[0].type == PlyType::Int32 || plan.props[0].type == PlyType::UInt32);
    }

    // Vertex records without lists: decode whole windows of records.
    void FixedVertices(const Plan& plan) {
        const size_t stride = size_t(plan.stride);
        const uint64_t count = plan.decl->count;
        uint64_t done = 0;
        while (done < count) {
            w_.record = done;
            if (w_.Available() < stride)
                w_.Need(stride);
            size_t k = std::min<uint64_t>(count - done, em_.VertexRoom());
            k = std::min(k, std::max<size_t>(1, kChunkBytes / std::max<size_t>(stride, 1)));
            k = std::min(k, w_.Available() / std::max<size_t>(stride, 1));
            DecodeVertices(plan, w_.Pos(), k);
            w_.Advance(k * stride);
            done += k;
            em_.VerticesAdded();
        }
    }

    // Decodes k records starting at the window position (not yet advanced past them).
    void DecodeVertices(const Plan& plan, const uint8_t* rec, size_t k) {
        const size_t stride = size_t(plan.stride);
        VertexBatch& b = em_.vb;
        const size_t n0 = b.size();
        auto prop = [&](int role) -> const Prop& {
            return plan.props[size_t(plan.role_prop[role])];
        };
        // Three float fields at their record offsets, else the generic load.
        auto decode3 = [&](std::vector<Vec3f>& dst, int first) {
            dst.resize(n0 + k);
            Vec3f* out = dst.data() + n0;
            const Prop &p0 = prop(first), &p1 = prop(first + 1), &p2 = prop(first + 2);
            const uint32_t o0 = p0.offset, o1 = p1.offset, o2 = p2.offset;
            if (p0.type == PlyType::Float32 && p1.type == PlyType::Float32 &&
                p2.type == PlyType::Float32) {
                for (size_t i = 0; i < k; ++i) {
                    const uint8_t* r = rec + i * stride;
                    out[i] = {LoadF32<kSwap>(r + o0), LoadF32<kSwap>(r + o1),
                              LoadF32<kSwap>(r + o2)};
                }
            } else {
                for (size_t i = 0; i < k; ++i) {
                    const uint8_t* r = rec + i * stride;
                    out[i] = {float(LoadDouble<kSwap>(r + o0, p0.type)),
                              float(LoadDouble<kSwap>(r + o1, p1.type)),
                              float(LoadDouble<kSwap>(r + o2, p2.type))};
                }
            }
            CheckFinite(plan, &out[0].x, 3, k, first, n0);
        };
        decode3(b.position, kX);
        if (plan.normals)
            decode3(b.normal, kNX);
        if (plan.colors) {
            b.color.resize(n0 + k);
            Vec3f* out = b.color.data() + n0;
            const uint32_t o0 = prop(kR).offset, o1 = prop(kG).offset, o2 = prop(kB).offset;
            if (prop(kR).type == PlyType::UInt8 && prop(kG).type == PlyType::UInt8 &&
                prop(kB).type == PlyType::UInt8) {
                const float* lut = UcharToUnit();
                for (size_t i = 0; i < k; ++i) {
                    const uint8_t* r = rec + i * stride;
                    out[i] = {lut[r[o0]], lut[r[o1]], lut[r[o2]]};
                }
            } else {
                for (size_t i = 0; i < k; ++i)
                    for (int c = 0; c < 3; ++c)
                        out[i][c] = Unit(plan, kR + c, rec, i, n0);
            }
        }
        if (plan.alpha) {
            b.alpha.resize(n0 + k);
            for (size_t i = 0; i < k; ++i)
                b.alpha[n0 + i] = Unit(plan, kA, rec, i, n0);
        }
        if (plan.uvs) {
            b.uv.resize(n0 + k);
            Vec2f* out = b.uv.data() + n0;
            const Prop &p0 = prop(kU), &p1 = prop(kV);
            for (size_t i = 0; i < k; ++i) {
                const uint8_t* r = rec + i * stride;
                out[i] = {float(LoadDouble<kSwap>(r + p0.offset, p0.type)),
                          float(LoadDouble<kSwap>(r + p1.offset, p1.type))};
            }
            CheckFinite(plan, &out[0].x, 2, k, kU, n0);
        }
    }

    // A colour channel of record i in [0,1].
    float Unit(const Plan& plan, int role, const uint8_t* rec, size_t i, size_t n0) {
        const Prop& p = plan.props[size_t(plan.role_prop[role])];
        const double v = LoadDouble<kSwap>(rec + i * plan.stride + p.offset, p.type);
        if (PlyTypeIsInteger(p.type))
            return std::clamp(float(v / PlyTypeMax(p.type)), 0.0f, 1.0f);
        const float f = float(v);
        if (!(std::fabs(f) <= kFloatMax))
            NotFinite(plan, role, f, i, n0);
        return std::clamp(f, 0.0f, 1.0f);
    }

    // `values` holds k records of `width` floats; names the first non-finite one.
    void CheckFinite(const Plan& plan, const float* values, int width, size_t k, int first_role,
                     size_t n0) {
        // Non-finite floats are those whose magnitude bits reach the all-ones exponent;
        // a max over the bits vectorizes, a float compare per value does not.
        uint32_t most = 0;
        const size_t n = k * size_t(width);
        for (size_t i = 0; i < n; ++i) {
            uint32_t bits;
            std::memcpy(&bits, values + i, 4);
            most = std::max(most, bits & 0x7fffffffu);
        }
        if (most < 0x7f800000u) [[likely]]
            return;
        for (size_t i = 0; i < n; ++i)
            if (!(std::fabs(values[i]) <= kFloatMax))
                NotFinite(plan, first_role + int(i % size_t(width)), values[i], i / size_t(width),
                          n0);
    }

    // Record i of the chunk being decoded (the window still points at record 0).
    [[noreturn]] void NotFinite(const Plan& plan, int role, float f, size_t i, size_t n0) {
        InputError({w_.file(), w_.Offset() + i * plan.stride},
                   "vertex {}: {} = {} is not a finite float", em_.vertices_delivered() + n0 + i,
                   *plan.props[size_t(plan.role_prop[role])].name, f);
    }

    // Faces whose only property is "list uchar int|uint vertex_indices".
    template <bool kSigned>
    void SimpleFaces(const Plan& plan) {
        const uint64_t count = plan.decl->count;
        const uint64_t nv = em_.vertex_count();
        FaceBatch& fb = em_.fb;
        uint64_t f = 0;
        while (f < count) {
            w_.record = f;
            const uint8_t* p = w_.Need(13);  // a triangle; larger polygons ask again
            const uint32_t n = p[0];
            if (n == 3) [[likely]] {
                // A run of triangles inside the window and the batch, in one tight loop.
                const size_t most =
                    size_t(std::min<uint64_t>({count - f, em_.FaceRoom(), w_.Available() / 13}));
                size_t k = 1;
                while (k < most && p[13 * k] == 3)
                    ++k;
                const size_t at = fb.index.size();
                fb.index.resize(at + 3 * k);
                fb.size.resize(fb.size.size() + k, 3);
                uint64_t* out = fb.index.data() + at;
                bool ok = true;
                auto index = [](uint32_t raw) {
                    return kSigned ? uint64_t(int64_t(int32_t(raw))) : uint64_t(raw);
                };
                for (size_t i = 0; i < k; ++i) {
                    const uint8_t* r = p + 1 + 13 * i;
                    const uint64_t a = index(LoadU32<kSwap>(r));
                    const uint64_t b = index(LoadU32<kSwap>(r + 4));
                    const uint64_t c = index(LoadU32<kSwap>(r + 8));
                    ok &= (a < nv) & (b < nv) & (c < nv);
                    out[3 * i] = a;
                    out[3 * i + 1] = b;
                    out[3 * i + 2] = c;
                }
                if (!ok) [[unlikely]] {
                    for (size_t i = 0; i < 3 * k; ++i)
                        if (out[i] >= nv)
                            em_.BadIndex({w_.file(), w_.Offset() + 13 * (i / 3) + 1 + 4 * (i % 3)},
                                         "face", em_.next_face() - k + i / 3, int64_t(out[i]));
                }
                w_.Advance(13 * k);
                f += k;
                em_.FaceAdded();
                continue;
            }
            if (n < 3)
                BadCorners({w_.file(), w_.Offset()}, "face", em_.next_face(), n);
            p = w_.Need(1 + 4 * size_t(n));
            const size_t at = fb.index.size();
            fb.index.resize(at + n);
            uint64_t* out = fb.index.data() + at;
            bool ok = true;
            for (uint32_t j = 0; j < n; ++j) {
                const uint32_t raw = LoadU32<kSwap>(p + 1 + 4 * j);
                const uint64_t v = kSigned ? uint64_t(int64_t(int32_t(raw))) : uint64_t(raw);
                ok &= v < nv;
                out[j] = v;
            }
            if (!ok) [[unlikely]] {
                for (uint32_t j = 0; j < n; ++j)
                    if (out[j] >= nv)
                        em_.BadIndex({w_.file(), w_.Offset() + 1 + 4 * j}, "face", em_.next_face(),
                                     int64_t(out[j]));
            }
            fb.size.push_back(n);
            w_.Advance(1 + 4 * size_t(n));
            ++f;
            em_.FaceAdded();
        }
    }

    // m strip indices of type T at the window position. Triangles collect in a small
    // local block (written unconditionally, kept by advancing the count) and are appended
    // in bulk; the strip state stays in registers.
    template <typename T>
    void StripChunk(StripState& strip, size_t m) {
        constexpr size_t kBlock = 512;
        uint64_t tri[3 * kBlock];
        const uint8_t* s = w_.Pos();
        const uint64_t nv = em_.vertex_count();
        FaceBatch& fb = em_.fb;
        uint64_t a = strip.a, b = strip.b, n = strip.n;
        size_t j = 0;
        while (j < m) {
            // Each index adds at most one triangle: the block never overfills the batch.
            const size_t end = j + std::min({m - j, kBlock, em_.FaceRoom()});
            size_t t = 0;
            for (; j < end; ++j) {
                T raw;
                std::memcpy(&raw, s + j * sizeof(T), sizeof(T));
                if constexpr (kSwap && sizeof(T) == 2)
                    raw = T(__builtin_bswap16(uint16_t(raw)));
                if constexpr (kSwap && sizeof(T) == 4)
                    raw = T(__builtin_bswap32(uint32_t(raw)));
                const int64_t v = int64_t(raw);
                if (uint64_t(v) >= nv) [[unlikely]] {
                    if (v == -1) {
                        n = 0;
                        continue;
                    }
                    em_.BadIndex({w_.file(), w_.Offset() + j * sizeof(T)}, "tristrip triangle",
                                 em_.next_face() + t, v);
                }
                const uint64_t w = uint64_t(v);
                const uint64_t p = (n & 1) ? b : a;
                const uint64_t q = (n & 1) ? a : b;
                tri[3 * t] = p;
                tri[3 * t + 1] = q;
                tri[3 * t + 2] = w;
                t += size_t((n >= 2) & (p != q) & (q != w) & (p != w));
                a = b;
                b = w;
                ++n;
            }
            fb.index.insert(fb.index.end(), tri, tri + 3 * t);
            fb.size.insert(fb.size.end(), t, 3u);
            em_.FaceAdded();
        }
        strip.a = a;
        strip.b = b;
        strip.n = n;
    }

    // Any element, one property at a time.
    void GenericRecords(const Plan& plan) {
        const uint64_t count = plan.decl->count;
        const uint64_t nv = em_.vertex_count();
        double values[kNumValueRoles] = {};
        for (uint64_t rec = 0; rec < count; ++rec) {
            w_.record = rec;
            const uint64_t record_offset = w_.Offset();
            for (const Prop& p : plan.props) {
                const uint32_t size = PlyTypeSize(p.type);
                if (!p.is_list) {
                    const uint8_t* q = w_.Need(size);
                    if (p.role < kNumValueRoles)
                        values[p.role] = LoadDouble<kSwap>(q, p.type);
                    w_.Advance(size);
                    continue;
                }
                const uint64_t at = w_.Offset();
                const uint8_t* q = w_.Need(PlyTypeSize(p.count_type));
                const int64_t n = LoadInt<kSwap>(q, p.count_type);
                w_.Advance(PlyTypeSize(p.count_type));
                if (n < 0)
                    InputError({w_.file(), at}, "{} {}: negative list count {} for '{}'",
                               plan.decl->name, rec, n, *p.name);
                if (p.role == kFaceList) {
                    if (n < 3 || n > kMaxPolygonCorners)
                        BadCorners({w_.file(), at}, "face", em_.next_face(), n);
                    q = w_.Need(size_t(n) * size);
                    for (int64_t j = 0; j < n; ++j) {
                        const int64_t v = LoadInt<kSwap>(q + size_t(j) * size, p.type);
                        if (v < 0 || uint64_t(v) >= nv)
                            em_.BadIndex(
                                {w_.file(), at + PlyTypeSize(p.count_type) + uint64_t(j) * size},
                                "face", em_.next_face(), v);
                        em_.fb.index.push_back(uint64_t(v));
                    }
                    em_.fb.size.push_back(uint32_t(n));
                    w_.Advance(size_t(n) * size);
                    em_.FaceAdded();
                } else if (p.role == kStripList) {
                    StripState strip;
                    uint64_t left = uint64_t(n);
                    while (left > 0) {
                        if (w_.Available() < size)
                            w_.Need(size);
                        const size_t m = size_t(std::min<uint64_t>(left, w_.Available() / size));
                        switch (p.type) {
                        case PlyType::Int8:
                            StripChunk<int8_t>(strip, m);
                            break;
                        case PlyType::UInt8:
                            StripChunk<uint8_t>(strip, m);
                            break;
                        case PlyType::Int16:
                            StripChunk<int16_t>(strip, m);
                            break;
                        case PlyType::UInt16:
                            StripChunk<uint16_t>(strip, m);
                            break;
                        case PlyType::Int32:
                            StripChunk<int32_t>(strip, m);
                            break;
                        case PlyType::UInt32:
                            StripChunk<uint32_t>(strip, m);
                            break;
                        default:
                            CHECK(false);  // index types are integers (MakePlan)
                        }
                        w_.Advance(m * size);
                        left -= m;
                    }
                } else {
                    w_.SkipBytes(uint64_t(n) * size);  // n < 2^32, size <= 8: no overflow
                }
            }
            if (plan.kind == Kind::Vertex)
                AppendVertex(values, plan, em_, w_.file(), record_offset, FileLoc::kNone);
        }
    }

    Window w_;
    Emitter& em_;
};

// ---------------------------------------------------------------------------------------
// ASCII bodies: whitespace-separated tokens, lines counted for messages.

class AsciiBody {
public:
    AsciiBody(InputStream& in, Emitter& em, uint64_t header_lines)
        : in_(in), em_(em), line_(header_lines + 1) {}

    void Read(const Plan& plan) {
        element_ = plan.decl;
        if (plan.props.empty())
            return;  // nothing to read, whatever the count says
        const uint64_t count = plan.decl->count;
        const uint64_t nv = em_.vertex_count();
        double values[kNumValueRoles] = {};
        for (record_ = 0; record_ < count; ++record_) {
            uint64_t record_line = 0;
            for (const Prop& p : plan.props) {
                std::string_view tok = Next();
                if (record_line == 0)
                    record_line = token_line_;
                if (!p.is_list) {
                    if (p.role < kNumValueRoles)
                        values[p.role] = ParseScalar(tok, p.type, p);
                    continue;
                }
                const int64_t n = ParseInt(tok, p.count_type, p);
                if (n < 0)
                    InputError(Loc(), "{} {}: negative list count {} for '{}'", plan.decl->name,
                               record_, n, *p.name);
                if (p.role == kFaceList) {
                    if (n < 3 || n > kMaxPolygonCorners)
                        BadCorners(Loc(), "face", em_.next_face(), n);
                    for (int64_t j = 0; j < n; ++j) {
                        const int64_t v = ParseInt(Next(), p.type, p);
                        if (v < 0 || uint64_t(v) >= nv)
                            em_.BadIndex(Loc(), "face", em_.next_face(), v);
                        em_.fb.index.push_back(uint64_t(v));
                    }
                    em_.fb.size.push_back(uint32_t(n));
                    em_.FaceAdded();
                } else if (p.role == kStripList) {
                    StripState strip;
                    for (int64_t j = 0; j < n; ++j) {
                        const int64_t v = ParseInt(Next(), p.type, p);
                        if (v == -1) {
                            strip.n = 0;
                            continue;
                        }
                        if (v < 0 || uint64_t(v) >= nv)
                            em_.BadIndex(Loc(), "tristrip triangle", em_.next_face(), v);
                        strip.Add(uint64_t(v), em_);
                    }
                } else {
                    for (int64_t j = 0; j < n; ++j)
                        Next();
                }
            }
            if (plan.kind == Kind::Vertex)
                AppendVertex(values, plan, em_, in_.name(), FileLoc::kNone, record_line);
        }
        if (plan.kind == Kind::Vertex)
            em_.FlushVertices();
        if (plan.kind == Kind::Face || plan.kind == Kind::Strips)
            em_.FlushFaces();
        element_ = nullptr;
    }

    // Reads past trailing whitespace so bytes_read covers the final line break.
    void Finish() {
        SkipSpace();
        Sync();
    }

    void Sync() {
        in_.Skip(size_t(p_ - base_));
        base_ = p_;
    }

private:
    FileLoc Loc() const { return {in_.name(), FileLoc::kNone, token_line_}; }

    // Makes at least n bytes available from p_ if the stream has them; false at its end.
    bool Refill(size_t n) {
        Sync();
        const size_t want = std::max(n, size_t(1) << 16);
        auto s = in_.Peek(want);
        base_ = p_ = s.data();
        end_ = p_ + s.size();
        if (s.size() < want)
            eof_ = true;
        return s.size() >= n;
    }

    // Consumes whitespace; false if the data ends first.
    bool SkipSpace() {
        for (;;) {
            while (p_ < end_) {
                const uint8_t c = *p_;
                if (!IsSpace(c))
                    return true;
                if (c == '\n')
                    ++line_;
                ++p_;
            }
            if (eof_ || !Refill(1))
                return false;
        }
    }

    std::string_view Next() {
        if (!SkipSpace()) {
            token_line_ = line_;
            if (element_)
                InputError(Loc(),
                           "unexpected end of file in element '{}' record {} of {} declared "
                           "in the header",
                           element_->name, record_, element_->count);
            InputError(Loc(), "unexpected end of file");
        }
        token_line_ = line_;
        for (;;) {
            const uint8_t* q = p_;
            while (q < end_ && !IsSpace(*q))
                ++q;
            const size_t len = size_t(q - p_);
            if (len > kMaxToken)
                InputError(Loc(), "a token longer than {} bytes, expected a number", kMaxToken);
            if (q < end_ || eof_) {
                std::string_view tok(reinterpret_cast<const char*>(p_), len);
                p_ = q;
                return tok;
            }
            Refill(len + 1);  // the token reaches the window's end: see more of it
        }
    }

    [[noreturn]] void BadNumber(std::string_view tok, const Prop& p, const char* expected) const {
        std::string shown;
        for (char c : tok.substr(0, 32)) {
            unsigned char u = static_cast<unsigned char>(c);
            shown += (u >= 0x20 && u < 0x7f) ? c : '?';
        }
        InputError(Loc(), "{} {}, property '{}': expected {}, found '{}'", element_->name, record_,
                   *p.name, expected, shown);
    }

    int64_t ParseInt(std::string_view tok, PlyType t, const Prop& p) const {
        const char* b = tok.data();
        const char* e = b + tok.size();
        if (b < e && *b == '+')
            ++b;
        int64_t v = 0;
        auto [q, ec] = std::from_chars(b, e, v);
        if (ec != std::errc() || q != e || b == e)
            BadNumber(tok, p, "an integer");
        if (double(v) < PlyTypeMin(t) || double(v) > PlyTypeMax(t))
            BadNumber(tok, p, "an integer in the range of its declared type");
        return v;
    }

    double ParseScalar(std::string_view tok, PlyType t, const Prop& p) const {
        if (PlyTypeIsInteger(t))
            return double(ParseInt(tok, t, p));
        const char* b = tok.data();
        const char* e = b + tok.size();
        if (b < e && *b == '+')
            ++b;
        if (t == PlyType::Float32) {
            float f = 0;
            auto [q, ec] = std::from_chars(b, e, f);
            if (ec == std::errc::result_out_of_range)
                BadNumber(tok, p, "a number in float range");
            if (ec != std::errc() || q != e || b == e)
                BadNumber(tok, p, "a number");
            return f;
        }
        double d = 0;
        auto [q, ec] = std::from_chars(b, e, d);
        if (ec == std::errc::result_out_of_range)
            BadNumber(tok, p, "a number in double range");
        if (ec != std::errc() || q != e || b == e)
            BadNumber(tok, p, "a number");
        return d;
    }

    InputStream& in_;
    Emitter& em_;
    const uint8_t* base_ = nullptr;
    const uint8_t* p_ = nullptr;
    const uint8_t* end_ = nullptr;
    bool eof_ = false;
    uint64_t line_;
    uint64_t token_line_ = 0;
    const PlyElement* element_ = nullptr;
    uint64_t record_ = 0;
};

const char* EncodingName(PlyEncoding e) {
    switch (e) {
    case PlyEncoding::Ascii:
        return "ascii";
    case PlyEncoding::BinaryLittleEndian:
        return "binary_little_endian";
    case PlyEncoding::BinaryBigEndian:
        return "binary_big_endian";
    }
    return "?";
}

}  // namespace

void ReadPly(InputStream& in, MeshSink& sink, const ReadOptions& opt) {
    const PlyHeader h = ParsePlyHeader(in);

    MeshHeader mh;
    mh.source = in.name();
    mh.format = MeshFormat::Ply;
    mh.encoding = EncodingName(h.encoding);
    mh.comments = h.comments;
    mh.obj_info = h.obj_info;

    std::vector<Plan> plans;
    plans.reserve(h.elements.size());
    bool have_vertex = false, have_face = false, have_strips = false;
    for (const auto& e : h.elements) {
        plans.push_back(MakePlan(e, in.name(), mh));
        switch (plans.back().kind) {
        case Kind::Vertex:
            have_vertex = true;
            mh.vertex_count = e.count;
            break;
        case Kind::Face:
            have_face = true;
            mh.face_count = e.count;
            break;
        case Kind::Strips:
            have_strips = true;
            break;
        case Kind::Other:
            break;
        }
    }
    if (!have_vertex)
        InputError({in.name(), FileLoc::kNone, h.lines},
                   "PLY header declares no 'vertex' element, expected 'element vertex <count>'");
    if (have_strips) {
        mh.face_count = kUnknownCount;  // triangles are known only once the strips are read
    } else if (!have_face) {
        mh.face_count = 0;
    }

    Emitter em(sink, opt, mh.vertex_count);
    em.Reserve(mh.vertex_count, have_strips ? kUnknownCount : mh.face_count, mh.has_normals,
               mh.has_colors, mh.has_alpha, mh.has_uvs);
    sink.Begin(mh);
    if (h.encoding == PlyEncoding::Ascii) {
        AsciiBody body(in, em, h.lines);
        for (const auto& plan : plans)
            body.Read(plan);
        body.Finish();
    } else {
        const bool little = h.encoding == PlyEncoding::BinaryLittleEndian;
        if (little == (std::endian::native == std::endian::little)) {
            BinaryBody<false> body(in, em);
            for (const auto& plan : plans)
                body.Read(plan);
            body.Sync();
        } else {
            BinaryBody<true> body(in, em);
            for (const auto& plan : plans)
                body.Read(plan);
            body.Sync();
        }
    }

    MeshSummary summary;
    summary.vertex_count = em.vertices_delivered();
    summary.face_count = em.faces_delivered();
    summary.bytes_read = in.offset();
    sink.End(summary);
}

}  // namespace mebake::io
