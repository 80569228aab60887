// PLY reader and writer: exact round trips across encodings, the real scans, tristrips,
// odd layouts and every kind of malformed input (each must throw mebake::Error naming the
// file and a position). Calls ReadPly/MakePlyWriter directly so only they link.
#include "core/error.h"
#include "io/byte_stream.h"
#include "io/mesh_format.h"
#include "io/mesh_stream.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstring>
#include <fcntl.h>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <sys/stat.h>
#include <thread>
#include <unistd.h>
#include <vector>

namespace mebake::io {
namespace {

namespace fs = std::filesystem;

// Everything a reader delivers, with the contract's ordering checked on the way.
struct Mesh {
    MeshHeader header;
    MeshSummary summary;
    std::vector<Vec3f> position, normal, color;
    std::vector<float> alpha;
    std::vector<Vec2f> uv;
    std::vector<uint32_t> size;
    std::vector<uint64_t> index;
    size_t max_vertex_batch = 0, max_face_batch = 0;

    uint64_t faces() const { return size.size(); }
    bool operator==(const Mesh& o) const {
        return position == o.position && normal == o.normal && color == o.color &&
               alpha == o.alpha && uv == o.uv && size == o.size && index == o.index;
    }
};

class CollectSink : public MeshSink {
public:
    explicit CollectSink(Mesh& m) : m_(m) {}
    void Begin(const MeshHeader& h) override {
        EXPECT_FALSE(begun_);
        begun_ = true;
        m_.header = h;
    }
    void Vertices(const VertexBatch& b) override {
        EXPECT_TRUE(begun_);
        EXPECT_EQ(b.first, m_.position.size());
        EXPECT_GT(b.size(), 0u);
        EXPECT_TRUE(b.normal.empty() || b.normal.size() == b.size());
        EXPECT_TRUE(b.color.empty() || b.color.size() == b.size());
        EXPECT_TRUE(b.alpha.empty() || b.alpha.size() == b.size());
        EXPECT_TRUE(b.uv.empty() || b.uv.size() == b.size());
        m_.max_vertex_batch = std::max(m_.max_vertex_batch, b.size());
        m_.position.insert(m_.position.end(), b.position.begin(), b.position.end());
        m_.normal.insert(m_.normal.end(), b.normal.begin(), b.normal.end());
        m_.color.insert(m_.color.end(), b.color.begin(), b.color.end());
        m_.alpha.insert(m_.alpha.end(), b.alpha.begin(), b.alpha.end());
        m_.uv.insert(m_.uv.end(), b.uv.begin(), b.uv.end());
    }
    void Faces(const FaceBatch& b) override {
        EXPECT_TRUE(begun_);
        EXPECT_EQ(b.first, m_.size.size());
        uint64_t corners = 0;
        for (uint32_t n : b.size) {
            EXPECT_GE(n, 3u);
            corners += n;
        }
        EXPECT_EQ(corners, b.index.size());
        m_.max_face_batch = std::max(m_.max_face_batch, b.count());
        m_.size.insert(m_.size.end(), b.size.begin(), b.size.end());
        m_.index.insert(m_.index.end(), b.index.begin(), b.index.end());
    }
    void End(const MeshSummary& s) override {
        EXPECT_TRUE(begun_);
        EXPECT_FALSE(ended_);
        ended_ = true;
        m_.summary = s;
        EXPECT_EQ(s.vertex_count, m_.position.size());
        EXPECT_EQ(s.face_count, m_.size.size());
    }

private:
    Mesh& m_;
    bool begun_ = false, ended_ = false;
};

std::span<const uint8_t> Bytes(const std::string& s) {
    return {reinterpret_cast<const uint8_t*>(s.data()), s.size()};
}

Mesh ReadString(const std::string& bytes, const std::string& name = "case.ply",
                ReadOptions opt = {}) {
    auto in = InputStream::FromMemory(Bytes(bytes), name);
    Mesh m;
    CollectSink sink(m);
    ReadPly(*in, sink, opt);
    EXPECT_EQ(m.summary.bytes_read, in->offset());
    return m;
}

Mesh ReadFile(const std::string& path, ReadOptions opt = {}) {
    auto in = InputStream::Open(path);
    Mesh m;
    CollectSink sink(m);
    ReadPly(*in, sink, opt);
    return m;
}

// Streams `m` through a sink in batches of `batch` (vertices first unless faces_first).
void Feed(const Mesh& m, MeshSink& sink, MeshHeader h, size_t batch = 3, bool faces_first = false) {
    sink.Begin(h);
    auto vertices = [&] {
        for (size_t at = 0; at < m.position.size(); at += batch) {
            VertexBatch b;
            b.first = at;
            size_t end = std::min(m.position.size(), at + batch);
            b.position.assign(m.position.begin() + at, m.position.begin() + end);
            if (!m.normal.empty())
                b.normal.assign(m.normal.begin() + at, m.normal.begin() + end);
            if (!m.color.empty())
                b.color.assign(m.color.begin() + at, m.color.begin() + end);
            if (!m.alpha.empty())
                b.alpha.assign(m.alpha.begin() + at, m.alpha.begin() + end);
            if (!m.uv.empty())
                b.uv.assign(m.uv.begin() + at, m.uv.begin() + end);
            sink.Vertices(b);
        }
    };
    auto faces = [&] {
        size_t corner = 0;
        for (size_t at = 0; at < m.size.size(); at += batch) {
            FaceBatch b;
            b.first = at;
            for (size_t f = at; f < std::min(m.size.size(), at + batch); ++f) {
                b.size.push_back(m.size[f]);
                for (uint32_t k = 0; k < m.size[f]; ++k)
                    b.index.push_back(m.index[corner++]);
            }
            sink.Faces(b);
        }
    };
    if (faces_first) {
        faces();
        vertices();
    } else {
        vertices();
        faces();
    }
    MeshSummary s;
    s.vertex_count = m.position.size();
    s.face_count = m.size.size();
    sink.End(s);
}

std::string Write(const Mesh& m, WriteOptions opt, bool counts_known = true,
                  bool faces_first = false, size_t batch = 3) {
    std::vector<uint8_t> bytes;
    auto out = OutputStream::ToMemory(&bytes);
    auto writer = MakePlyWriter(*out, opt);
    MeshHeader h = m.header;
    if (!counts_known)
        h.vertex_count = h.face_count = kUnknownCount;
    Feed(m, *writer, h, batch, faces_first);
    return std::string(bytes.begin(), bytes.end());
}

WriteOptions Encoding(PlyEncoding e) {
    WriteOptions o;
    o.ply_encoding = e;
    return o;
}

// A small mesh with every attribute: awkward floats, uchar-exact colours, tris and quads.
Mesh Sample() {
    Mesh m;
    const int n = 11;
    for (int i = 0; i < n; ++i) {
        float f = float(i);
        m.position.push_back({0.1f * f - 3.3f, std::nextafter(1e-7f * f, 1.0f), -1234.5678f + f});
        m.normal.push_back({0.2672612f, -0.5345225f * f, 0.8017837f});
        m.color.push_back({float(i * 23 % 256) / 255.0f, 1.0f, float(255 - i) / 255.0f});
        m.alpha.push_back(float(i * 7) / 255.0f);
        m.uv.push_back({0.3f * f, 1.0f / 3.0f + f});
    }
    m.position[3] = {std::numeric_limits<float>::max(), std::numeric_limits<float>::denorm_min(),
                     -0.0f};
    m.size = {3, 4, 3, 5};
    m.index = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 0, 2, 4, 6};
    m.header.vertex_count = n;
    m.header.face_count = 4;
    m.header.has_normals = m.header.has_colors = m.header.has_alpha = m.header.has_uvs = true;
    m.header.comments = {"made by ply_test", "second  comment"};
    m.header.obj_info = {"obj info line"};
    return m;
}

// ---------------------------------------------------------------------------------------
// Round trips.

TEST(PlyRoundTrip, EveryEncodingIsExact) {
    const Mesh m = Sample();
    for (auto e :
         {PlyEncoding::Ascii, PlyEncoding::BinaryLittleEndian, PlyEncoding::BinaryBigEndian}) {
        const std::string bytes = Write(m, Encoding(e));
        const Mesh r = ReadString(bytes);
        EXPECT_TRUE(r == m) << "encoding " << int(e);
        EXPECT_EQ(r.header.vertex_count, 11u);
        EXPECT_EQ(r.header.face_count, 4u);
        EXPECT_TRUE(r.header.has_normals && r.header.has_colors && r.header.has_alpha &&
                    r.header.has_uvs);
        EXPECT_FALSE(r.header.colors_are_float);
        EXPECT_EQ(r.header.comments, m.header.comments);
        EXPECT_EQ(r.header.obj_info, m.header.obj_info);
        EXPECT_TRUE(r.header.skipped.empty());
        EXPECT_EQ(r.summary.bytes_read, bytes.size());
    }
}

TEST(PlyRoundTrip, ChainAcrossEncodingsKeepsBytes) {
    const Mesh m = Sample();
    const std::string le = Write(m, Encoding(PlyEncoding::BinaryLittleEndian));
    const std::string be = Write(ReadString(le), Encoding(PlyEncoding::BinaryBigEndian));
    const std::string ascii = Write(ReadString(be), Encoding(PlyEncoding::Ascii));
    const std::string le2 = Write(ReadString(ascii), Encoding(PlyEncoding::BinaryLittleEndian));
    EXPECT_EQ(le, le2);
    EXPECT_NE(le, be);
    EXPECT_NE(ascii.find("format ascii 1.0"), std::string::npos);
    EXPECT_NE(be.find("format binary_big_endian 1.0"), std::string::npos);
    // The header has what the layout says.
    EXPECT_NE(le.find("property uchar red"), std::string::npos);
    EXPECT_NE(le.find("property float s\nproperty float t\n"), std::string::npos);
    EXPECT_NE(le.find("property list uchar int vertex_indices"), std::string::npos);
    EXPECT_NE(le.find("comment made by ply_test\n"), std::string::npos);
}

TEST(PlyRoundTrip, FloatColorsAndDisabledAttributes) {
    Mesh m = Sample();
    m.color[2] = {0.123456789f, 0.5f, 1.0f};  // not uchar-exact: float colours keep it
    WriteOptions opt;
    opt.float_colors = true;
    Mesh r = ReadString(Write(m, opt));
    EXPECT_TRUE(r == m);
    EXPECT_TRUE(r.header.colors_are_float);

    opt = WriteOptions{};
    opt.normals = opt.colors = opt.uvs = false;
    r = ReadString(Write(m, opt));
    EXPECT_TRUE(r.normal.empty() && r.color.empty() && r.alpha.empty() && r.uv.empty());
    EXPECT_EQ(r.position, m.position);
    EXPECT_EQ(r.index, m.index);
}

TEST(PlyRoundTrip, UnknownCountsAndFacesFirstSpill) {
    const Mesh m = Sample();
    for (auto e : {PlyEncoding::Ascii, PlyEncoding::BinaryBigEndian}) {
        const std::string direct = Write(m, Encoding(e));
        EXPECT_EQ(Write(m, Encoding(e), /*counts_known=*/false), direct);
        EXPECT_EQ(Write(m, Encoding(e), true, /*faces_first=*/true), direct);
        EXPECT_EQ(Write(m, Encoding(e), false, true), direct);
    }
}

TEST(PlyRoundTrip, SmallBatchesGiveTheSameMesh) {
    const std::string bytes = Write(Sample(), {});
    ReadOptions opt;
    opt.batch_vertices = 2;
    opt.batch_faces = 3;
    const Mesh small = ReadString(bytes, "case.ply", opt);
    EXPECT_TRUE(small == ReadString(bytes));
    EXPECT_LE(small.max_vertex_batch, 2u);
    EXPECT_LE(small.max_face_batch, 3u);
}

TEST(PlyRoundTrip, ThroughRealFiles) {
    const fs::path dir = fs::path(testing::TempDir()) / "ply_test_files";
    fs::create_directories(dir);
    const Mesh m = Sample();
    for (auto e :
         {PlyEncoding::Ascii, PlyEncoding::BinaryLittleEndian, PlyEncoding::BinaryBigEndian}) {
        const std::string path = (dir / fmt::format("sample{}.ply", int(e))).string();
        {
            auto out = OutputStream::Open(path);
            auto writer = MakePlyWriter(*out, Encoding(e));
            MeshHeader h = m.header;
            h.vertex_count = h.face_count = kUnknownCount;  // spill through temp files
            Feed(m, *writer, h);
        }
        ASSERT_TRUE(fs::exists(path));
        const Mesh r = ReadFile(path);
        EXPECT_TRUE(r == m);
        EXPECT_EQ(r.summary.bytes_read, fs::file_size(path));
        EXPECT_EQ(r.header.source, path);
    }
    // Only the outputs are left: no temporaries beside them.
    size_t files = 0;
    for (const auto& entry : fs::directory_iterator(dir)) {
        EXPECT_EQ(entry.path().filename().string().rfind("sample", 0), 0u) << entry.path();
        ++files;
    }
    EXPECT_EQ(files, 3u);
    fs::remove_all(dir);
}

TEST(PlyWriter, CountMismatchAndBadIndicesAreErrors) {
    Mesh m = Sample();
    std::vector<uint8_t> bytes;
    {
        auto out = OutputStream::ToMemory(&bytes);
        auto writer = MakePlyWriter(*out, {});
        MeshHeader h = m.header;
        h.vertex_count = 12;  // one more than delivered
        EXPECT_THROW(Feed(m, *writer, h), Error);
    }
    {
        auto out = OutputStream::ToMemory(&bytes);
        auto writer = MakePlyWriter(*out, {});
        MeshHeader h = m.header;
        h.face_count = 5;
        EXPECT_THROW(Feed(m, *writer, h), Error);
    }
    {
        auto out = OutputStream::ToMemory(&bytes);
        auto writer = MakePlyWriter(*out, {});
        MeshHeader h = m.header;
        h.vertex_count = h.face_count = kUnknownCount;
        m.index[5] = 11;  // == vertex count
        EXPECT_THROW(Feed(m, *writer, h), Error);
    }
}

// ---------------------------------------------------------------------------------------
// Hand-made files.

// Little helpers to build binary bodies.
struct Bin {
    bool big = false;
    std::string s;
    template <typename T>
    Bin& Put(T v) {
        char b[sizeof(T)];
        std::memcpy(b, &v, sizeof(T));
        if (big)
            std::reverse(b, b + sizeof(T));
        s.append(b, sizeof(T));
        return *this;
    }
};

std::string Header(const char* format, const std::string& decl) {
    return std::string("ply\nformat ") + format + " 1.0\n" + decl + "end_header\n";
}

TEST(PlyRead, OddLayoutTakesTheGenericPath) {
    const std::string decl = "comment odd\n"
                             "element vertex 2\n"
                             "property double x\nproperty short y\nproperty int z\n"
                             "property list uchar float junk\n"
                             "property ushort red\nproperty uchar green\nproperty float blue\n"
                             "property float u\nproperty float v\nproperty float confidence\n"
                             "element face 2\n"
                             "property uchar flags\n"
                             "property list uint short vertex_index\n"
                             "property list uchar float texcoord\n"
                             "element extra 3\nproperty list int double stuff\n";
    for (bool big : {false, true}) {
        Bin b;
        b.big = big;
        for (int i = 0; i < 2; ++i) {
            b.Put(double(1.5 + i)).Put(int16_t(-7 - i)).Put(int32_t(100000 + i));
            b.Put(uint8_t(2)).Put(1.0f).Put(2.0f);
            b.Put(uint16_t(65535)).Put(uint8_t(51)).Put(0.25f);
            b.Put(0.5f).Put(0.75f).Put(9.0f);
        }
        b.Put(uint8_t(1)).Put(uint32_t(3)).Put(int16_t(0)).Put(int16_t(1)).Put(int16_t(1));
        b.Put(uint8_t(0));
        b.Put(uint8_t(1)).Put(uint32_t(4)).Put(int16_t(1)).Put(int16_t(0)).Put(int16_t(1));
        b.Put(int16_t(0));
        b.Put(uint8_t(2)).Put(1.0f).Put(2.0f);
        for (int i = 0; i < 3; ++i)
            b.Put(int32_t(1)).Put(3.0);
        const Mesh m =
            ReadString(Header(big ? "binary_big_endian" : "binary_little_endian", decl) + b.s);
        ASSERT_EQ(m.position.size(), 2u);
        EXPECT_EQ(m.position[1], Vec3f(2.5f, -8.0f, 100001.0f));
        EXPECT_EQ(m.color[0], Vec3f(1.0f, 0.2f, 0.25f));
        EXPECT_EQ(m.uv[1], Vec2f(0.5f, 0.75f));
        EXPECT_TRUE(m.header.has_colors && m.header.has_uvs && !m.header.has_normals);
        EXPECT_FALSE(m.header.colors_are_float);  // red is ushort
        EXPECT_EQ(m.size, (std::vector<uint32_t>{3, 4}));
        EXPECT_EQ(m.index, (std::vector<uint64_t>{0, 1, 1, 1, 0, 1, 0}));
        EXPECT_EQ(m.header.skipped,
                  (std::vector<std::string>{"vertex.junk", "vertex.confidence", "face.flags",
                                            "face.texcoord", "extra"}));
        EXPECT_EQ(m.header.comments, std::vector<std::string>{"odd"});
    }
}

TEST(PlyRead, AsciiWithCrLfAndSkippedLists) {
    const std::string text =
        "ply\r\nformat ascii 1.0\r\nobj_info made by hand\r\nelement vertex 3\r\n"
        "property float x\r\nproperty float y\r\nproperty float z\r\n"
        "property list uchar int neighbours\r\n"
        "property uchar red\r\nproperty uchar green\r\nproperty uchar blue\r\n"
        "element face 1\r\nproperty list uchar uint vertex_indices\r\nend_header\r\n"
        "0 0 0 2 1 2 255 0 0\r\n1 0 0 0 0 255 0\r\n+0 1e0 -0.5 1 0 0 0 255\r\n3 0 1 2\r\n";
    const Mesh m = ReadString(text);
    EXPECT_EQ(m.position[2], Vec3f(0, 1, -0.5f));
    EXPECT_EQ(m.color[1], Vec3f(0, 1, 0));
    EXPECT_EQ(m.index, (std::vector<uint64_t>{0, 1, 2}));
    EXPECT_EQ(m.header.obj_info, std::vector<std::string>{"made by hand"});
    EXPECT_EQ(m.header.skipped, std::vector<std::string>{"vertex.neighbours"});
}

TEST(PlyRead, FacesBeforeVertices) {
    const std::string text =
        "ply\nformat ascii 1.0\nelement face 1\nproperty list uchar int vertex_indices\n"
        "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
        "end_header\n3 2 1 0\n0 0 0\n1 0 0\n0 1 0\n";
    const Mesh m = ReadString(text);
    EXPECT_EQ(m.index, (std::vector<uint64_t>{2, 1, 0}));
    EXPECT_EQ(m.position.size(), 3u);
    // The writer streams vertices and holds the early faces back.
    const std::string le = Write(m, {});
    EXPECT_TRUE(ReadString(le) == m);
}

// Expected triangles: strip 0 1 2 3 -> (0,1,2) (2,1,3); strip 4 5 0 -> (4,5,0);
// strip 1 2 2 3 4 (a swap) -> i=0 (1,2,2) and i=1 (2,2,3) dropped, i=2 (2,3,4);
// second record 5 4 3 -> (5,4,3).
const std::vector<uint64_t> kStripTriangles = {0, 1, 2, 2, 1, 3, 4, 5, 0, 2, 3, 4, 5, 4, 3};

TEST(PlyRead, TristripsAscii) {
    const std::string text =
        "ply\nformat ascii 1.0\nelement vertex 6\nproperty float x\nproperty float y\n"
        "property float z\nelement tristrips 2\nproperty list int int vertex_indices\n"
        "end_header\n0 0 0\n1 0 0\n0 1 0\n1 1 0\n0 2 0\n1 2 0\n"
        "14 0 1 2 3 -1 4 5 0 -1 1 2 2 3 4\n3 5 4 3\n";
    const Mesh m = ReadString(text);
    EXPECT_EQ(m.index, kStripTriangles);
    EXPECT_EQ(m.size, std::vector<uint32_t>(5, 3));
    EXPECT_EQ(m.header.face_count, kUnknownCount);
}

TEST(PlyRead, TristripsBinaryInSmallBatches) {
    for (bool big : {false, true}) {
        Bin b;
        b.big = big;
        for (int i = 0; i < 18; ++i)
            b.Put(float(i));
        const int32_t strip[] = {0, 1, 2, 3, -1, 4, 5, 0, -1, 1, 2, 2, 3, 4};
        b.Put(int32_t(14));
        for (int32_t v : strip)
            b.Put(v);
        b.Put(int32_t(3)).Put(int32_t(5)).Put(int32_t(4)).Put(int32_t(3));
        const std::string text =
            Header(big ? "binary_big_endian" : "binary_little_endian",
                   "element vertex 6\nproperty float x\nproperty float y\nproperty float z\n"
                   "element tristrips 2\nproperty list int int vertex_indices\n") +
            b.s;
        ReadOptions opt;
        opt.batch_faces = 2;
        const Mesh m = ReadString(text, "strips.ply", opt);
        EXPECT_EQ(m.index, kStripTriangles);
        EXPECT_LE(m.max_face_batch, 2u);
    }
}

// ---------------------------------------------------------------------------------------
// Malformed input: Error naming the file and a position.

void ExpectError(const std::string& bytes, const std::string& needle = "") {
    try {
        ReadString(bytes, "bad.ply");
        ADD_FAILURE() << "no error for:\n" << bytes.substr(0, 300);
    } catch (const Error& e) {
        const std::string msg = e.what();
        EXPECT_EQ(e.kind(), ErrorKind::Input) << msg;
        EXPECT_EQ(msg.rfind("bad.ply: ", 0), 0u) << msg;
        EXPECT_TRUE(msg.find(": line ") != std::string::npos ||
                    msg.find(": byte ") != std::string::npos)
            << msg;
        if (!needle.empty()) {
            EXPECT_NE(msg.find(needle), std::string::npos) << msg;
        }
    }
}

const char* kTriDecl = "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                       "element face 1\nproperty list uchar int vertex_indices\n";

std::string BinaryTriangle(bool big = false, float x0 = 0.0f, int32_t i2 = 2, uint8_t count = 3) {
    Bin b;
    b.big = big;
    b.Put(x0).Put(0.0f).Put(0.0f).Put(1.0f).Put(0.0f).Put(0.0f).Put(0.0f).Put(1.0f).Put(0.0f);
    b.Put(count).Put(int32_t(0)).Put(int32_t(1)).Put(i2);
    return Header(big ? "binary_big_endian" : "binary_little_endian", kTriDecl) + b.s;
}

std::string AsciiTriangle(const std::string& x0 = "0", const std::string& face = "3 0 1 2") {
    return Header("ascii", kTriDecl) + x0 + " 0 0\n1 0 0\n0 1 0\n" + face + "\n";
}

TEST(PlyMalformed, ValidBaselinesRead) {
    EXPECT_EQ(ReadString(BinaryTriangle()).index.size(), 3u);
    EXPECT_EQ(ReadString(BinaryTriangle(true)).index.size(), 3u);
    EXPECT_EQ(ReadString(AsciiTriangle()).index.size(), 3u);
}

TEST(PlyMalformed, Truncated) {
    const std::string bin = BinaryTriangle();
    for (size_t cut : {1, 4, 13, 20})
        ExpectError(bin.substr(0, bin.size() - cut), "end of data");
    const std::string text = AsciiTriangle();
    ExpectError(text.substr(0, text.size() - 4), "end of file");
    ExpectError(text.substr(0, text.size() - 12), "end of file");
}

TEST(PlyMalformed, HeaderCountLargerThanData) {
    std::string text = AsciiTriangle();
    text.replace(text.find("vertex 3"), 8, "vertex 4");
    ExpectError(text);
    std::string bin = BinaryTriangle();
    bin.replace(bin.find("face 1"), 6, "face 2");
    ExpectError(bin, "record 1 of 2");
}

TEST(PlyMalformed, Indices) {
    ExpectError(BinaryTriangle(false, 0, 3), "out of range");
    ExpectError(BinaryTriangle(true, 0, -1), "negative");
    ExpectError(AsciiTriangle("0", "3 0 1 3"), "out of range");
    ExpectError(AsciiTriangle("0", "3 0 -2 1"), "negative");
    ExpectError(AsciiTriangle("0", "3 0 1 2.0"));
}

std::string ErrorOf(const std::string& bytes) {
    try {
        ReadString(bytes, "bad.ply");
    } catch (const Error& e) {
        return e.what();
    }
    return "no error";
}

TEST(PlyMalformed, ErrorsNameThePlace) {
    // Binary: the third of three triangles names vertex 7; its byte offset is exact.
    const std::string header =
        Header("binary_little_endian", "element vertex 3\nproperty float x\nproperty float y\n"
                                       "property float z\nelement face 3\n"
                                       "property list uchar int vertex_indices\n");
    Bin b;
    for (int i = 0; i < 9; ++i)
        b.Put(0.0f);
    for (int f = 0; f < 3; ++f)
        b.Put(uint8_t(3)).Put(int32_t(0)).Put(int32_t(1)).Put(int32_t(f == 2 ? 7 : 2));
    const size_t offset = header.size() + 36 + 2 * 13 + 1 + 2 * 4;
    EXPECT_EQ(ErrorOf(header + b.s),
              fmt::format("bad.ply: byte {}: face 2: vertex index 7 out of range, the header "
                          "declares 3 vertices",
                          offset));
    // ASCII: line numbers count the header (9 lines here) and the body.
    EXPECT_EQ(ErrorOf(AsciiTriangle("0", "3 0 1 5")),
              "bad.ply: line 13: face 0: vertex index 5 out of range, the header declares 3 "
              "vertices");
    EXPECT_EQ(ErrorOf(AsciiTriangle("abc")).rfind("bad.ply: line 10: vertex 0, property 'x'", 0),
              0u);
    // A non-finite coordinate in binary names the vertex record.
    const size_t body = Header("binary_little_endian", kTriDecl).size();
    EXPECT_EQ(ErrorOf(BinaryTriangle(false, std::numeric_limits<float>::infinity())),
              fmt::format("bad.ply: byte {}: vertex 0: x = inf is not a finite float", body));
}

TEST(PlyMalformed, NonFiniteCoordinates) {
    ExpectError(BinaryTriangle(false, std::numeric_limits<float>::quiet_NaN()), "finite");
    ExpectError(BinaryTriangle(true, std::numeric_limits<float>::infinity()), "finite");
    ExpectError(AsciiTriangle("nan"), "finite");
    ExpectError(AsciiTriangle("-inf"), "finite");
    ExpectError(AsciiTriangle("1e39"), "float range");
    // A double too large for a float is rejected too.
    Bin b;
    b.Put(1e300).Put(0.0).Put(0.0);
    ExpectError(
        Header("binary_little_endian", "element vertex 1\nproperty double x\nproperty double y\n"
                                       "property double z\n") +
            b.s,
        "finite");
}

TEST(PlyMalformed, ListCounts) {
    ExpectError(BinaryTriangle(false, 0, 2, 0), "at least 3");
    ExpectError(BinaryTriangle(false, 0, 2, 2), "at least 3");
    ExpectError(AsciiTriangle("0", "0"), "at least 3");
    Bin b;
    b.Put(0.0f).Put(0.0f).Put(0.0f).Put(int32_t(INT32_MIN)).Put(int32_t(0));
    ExpectError(Header("binary_little_endian",
                       "element vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
                       "element face 1\nproperty list int int vertex_indices\n") +
                    b.s,
                "negative");
    Bin c;
    c.Put(0.0f).Put(0.0f).Put(0.0f).Put(uint32_t(1) << 31).Put(int32_t(0));
    ExpectError(Header("binary_little_endian",
                       "element vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
                       "element face 1\nproperty list uint int vertex_indices\n") +
                    c.s,
                "at most 65536");
    ExpectError(AsciiTriangle("0", "2147483648 0 1 2"));  // beyond uchar
}

TEST(PlyMalformed, Headers) {
    ExpectError("", "empty file");
    ExpectError("plx\nformat ascii 1.0\nend_header\n", "not a PLY");
    ExpectError("ply\nformat binary_middle_endian 1.0\nelement vertex 0\nend_header\n",
                "unknown PLY format");
    ExpectError("ply\nformat ascii 2.0\nend_header\n", "version");
    ExpectError("ply\nproperty float x\nformat ascii 1.0\nend_header\n", "before any 'element'");
    ExpectError("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                "property float z\n0 0 0\n",
                "unexpected '0'");
    ExpectError("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n",
                "end_header");
    ExpectError(Header("ascii", "element vertex 0\nproperty float x\nproperty float y\n"
                                "property float z\nelement face 0\n"
                                "property list float int vertex_indices\n"),
                "integer type");
    ExpectError(Header("ascii", "element vertex 0\nproperty float x\nproperty float y\n"
                                "property float z\nelement face 0\n"
                                "property list uchar float vertex_indices\n"),
                "integer type");
    ExpectError(Header("ascii", "element vertex 0\nproperty float x\nproperty float y\n"
                                "property float z\nelement face 0\nproperty int vertex_indices\n"),
                "must be a list");
    ExpectError(Header("ascii", "element vertex 0\nproperty float x\nproperty float y\n"), "'z'");
    ExpectError(Header("ascii", "element vertex 0\nproperty float x\nproperty float x\n"), "twice");
    ExpectError(Header("ascii", "element vertex 0\nproperty quad x\n"), "unknown PLY type");
    ExpectError(Header("ascii", "element vertex -1\n"), "count");
    ExpectError(Header("ascii", "element vertex 99999999999999999999\n"), "count");
    ExpectError(Header("ascii", "element face 0\nproperty list uchar int vertex_indices\n"),
                "no 'vertex' element");
    ExpectError("ply\nelement vertex 0\nend_header\n", "no 'format'");
}

TEST(PlyMalformed, BinaryGarbage) {
    std::string garbage;
    uint32_t x = 12345;
    for (int i = 0; i < 5000; ++i) {
        x = x * 1664525u + 1013904223u;
        garbage.push_back(char(x >> 24));
    }
    ExpectError(garbage, "not a PLY");
    ExpectError("ply\n" + garbage);
    ExpectError(Header("binary_little_endian", kTriDecl) + garbage.substr(0, 40));
}

TEST(PlyMalformed, HugeHeaderCountsFailFast) {
    const auto start = std::chrono::steady_clock::now();
    const std::string decl =
        "element vertex 1099511627776\nproperty float x\nproperty float y\nproperty float z\n"
        "element face 1099511627776\nproperty list uchar int vertex_indices\n";
    Bin b;
    for (int i = 0; i < 9; ++i)
        b.Put(1.0f);
    ExpectError(Header("binary_little_endian", decl) + b.s, "record 3 of 1099511627776");
    ExpectError(Header("ascii", decl) + "0 0 0\n1 1 1\n", "record 2 of 1099511627776");
    // A skipped element whose byte size exceeds 2^64, and one with no properties at all.
    ExpectError(Header("binary_little_endian",
                       "element vertex 0\nproperty float x\nproperty float y\nproperty float z\n"
                       "element blob 4611686018427387904\nproperty double a\nproperty double b\n"),
                "more than any file");
    const Mesh empty =
        ReadString(Header("ascii", "element vertex 0\nproperty float x\nproperty float y\n"
                                   "property float z\nelement nothing 1099511627776\n"));
    EXPECT_EQ(empty.position.size(), 0u);
    ExpectError(Header("ascii", "element vertex 1\nproperty float x\nproperty float y\n"
                                "property float z\nelement blob 1099511627776\nproperty int a\n") +
                "0 0 0\n1 2 3\n");
    EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(2));
}

