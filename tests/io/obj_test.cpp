// Tests of the streaming OBJ reader and writer, on small cases and on the real scenes
// and scans in ../shared/data (skipped when absent).
#include "io/mesh_format.h"
#include "text_collect_sink.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <unistd.h>

namespace mebake::io {
namespace {

using testing::Collected;
using testing::ErrorOf;
using testing::ReadPath;
using testing::ReadText;
using testing::SharedData;

Collected Obj(std::string_view text, const ReadOptions& opt = {}) {
    return ReadText(ReadObj, text, opt, "test.obj");
}
std::string ObjError(std::string_view text) {
    return ErrorOf(ReadObj, text, "bad.obj");
}

// An independent, deliberately simple OBJ reader (iostreams, whole file in memory): the
// positions of every polygon's corners, to compare with the streaming reader.
struct Reference {
    std::vector<Vec3f> position;
    std::vector<std::vector<Vec3f>> polygons;
};

Reference ReferenceRead(const std::string& path) {
    Reference r;
    std::ifstream f(path);
    std::string line;
    while (std::getline(f, line)) {
        std::istringstream ss(line);
        std::string kw;
        ss >> kw;
        if (kw == "v") {
            std::string x, y, z;
            ss >> x >> y >> z;
            r.position.push_back(Vec3f(std::strtof(x.c_str(), nullptr),
                                       std::strtof(y.c_str(), nullptr),
                                       std::strtof(z.c_str(), nullptr)));
        } else if (kw == "f") {
            std::vector<Vec3f> poly;
            std::string corner;
            while (ss >> corner) {
                long i = std::stol(corner.substr(0, corner.find('/')));
                size_t k = i > 0 ? size_t(i - 1) : size_t(long(r.position.size()) + i);
                poly.push_back(r.position.at(k));
            }
            r.polygons.push_back(poly);
        }
    }
    return r;
}

// How many lines of `path` start with the statement `kw`.
size_t CountStatements(const std::string& path, const std::string& kw) {
    std::ifstream f(path);
    std::string line, first;
    size_t n = 0;
    while (std::getline(f, line)) {
        std::istringstream ss(line);
        if (ss >> first && first == kw)
            ++n;
    }
    return n;
}

// Compares the streaming reader's polygons with the reference, corner by corner.
void ExpectMatchesReference(const std::string& path) {
    SCOPED_TRACE(path);
    Collected c = ReadPath(ReadObj, path);
    Reference r = ReferenceRead(path);
    EXPECT_EQ(c.position.size(), r.position.size());
    ASSERT_EQ(c.faces(), r.polygons.size());
    size_t at = 0;
    for (size_t f = 0; f < c.faces(); ++f) {
        ASSERT_EQ(c.face_size[f], r.polygons[f].size()) << "polygon " << f;
        for (size_t k = 0; k < c.face_size[f]; ++k) {
            ASSERT_EQ(c.position[c.index[at + k]], r.polygons[f][k]) << "polygon " << f;
        }
        at += c.face_size[f];
    }
}

// The material name of polygon f.
std::string MaterialOf(const Collected& c, size_t f) {
    return c.summary.materials.at(c.material.at(f));
}

TEST(ObjReader, VerticesAndAllFaceForms) {
    Collected c = Obj("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0.5 2 0 1.0\n"
                      "vt 0 0\nvt 1 0\nvt 1 1 0\n"
                      "vn 0 0 1\n"
                      "f 1 2 3\n"
                      "f 1/1 2/2 3/3\n"
                      "f 1//1 3//1 4//1\n"
                      "f 1/1/1 2/2/1 3/3/1 4/1/1\n"
                      "f -5 -4 -3 -2 -1\n"
                      "f -5/-3/-1 -4/-2/-1 -3/-1/-1\n");
    ASSERT_EQ(c.position.size(), 5u);
    EXPECT_EQ(c.position[4], Vec3f(0.5f, 2, 0));  // w dropped
    EXPECT_FALSE(c.header.has_colors);
    EXPECT_EQ(c.header.format, MeshFormat::Obj);
    EXPECT_EQ(c.summary.corner_uv_count, 3u);
    EXPECT_EQ(c.summary.corner_normal_count, 1u);
    ASSERT_EQ(c.faces(), 6u);
    EXPECT_EQ(c.face_size, (std::vector<uint32_t>{3, 3, 3, 4, 5, 3}));
    EXPECT_EQ(c.index, (std::vector<uint64_t>{0, 1, 2, 0, 1, 2, 0, 2, 3, 0, 1,
                                              2, 3, 0, 1, 2, 3, 4, 0, 1, 2}));
    // No usemtl: every polygon has the unnamed material.
    EXPECT_EQ(c.summary.materials, std::vector<std::string>{""});
    EXPECT_EQ(c.material, std::vector<uint32_t>(6, 0));
}

TEST(ObjReader, ByteOrderMarkAndTabs) {
    Collected c = Obj("\xEF\xBB\xBFv\t0 0 0\nv 1\t0 0\nv 0 1 0\nf\t1 2 3\n");
    EXPECT_EQ(c.position.size(), 3u);
    EXPECT_EQ(c.faces(), 1u);
}

TEST(ObjReader, RelativeIndicesCountFromWhereTheFaceIs) {
    Collected c = Obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\nv 5 5 5\nf -4 -3 -1\n");
    EXPECT_EQ(c.index, (std::vector<uint64_t>{0, 1, 2, 0, 1, 3}));
}

TEST(ObjReader, VertexColoursFollowTheFirstVertex) {
    Collected c = Obj("v 0 0 0 1 0.5 0\nv 1 0 0\nv 0 1 0 2 -1 0.25\nf 1 2 3\n");
    ASSERT_TRUE(c.header.has_colors);
    ASSERT_EQ(c.color.size(), 3u);
    EXPECT_EQ(c.color[0], Vec3f(1, 0.5f, 0));
    EXPECT_EQ(c.color[1], Vec3f(1, 1, 1));      // missing: white
    EXPECT_EQ(c.color[2], Vec3f(1, 0, 0.25f));  // clamped to [0,1]

    Collected d = Obj("v 0 0 0\nv 1 0 0 1 0 0\nv 0 1 0\nf 1 2 3\n");
    EXPECT_FALSE(d.header.has_colors);
    EXPECT_TRUE(d.color.empty());
    EXPECT_EQ(d.position[1], Vec3f(1, 0, 0));
}

TEST(ObjReader, GroupsMaterialsAndLibraries) {
    Collected c = Obj("# first comment\n#second\n\nmtllib a.mtl b.mtl\n"
                      "v 0 0 0\nv 1 0 0\nv 0 1 0\n"
                      "f 1 2 3\n"
                      "o thing one\ng left right\nusemtl red\nf 1 2 3\n"
                      "g right\nusemtl blue # a comment\nf 1 2 3\n"
                      "usemtl red\nmtllib a.mtl\nf 1 2 3\n"
                      "# not a header comment\n");
    EXPECT_EQ(c.header.comments, (std::vector<std::string>{"first comment", "second"}));
    EXPECT_EQ(c.summary.mtllibs, (std::vector<std::string>{"a.mtl", "b.mtl"}));
    EXPECT_EQ(c.summary.groups, (std::vector<std::string>{"thing one", "left", "right"}));
    EXPECT_EQ(c.summary.materials, (std::vector<std::string>{"", "red", "blue"}));
    EXPECT_EQ(c.material, (std::vector<uint32_t>{0, 1, 2, 1}));
}

TEST(ObjReader, SkipsUnknownStatementsOnceAndHandlesContinuations) {
    Collected c = Obj("v 0 0 0\nv 1 0 0\nv 0 1 0\r\nv 1 1 0\n"
                      "vp 0.5\nl 1 2\np 1\ncstype bezier\nl 2 3\ns 1\ns off\n"
                      "f 1 2 \\\n  3 \\\n 4\n"
                      "v 2 \\\n 2 2\n"
                      "f 1 2 5\n");
    EXPECT_EQ(c.header.skipped, (std::vector<std::string>{"vp", "l", "p", "cstype"}));
    EXPECT_EQ(c.face_size, (std::vector<uint32_t>{4, 3}));
    EXPECT_EQ(c.position.size(), 5u);
    EXPECT_EQ(c.position[4], Vec3f(2, 2, 2));
    EXPECT_EQ(c.position[2], Vec3f(0, 1, 0));  // CRLF line
}

TEST(ObjReader, NumberSyntax) {
    Collected c = Obj("v +1.5 -2e-3 .25\nv 1e-50 -1e-60 3.\nv 1E2 -0 1e-400\n");
    ASSERT_EQ(c.position.size(), 3u);
    EXPECT_EQ(c.position[0], Vec3f(1.5f, -2e-3f, 0.25f));
    EXPECT_EQ(c.position[1], Vec3f(0, 0, 3));  // underflow: zero
    EXPECT_TRUE(std::signbit(c.position[1].y));
    EXPECT_EQ(c.position[2], Vec3f(100, 0, 0));
    EXPECT_NE(ObjError("v 0x10 0 0\n").find("malformed number '0x10'"), std::string::npos);
    EXPECT_NE(ObjError("v 1,5 0 0\n").find("malformed"), std::string::npos);
    EXPECT_NE(ObjError("v --1 0 0\n").find("malformed"), std::string::npos);
    EXPECT_NE(ObjError("v 1e400 0 0\n").find("out of float range"), std::string::npos);
}

TEST(ObjReader, SmallBatchesDeliverTheSameMesh) {
    std::string text;
    for (int i = 0; i < 50; ++i) {
        text += fmt::format("v {} {} 0\nv {} {} 1\nv {} {} 2\n", i, i, i, i + 1, i + 1, i);
        text += "f -3 -2 -1\n";
        if (i % 7 == 0)
            text += fmt::format("usemtl m{}\n", i % 3);
    }
    Collected big = Obj(text);
    for (size_t bv : {1, 2, 5}) {
        for (size_t bf : {1, 3}) {
            ReadOptions opt;
            opt.batch_vertices = bv;
            opt.batch_faces = bf;
            Collected small = Obj(text, opt);
            EXPECT_EQ(small.position, big.position);
            EXPECT_EQ(small.index, big.index);
            EXPECT_EQ(small.material, big.material);
            EXPECT_GT(small.face_batches, 10u);
        }
    }
    EXPECT_EQ(big.summary.materials, (std::vector<std::string>{"", "m0", "m1", "m2"}));
}

// Every malformed input is an input error naming the file and the line (or byte).
TEST(ObjReader, Errors) {
    struct Case {
        std::string text, where, what;
    };
    std::string tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
    std::vector<Case> cases = {
        {"v 1 x 3\n", "line 1", "malformed number"},
        {"v 1 2 3\nv 1 2 3e\n", "line 2", "malformed number"},
        {"v nan 0 0\n", "line 1", "not finite"},
        {"v 0 inf 0\n", "line 1", "not finite"},
        {"v 0 0 1e39\n", "line 1", "out of float range"},
        {"v 1 2\n", "line 1", "2 numbers"},
        {"v 1 2 3 4 5\n", "line 1", "5 numbers"},
        {"v 1 2 3 4 5 6 7 8\n", "line 1", "too many"},
        {tri + "vt\n", "line 4", "0 numbers"},
        {tri + "vn 1 2\n", "line 4", "2 numbers"},
        {tri + "f 0 1 2\n", "line 4", "index 0"},
        {tri + "f 1 2 4\n", "line 4", "only 3 vertices"},
        {tri + "f -4 1 2\n", "line 4", "relative vertex index -4"},
        {"f 1 2 3\nv 0 0 0\nv 1 0 0\nv 0 1 0\n", "line 1", "only 0 vertices"},
        {tri + "f 1/1 2/1 3/1\n", "line 4", "vt index 1"},
        {tri + "vn 0 0 1\nf 1//2 2//1 3//1\n", "line 5", "vn index 2"},
        {tri + "f 1/ 2 3\n", "line 4", "malformed corner"},
        {tri + "vt 0 0\nvn 0 0 1\nf 1/1/1/1 2 3\n", "line 6", "malformed corner"},
        {tri + "f 1 a 3\n", "line 4", "malformed vertex index"},
        {tri + "f 1 2\n", "line 4", "2 corners"},
        {"", "byte 0", "empty file"},
        {"# only a comment\n\n", "byte", "no vertices"},
        {tri + "\x01\x02\x03 garbage\n", "line 4", "expected an OBJ statement"},
        {tri + std::string("v 1 \0 2\n", 8), "line 4", "NUL byte"},
        {"v 0 0 0\n" + std::string(InputStream::kMaxLine + 10, 'x'), "line 2", "longer"},
        {tri + "usemtl a\nf 1 2 3 \\\n 99\n", "line 6", "only 3 vertices"},
    };
    std::string huge = tri + "f";
    for (int i = 0; i < (1 << 16) + 1; ++i)
        huge += " 1";
    cases.push_back({huge + "\n", "line 4", "more than 65536 corners"});
    for (const auto& c : cases) {
        std::string msg = ObjError(c.text);
        SCOPED_TRACE(c.text.substr(0, 60));
        EXPECT_NE(msg.find("bad.obj: " + c.where), std::string::npos) << msg;
        EXPECT_NE(msg.find(c.what), std::string::npos) << msg;
    }
}

// A line straddling the stream buffer (read from a file, not memory) is put together.
TEST(ObjReader, LongLinesAcrossTheBufferFromAFile) {
    auto path =
        std::filesystem::temp_directory_path() / fmt::format("mebake-obj-test-{}.obj", ::getpid());
    // Lines over 64 KiB: one of them crosses the end of the 1 MiB buffer.
    std::string text = "# short comment\n";
    for (char g = 'a'; g < 'f'; ++g)
        text += "g " + std::string(300000, g) + "\n";
    const int n = 20000;
    for (int i = 0; i < n; ++i)
        text += fmt::format("v {} {} {}\n", i, i * 0.5, -i);
    text += "f";
    for (int i = 1; i <= n; ++i)
        text += fmt::format(" {}", i);
    text += "\n";
    { std::ofstream(path, std::ios::binary) << text; }
    Collected c = ReadPath(ReadObj, path.string());
    std::filesystem::remove(path);
    ASSERT_EQ(c.position.size(), size_t(n));
    EXPECT_EQ(c.position[n - 1], Vec3f(n - 1, (n - 1) * 0.5f, 1 - n));
    ASSERT_EQ(c.face_size, std::vector<uint32_t>{n});
    EXPECT_EQ(c.index[n - 1], uint64_t(n - 1));
    EXPECT_EQ(c.header.comments, std::vector<std::string>{"short comment"});
    ASSERT_EQ(c.summary.groups.size(), 5u);
    for (char g = 'a'; g < 'f'; ++g)
        EXPECT_EQ(c.summary.groups[size_t(g - 'a')], std::string(300000, g));
    EXPECT_EQ(c.summary.bytes_read, text.size());
}

TEST(ObjReader, CornellBoxTinyObjLoader) {
    std::string path = SharedData("scenes/cornell-tinyobjloader/cornell_box.obj");
    if (!testing::Exists(path))
        GTEST_SKIP() << path << " not found";
    Collected c = ReadPath(ReadObj, path);
    // The front wall's face is commented out: its usemtl still names "blue".
    EXPECT_EQ(c.summary.materials,
              (std::vector<std::string>{"white", "light", "blue", "green", "red"}));
    EXPECT_EQ(c.summary.groups,
              (std::vector<std::string>{"floor", "light", "ceiling", "back_wall", "front_wall",
                                        "green_wall", "red_wall", "short_block", "tall_block"}));
    EXPECT_EQ(c.summary.mtllibs, std::vector<std::string>{"cornell_box.mtl"});
    EXPECT_EQ(c.header.comments[0],
              "cornell_box.obj and cornell_box.mtl are grabbed from Intel's embree project.");
    EXPECT_EQ(c.faces(), CountStatements(path, "f"));
    EXPECT_EQ(c.faces(), 18u);
    EXPECT_EQ(c.position.size(), CountStatements(path, "v"));
    size_t lights = 0;
    for (size_t f = 0; f < c.faces(); ++f) {
        if (MaterialOf(c, f) != "light")
            continue;
        ++lights;
        for (size_t k = 0; k < c.face_size[f]; ++k)
            EXPECT_EQ(c.position[c.Corner(f, k)].y, 548.0f);
    }
    EXPECT_EQ(lights, 1u);
    ExpectMatchesReference(path);
}

TEST(ObjReader, CornellBoxMcGuire) {
    std::string path = SharedData("scenes/cornell-mcguire/CornellBox-Original.obj");
    if (!testing::Exists(path))
        GTEST_SKIP() << path << " not found";
    Collected c = ReadPath(ReadObj, path);
    EXPECT_EQ(c.summary.materials,
              (std::vector<std::string>{"floor", "ceiling", "backWall", "rightWall", "leftWall",
                                        "shortBox", "tallBox", "light"}));
    EXPECT_EQ(c.summary.groups, c.summary.materials);
    EXPECT_EQ(c.summary.mtllibs,
              std::vector<std::string>{"models/CornellBox/CornellBox-Original.mtl"});
    EXPECT_EQ(c.header.comments.size(), 10u);
    EXPECT_EQ(c.faces(), CountStatements(path, "f"));
    EXPECT_EQ(c.faces(), 18u);
    EXPECT_EQ(c.position.size(), CountStatements(path, "v"));
    EXPECT_EQ(MaterialOf(c, 17), "light");
    for (size_t k = 0; k < 4; ++k)
        EXPECT_EQ(c.position[c.Corner(17, k)].y, 1.98f);
    // "f -8 -7 -6 -5" (the tall box bottom) names the previous face's vertices.
    EXPECT_EQ(c.Corner(16, 0), 60u);
    EXPECT_EQ(c.Corner(15, 0), 60u);
    ExpectMatchesReference(path);
}

TEST(ObjReader, NefertitiScan) {
    std::string path = SharedData("scans/nefertiti.obj");
    if (!testing::Exists(path))
        GTEST_SKIP() << path << " not found";
    Collected c = ReadPath(ReadObj, path);
    EXPECT_EQ(c.faces(), 99938u);
    EXPECT_EQ(c.faces(), CountStatements(path, "f"));
    EXPECT_EQ(c.position.size(), 49971u);
    EXPECT_TRUE(
        std::all_of(c.face_size.begin(), c.face_size.end(), [](uint32_t n) { return n == 3; }));
    EXPECT_GT(c.vertex_batches, 0u);
    ExpectMatchesReference(path);
}

// Every OBJ of the shared scenes reads, and agrees with the reference reader.
TEST(ObjReader, AllSceneMeshes) {
    std::string root = SharedData("scenes");
    if (!testing::Exists(root + "/cornell-mcguire/CornellBox-Original.obj"))
        GTEST_SKIP() << root << " not found";
    size_t files = 0;
    for (const auto& e : std::filesystem::recursive_directory_iterator(root)) {
        if (e.path().extension() != ".obj")
            continue;
        ExpectMatchesReference(e.path().string());
        ++files;
    }
    EXPECT_GE(files, 90u);
}

TEST(ObjReader, GreyWhiteRoomCornerData) {
    std::string path = SharedData("scenes/grey-white-room-bitterli-toyray/models/Mesh000.obj");
    if (!testing::Exists(path))
        GTEST_SKIP() << path << " not found";
    Collected c = ReadPath(ReadObj, path);
    EXPECT_EQ(c.summary.corner_uv_count, CountStatements(path, "vt"));
    EXPECT_EQ(c.summary.corner_normal_count, CountStatements(path, "vn"));
    EXPECT_EQ(c.faces(), CountStatements(path, "f"));
    EXPECT_GT(c.faces(), 0u);
}

// --- writer ---

std::string WriteObj(const Collected& c, const MeshHeader& header, const WriteOptions& opt = {},
                     bool faces_first = false) {
    std::vector<uint8_t> bytes;
    auto out = OutputStream::ToMemory(&bytes);
    auto w = MakeObjWriter(*out, opt);
    w->Begin(header);
    VertexBatch vb;
    vb.position = c.position;
    vb.normal = c.normal;
    vb.color = c.color;
    vb.uv = c.uv;
    FaceBatch fb;
    fb.size = c.face_size;
    fb.index = c.index;
    if (faces_first)
        w->Faces(fb);
    // Vertices in two batches, faces between them when they only name the first half.
    size_t half = c.position.size() / 2;
    VertexBatch first = vb, second;
    first.position.resize(half);
    if (!vb.normal.empty())
        first.normal.resize(half);
    if (!vb.color.empty())
        first.color.resize(half);
    if (!vb.uv.empty())
        first.uv.resize(half);
    second.first = half;
    second.position.assign(vb.position.begin() + long(half), vb.position.end());
    if (!vb.normal.empty())
        second.normal.assign(vb.normal.begin() + long(half), vb.normal.end());
    if (!vb.color.empty())
        second.color.assign(vb.color.begin() + long(half), vb.color.end());
    if (!vb.uv.empty())
        second.uv.assign(vb.uv.begin() + long(half), vb.uv.end());
    if (half > 0)
        w->Vertices(first);
    if (second.size() > 0)
        w->Vertices(second);
    if (!faces_first)
        w->Faces(fb);
    MeshSummary s;
    s.vertex_count = c.position.size();
    s.face_count = c.faces();
    w->End(s);
    return std::string(bytes.begin(), bytes.end());
}

std::vector<uint32_t> Bits(const std::vector<Vec3f>& v) {
    std::vector<uint32_t> b(v.size() * 3);
    std::memcpy(b.data(), v.data(), b.size() * 4);
    return b;
}

TEST(ObjWriter, RoundTripIsBitExact) {
    Collected c;
    // Awkward floats: shortest printing must still give these exact bits back.
    c.position = {{0.1f, -0.0f, 1e-45f},
                  {3.4028235e38f, -1.17549435e-38f, 1.0f / 3.0f},
                  {16777217.0f, 1e-7f, 2},
                  {-5.5f, 123456.789f, 0.3f},
                  {7, 8, 9}};
    c.color = {{0, 0.5f, 1}, {0.1f, 0.2f, 0.3f}, {1, 1, 1}, {0.003921569f, 0, 0}, {0, 0, 0}};
    c.normal = {
        {0, 0, 1}, {0.6f, 0.8f, 0}, {1, 0, 0}, {0, 1, 0}, {0.57735026f, 0.57735026f, 0.57735026f}};
    c.uv = {{0, 0}, {1, 0}, {0.25f, 0.75f}, {1, 1}, {0.5f, 0.5f}};
    c.face_size = {3, 4};
    c.index = {0, 1, 2, 1, 2, 3, 4};
    MeshHeader h;
    h.has_colors = h.has_normals = h.has_uvs = true;
    h.comments = {"made by a test", "two\nlines"};
    std::string text = WriteObj(c, h);
    EXPECT_EQ(text.rfind("# made by a test\n# two\n# lines\nv ", 0), 0u) << text;
    EXPECT_NE(text.find("\nf 1/1/1 2/2/2 3/3/3\nf 2/2/2 3/3/3 4/4/4 5/5/5\n"), std::string::npos)
        << text;
    Collected back = Obj(text);
    EXPECT_EQ(Bits(back.position), Bits(c.position));
    EXPECT_EQ(Bits(back.color), Bits(c.color));
    EXPECT_EQ(back.face_size, c.face_size);
    EXPECT_EQ(back.index, c.index);
    EXPECT_EQ(back.summary.corner_normal_count, 5u);
    EXPECT_EQ(back.summary.corner_uv_count, 5u);
    EXPECT_EQ(back.header.comments, (std::vector<std::string>{"made by a test", "two", "lines"}));

    // Options turn attributes off; faces then have plain or partial corners.
    WriteOptions no_normals;
    no_normals.normals = false;
    no_normals.colors = false;
    std::string t2 = WriteObj(c, h, no_normals);
    EXPECT_NE(t2.find("\nf 1/1 2/2 3/3\n"), std::string::npos) << t2;
    EXPECT_EQ(t2.find("vn "), std::string::npos);
    EXPECT_FALSE(Obj(t2).header.has_colors);
    WriteOptions no_uvs;
    no_uvs.uvs = false;
    std::string t3 = WriteObj(c, h, no_uvs);
    EXPECT_NE(t3.find("\nf 1//1 2//2 3//3\n"), std::string::npos) << t3;
    EXPECT_EQ(Bits(Obj(t3).position), Bits(c.position));
}

TEST(ObjWriter, FacesBeforeTheirVerticesAreSpilledToTheEnd) {
    Collected c;
    c.position = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}};
    c.face_size = {3, 3};
    c.index = {0, 1, 2, 2, 1, 3};
    std::string text = WriteObj(c, MeshHeader{}, {}, /*faces_first=*/true);
    EXPECT_EQ(text, "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 3 2 4\n");
}