// ---------------------------------------------------------------------------------------
// The real scans (see ../shared/data/README.md).

struct Scan {
    const char* file;
    uint64_t vertices, faces;
    const char* encoding;
};

TEST(PlyScans, CountsMatchTheDataReadme) {
    const Scan scans[] = {
        {"igea.ply", 134345, 268686, "binary_little_endian"},
        {"horse.ply", 48485, 96966, "binary_big_endian"},
        {"bun_zipper.ply", 35947, 69451, "ascii"},
        {"bun_zipper_res2.ply", 8171, 16301, "ascii"},
        {"bun_zipper_res3.ply", 1889, 3851, "ascii"},
        {"bun_zipper_res4.ply", 453, 948, "ascii"},
        {"lucy.ply", 49987, 99970, "binary_little_endian"},
        {"turbineblade.ply", 99519, 199034, "binary_little_endian"},
        {"pepper.ply", 14980, 29956, "binary_little_endian"},
    };
    int found = 0;
    for (const Scan& s : scans) {
        const std::string path = std::string(MEBAKE_SHARED_DATA) + "/scans/" + s.file;
        if (!fs::exists(path))
            continue;
        ++found;
        SCOPED_TRACE(s.file);
        ReadOptions opt;
        opt.batch_vertices = 10000;  // several batches each
        opt.batch_faces = 7000;
        const Mesh m = ReadFile(path, opt);
        EXPECT_EQ(m.position.size(), s.vertices);
        EXPECT_EQ(m.faces(), s.faces);
        EXPECT_EQ(m.index.size(), 3 * s.faces);  // all triangles
        EXPECT_EQ(m.header.encoding, s.encoding);
        EXPECT_EQ(m.summary.bytes_read, fs::file_size(path));
        uint64_t max_index = 0;
        for (uint64_t v : m.index)
            max_index = std::max(max_index, v);
        EXPECT_LT(max_index, s.vertices);
        // Batching does not change what is read, nor do the stream's buffer boundaries.
        EXPECT_TRUE(ReadFile(path) == m);
        std::ifstream f(path, std::ios::binary);
        const std::string bytes((std::istreambuf_iterator<char>(f)), {});
        EXPECT_TRUE(ReadString(bytes) == m);
        // And the writer reproduces it exactly in every encoding.
        for (auto e : {PlyEncoding::BinaryLittleEndian, PlyEncoding::Ascii}) {
            Mesh copy = m;
            copy.header.face_count = m.faces();  // tristrips: the writer needs the count
            EXPECT_TRUE(ReadString(Write(copy, Encoding(e), true, false, 4096)) == m);
        }
    }
    if (found == 0)
        GTEST_SKIP() << "no scans in " << MEBAKE_SHARED_DATA << "/scans";
}

// A pipe delivers data in pieces, so tokens, records and lists straddle the reader's
// windows at arbitrary places; the result must equal reading the bytes from memory.
TEST(PlyScans, ThroughAPipeInOddChunks) {
    const std::string dir = std::string(MEBAKE_SHARED_DATA) + "/scans/";
    const fs::path fifo_dir = fs::path(testing::TempDir()) / "ply_test_fifo";
    fs::create_directories(fifo_dir);
    int found = 0;
    for (const char* scan : {"bun_zipper_res2.ply", "horse.ply", "igea.ply"}) {
        if (!fs::exists(dir + scan))
            continue;
        ++found;
        SCOPED_TRACE(scan);
        std::ifstream f(dir + scan, std::ios::binary);
        const std::string bytes((std::istreambuf_iterator<char>(f)), {});
        const std::string fifo = (fifo_dir / "pipe").string();
        fs::remove(fifo);
        ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
        std::thread writer([&] {
            int fd = ::open(fifo.c_str(), O_WRONLY);
            size_t at = 0, chunk = 1;
            while (fd >= 0 && at < bytes.size()) {
                size_t n = std::min(bytes.size() - at, chunk);
                ssize_t k = ::write(fd, bytes.data() + at, n);
                if (k <= 0)
                    break;
                at += size_t(k);
                chunk = chunk * 7 % 100003 + 1;  // 1, 8, 57, ... up to ~100 KB
            }
            if (fd >= 0)
                ::close(fd);
        });
        Mesh piped;
        try {
            piped = ReadFile(fifo);
        } catch (...) {
            writer.join();
            throw;
        }
        writer.join();
        EXPECT_TRUE(piped == ReadString(bytes));
        EXPECT_EQ(piped.summary.bytes_read, bytes.size());
    }
    fs::remove_all(fifo_dir);
    if (found == 0)
        GTEST_SKIP() << "no scans in " << dir;
}