TEST(ObjWriter, CommitsAFileOnlyAtTheEnd) {
    auto path = std::filesystem::temp_directory_path() /
                fmt::format("mebake-obj-writer-{}.obj", ::getpid());
    std::filesystem::remove(path);
    {
        auto out = OutputStream::Open(path.string());
        auto w = MakeObjWriter(*out, {});
        MeshHeader h;
        w->Begin(h);
        VertexBatch vb;
        vb.position = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
        w->Vertices(vb);
        FaceBatch fb;
        fb.size = {3};
        fb.index = {0, 1, 2};
        w->Faces(fb);
        EXPECT_FALSE(std::filesystem::exists(path));
        w->End(MeshSummary{});
    }
    ASSERT_TRUE(std::filesystem::exists(path));
    Collected c = ReadPath(ReadObj, path.string());
    std::filesystem::remove(path);
    EXPECT_EQ(c.position.size(), 3u);
    EXPECT_EQ(c.index, (std::vector<uint64_t>{0, 1, 2}));
}

TEST(ObjWriter, RealMeshesRoundTripExactly) {
    for (const char* rel : {"scans/nefertiti.obj", "scenes/cornell-mcguire/CornellBox-Original.obj",
                            "scenes/cornell-mcguire/CornellBox-Water.obj"}) {
        std::string path = SharedData(rel);
        if (!testing::Exists(path))
            GTEST_SKIP() << path << " not found";
        SCOPED_TRACE(path);
        // Stream straight from the reader into the writer, then read the result back.
        std::vector<uint8_t> bytes;
        auto out = OutputStream::ToMemory(&bytes);
        auto writer = MakeObjWriter(*out, {});
        ReadOptions small;
        small.batch_vertices = 1000;
        small.batch_faces = 777;
        auto in = InputStream::Open(path);
        ReadObj(*in, *writer, small);
        Collected a = ReadPath(ReadObj, path);
        Collected b = Obj(std::string(bytes.begin(), bytes.end()));
        EXPECT_EQ(Bits(a.position), Bits(b.position));
        EXPECT_EQ(a.face_size, b.face_size);
        EXPECT_EQ(a.index, b.index);
        EXPECT_EQ(a.header.comments, b.header.comments);
    }
}

}  // namespace
}  // namespace mebake::io