TEST(PlyScans, HeaderDetails) {
    const std::string dir = std::string(MEBAKE_SHARED_DATA) + "/scans/";
    if (!fs::exists(dir + "horse.ply") || !fs::exists(dir + "bun_zipper.ply") ||
        !fs::exists(dir + "pepper.ply") || !fs::exists(dir + "igea.ply"))
        GTEST_SKIP() << "scans missing in " << dir;
    const Mesh horse = ReadFile(dir + "horse.ply");
    EXPECT_TRUE(horse.header.has_colors);
    EXPECT_FALSE(horse.header.colors_are_float);
    EXPECT_EQ(horse.color.size(), horse.position.size());
    EXPECT_EQ(horse.header.comments.size(), 2u);
    EXPECT_EQ(horse.header.skipped, std::vector<std::string>{"vertex.confidence"});

    const Mesh bunny = ReadFile(dir + "bun_zipper.ply");
    EXPECT_EQ(bunny.header.skipped,
              (std::vector<std::string>{"vertex.confidence", "vertex.intensity"}));
    EXPECT_EQ(bunny.header.comments, std::vector<std::string>{"zipper output"});
    EXPECT_EQ(bunny.position[0], Vec3f(-0.0378297f, 0.12794f, 0.00447467f));

    const Mesh pepper = ReadFile(dir + "pepper.ply");
    EXPECT_EQ(pepper.header.skipped,
              (std::vector<std::string>{"multi_texture_vertex", "multi_texture_face"}));
    EXPECT_FALSE(pepper.header.has_uvs);

    const Mesh igea = ReadFile(dir + "igea.ply");
    EXPECT_EQ(igea.header.face_count, kUnknownCount);
    EXPECT_EQ(igea.header.vertex_count, 134345u);
}

// ---------------------------------------------------------------------------------------
// Throughput (run by hand: --gtest_also_run_disabled_tests --gtest_filter=*Throughput*).

class NullSink : public MeshSink {
public:
    void Begin(const MeshHeader&) override {}
    void Vertices(const VertexBatch& b) override { vertices += b.size(); }
    void Faces(const FaceBatch& b) override { faces += b.count(); }
    void End(const MeshSummary& s) override { bytes = s.bytes_read; }
    uint64_t vertices = 0, faces = 0, bytes = 0;
};

void TimeRead(const std::string& path) {
    double best = 1e9;
    NullSink sink;
    for (int rep = 0; rep < 100; ++rep) {
        auto in = InputStream::Open(path);
        sink = NullSink{};
        auto t0 = std::chrono::steady_clock::now();
        ReadPly(*in, sink, {});
        best = std::min(
            best, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    }
    std::printf("%s: %.1f MB in %.3f s: %.0f MB/s, %.1f M faces/s (%lu faces)\n", path.c_str(),
                double(sink.bytes) / 1e6, best, double(sink.bytes) / 1e6 / best,
                double(sink.faces) / 1e6 / best, (unsigned long)sink.faces);
}

TEST(PlyBench, DISABLED_Throughput) {
    for (const char* scan : {"igea.ply", "horse.ply", "bun_zipper.ply"}) {
        const std::string path = std::string(MEBAKE_SHARED_DATA) + "/scans/" + scan;
        if (fs::exists(path))
            TimeRead(path);
    }
    const char* tmp = std::getenv("TMPDIR");
    const std::string big = std::string(tmp && *tmp ? tmp : "/tmp") + "/mebake_ply_bench.ply";
    if (!fs::exists(big)) {
        // A 1500 x 1500 grid with normals and colours: 2.25 M vertices, 4.5 M triangles.
        const uint32_t n = 1500;
        auto out = OutputStream::Open(big);
        auto writer = MakePlyWriter(*out, {});
        MeshHeader h;
        h.vertex_count = uint64_t(n) * n;
        h.face_count = 2 * uint64_t(n - 1) * (n - 1);
        h.has_normals = h.has_colors = true;
        writer->Begin(h);
        VertexBatch vb;
        for (uint32_t y = 0; y < n; ++y) {
            vb.Clear();
            vb.first = uint64_t(y) * n;
            for (uint32_t x = 0; x < n; ++x) {
                vb.position.push_back({float(x), float(y), std::sin(0.01f * float(x * y))});
                vb.normal.push_back({0, 0, 1});
                vb.color.push_back({float(x % 256) / 255.0f, float(y % 256) / 255.0f, 0.5f});
            }
            writer->Vertices(vb);
        }
        FaceBatch fb;
        for (uint32_t y = 0; y + 1 < n; ++y) {
            fb.Clear();
            fb.first = 2 * uint64_t(y) * (n - 1);
            for (uint32_t x = 0; x + 1 < n; ++x) {
                const uint64_t v = uint64_t(y) * n + x;
                fb.size.insert(fb.size.end(), {3, 3});
                fb.index.insert(fb.index.end(), {v, v + 1, v + n, v + 1, v + n + 1, v + n});
            }
            writer->Faces(fb);
        }
        writer->End({});
    }
    TimeRead(big);
}

}  // namespace
}  // namespace mebake::io
