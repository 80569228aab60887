// Tests of the streaming STL reader: binary (from memory, and from a pipe whose size is
// unknown), ASCII, detection of binary files whose header starts with "solid", and
// malformed input.
#include "io/mesh_format.h"
#include "text_collect_sink.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <thread>
#include <unistd.h>

namespace mebake::io {
namespace {

using testing::Collected;
using Tri = std::array<Vec3f, 3>;

const std::vector<Tri> kTris = {
    Tri{Vec3f(0, 0, 0), Vec3f(1, 0, 0), Vec3f(0, 1, 0)},
    Tri{Vec3f(1, 0, 0), Vec3f(1, 1, 0), Vec3f(0, 1, 0.5f)},
    Tri{Vec3f(-1e-3f, 2.5f, 1e30f), Vec3f(3, -4, 5), Vec3f(0.1f, 0.2f, 0.3f)},
};

// A binary STL: `header` padded with `pad` to 80 bytes, `count` (default: the real
// number), then one 50-byte record per triangle.
std::string BinaryStl(const std::string& header, const std::vector<Tri>& tris,
                      uint32_t count = std::numeric_limits<uint32_t>::max(), char pad = '\0') {
    std::string s = header.substr(0, 80);
    s.resize(80, pad);
    uint32_t n = count == std::numeric_limits<uint32_t>::max() ? uint32_t(tris.size()) : count;
    s.append(reinterpret_cast<const char*>(&n), 4);
    for (const Tri& t : tris) {
        float f[12] = {0, 0, 1};
        for (int v = 0; v < 3; ++v)
            for (int k = 0; k < 3; ++k)
                f[3 + 3 * v + k] = t[size_t(v)][k];
        s.append(reinterpret_cast<const char*>(f), sizeof(f));
        uint16_t attr = 0x7fff;
        s.append(reinterpret_cast<const char*>(&attr), 2);
    }
    return s;
}

Collected Stl(std::string_view bytes, const ReadOptions& opt = {}) {
    return testing::ReadText(ReadStl, bytes, opt, "test.stl");
}
std::string StlError(std::string_view bytes) {
    return testing::ErrorOf(ReadStl, bytes, "bad.stl");
}

void ExpectTriangles(const Collected& c, const std::vector<Tri>& tris) {
    ASSERT_EQ(c.position.size(), 3 * tris.size());
    ASSERT_EQ(c.faces(), tris.size());
    for (size_t f = 0; f < tris.size(); ++f) {
        EXPECT_EQ(c.face_size[f], 3u);
        for (size_t k = 0; k < 3; ++k) {
            EXPECT_EQ(c.index[3 * f + k], 3 * f + k);
            EXPECT_EQ(c.position[3 * f + k], tris[f][k]) << "facet " << f;
        }
    }
}

TEST(StlReader, Binary) {
    std::string bytes = BinaryStl("exported by a test", kTris);
    Collected c = Stl(bytes);
    EXPECT_EQ(c.header.format, MeshFormat::Stl);
    EXPECT_EQ(c.header.encoding, "binary_little_endian");
    EXPECT_EQ(c.header.face_count, 3u);
    EXPECT_EQ(c.header.vertex_count, 9u);
    EXPECT_FALSE(c.header.has_normals);
    EXPECT_EQ(c.header.comments, std::vector<std::string>{"exported by a test"});
    EXPECT_EQ(c.summary.bytes_read, bytes.size());
    ExpectTriangles(c, kTris);
}

TEST(StlReader, BinaryWhoseHeaderStartsWithSolid) {
    // Space padding keeps the header plain text; the size still says binary.
    Collected c = Stl(BinaryStl("solid cube exported as binary", kTris, ~0u, ' '));
    EXPECT_EQ(c.header.encoding, "binary_little_endian");
    ExpectTriangles(c, kTris);
    // No facets at all: 84 bytes, the NUL count bytes say binary too.
    Collected e = Stl(BinaryStl("solid empty", {}, ~0u, ' '));
    EXPECT_EQ(e.header.encoding, "binary_little_endian");
    EXPECT_EQ(e.faces(), 0u);
    // Wrong size and "solid": still binary (its records are not text), so a size error.
    std::string bad = BinaryStl("solid wrong count", kTris, 7, ' ');
    std::string msg = StlError(bad);
    EXPECT_NE(msg.find("bad.stl: byte 80: binary STL header says 7 facets (434 bytes) but the "
                       "file has 234 bytes"),
              std::string::npos)
        << msg;
}

TEST(StlReader, BinarySmallBatches) {
    std::vector<Tri> many;
    for (int i = 0; i < 100; ++i)
        many.push_back(Tri{Vec3f(i, 0, 0), Vec3f(i, 1, 0), Vec3f(i, 0, 1)});
    for (size_t bv : {1, 3, 7, 64}) {
        ReadOptions opt;
        opt.batch_vertices = bv;
        opt.batch_faces = 5;
        Collected c = Stl(BinaryStl("", many), opt);
        ExpectTriangles(c, many);
        EXPECT_GE(c.face_batches, 20u);
    }
}

const char* kAscii =
    "solid two triangles\n"
    "  facet normal 0 0 1\n"
    "    outer loop\n"
    "      vertex 0 0 0\n"
    "      vertex 1 0 0\n"
    "      vertex 0 1 0\n"
    "    endloop\n"
    "  endfacet\n"
    "  FACET NORMAL nan nan nan\r\n"  // upper case, CRLF, a broken normal: all fine
    "    OUTER LOOP VERTEX 1 0 0\r\n"
    "      VERTEX 1 1 0 vertex 0 1 5e-1\r\n"
    "    ENDLOOP ENDFACET\r\n"
    "endsolid two triangles\n"
    "solid second\n"
    "facet normal 0 0 0 outer loop\n"
    "vertex -1e-3 2.5 1e30\nvertex 3 -4 5\nvertex 0.1 0.2 0.3\n"
    "endloop endfacet\n"
    "endsolid\n";

TEST(StlReader, Ascii) {
    Collected c = Stl(kAscii);
    EXPECT_EQ(c.header.encoding, "ascii");
    EXPECT_EQ(c.header.comments, std::vector<std::string>{"two triangles"});
    EXPECT_EQ(c.summary.bytes_read, std::string_view(kAscii).size());
    ExpectTriangles(c, kTris);
    ReadOptions opt;
    opt.batch_vertices = 1;
    opt.batch_faces = 1;
    ExpectTriangles(Stl(kAscii, opt), kTris);
    Collected e = Stl("  solid\nendsolid\n");
    EXPECT_EQ(e.faces(), 0u);
    EXPECT_EQ(e.begins, 1);
}

TEST(StlReader, Errors) {
    struct Case {
        std::string bytes, where, what;
    };
    std::string good = BinaryStl("x", kTris);
    std::vector<Tri> nan_tris = kTris;
    nan_tris[1][2].y = std::numeric_limits<float>::quiet_NaN();
    std::vector<Tri> inf_tris = kTris;
    inf_tris[2][0].x = std::numeric_limits<float>::infinity();
    std::string facet = "facet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n";
    std::vector<Case> cases = {
        {"", "byte 0", "empty file"},
        {good.substr(0, 50), "byte 50", "file ends after 50 bytes"},
        {good.substr(0, good.size() - 10), "byte 80", "says 3 facets (234 bytes)"},
        {BinaryStl("x", kTris, 2), "byte 80", "says 2 facets (184 bytes) but the file has 234"},
        {BinaryStl("x", kTris, 0xffffffffu - 1), "byte 80", "says 4294967294 facets"},
        {BinaryStl("x", nan_tris), "byte 146", "facet 1 has a non-finite"},
        {BinaryStl("x", inf_tris), "byte 196", "facet 2 has a non-finite"},
        {"solid x\n" + facet + "vertex 0 1 0\nvertex 1 1 1\n", "line 7", "expected 'endloop'"},
        {"solid x\n" + facet + "vertex 0 1 0\nendloop\n", "line 7",
         "file ends; expected "
         "'endfacet'"},
        {"solid x\n" + facet + "endloop\n", "line 6", "expected 'vertex'"},
        {"solid x\n" + facet + "vertex 0 1\nendloop\n", "line 7", "malformed number 'endloop'"},
        {"solid x\n" + facet + "vertex 0 nan 0\n", "line 6", "not finite"},
        {"solid x\n" + facet + "vertex 0 1e40 0\n", "line 6", "out of float range"},
        {"solid x\nfacet normal 0 0 1 inner loop\n", "line 2", "expected 'outer'"},
        {"solid x\nfacet\n", "line 2", "file ends; expected 'normal'"},
        {"solid x\n", "line 1", "file ends inside a solid"},
        {"solid x\nendsolid x\ngarbage\n", "line 3", "after 'endsolid'"},
        {"solid x\nvertex 1 2 3\n", "line 2", "expected 'facet' or 'endsolid'"},
    };
    for (const auto& c : cases) {
        std::string msg = StlError(c.bytes);
        SCOPED_TRACE(c.bytes.substr(0, 60));
        EXPECT_NE(msg.find("bad.stl: " + c.where), std::string::npos) << msg;
        EXPECT_NE(msg.find(c.what), std::string::npos) << msg;
    }
}

// Reads `bytes` through a real pipe, whose size the stream cannot know.
Collected ReadThroughPipe(const std::string& bytes) {
    int fds[2];
    EXPECT_EQ(::pipe(fds), 0);
    std::thread writer([&] {
        size_t done = 0;
        while (done < bytes.size()) {
            ssize_t k = ::write(fds[1], bytes.data() + done, bytes.size() - done);
            if (k <= 0)
                break;
            done += size_t(k);
        }
        ::close(fds[1]);
    });
    Collected c;
    try {
        c = testing::ReadPath(ReadStl, "/dev/fd/" + std::to_string(fds[0]));
    } catch (...) {
        writer.join();
        ::close(fds[0]);
        throw;
    }
    writer.join();
    ::close(fds[0]);
    return c;
}

TEST(StlReader, BinaryFromAPipe) {
    std::vector<Tri> many;
    for (int i = 0; i < 3000; ++i)  // 150 KB: more than one pipe buffer
        many.push_back(Tri{Vec3f(i, 0, 0), Vec3f(i, 1, 0), Vec3f(i, 0, float(i))});
    std::string bytes = BinaryStl("solid but binary", many, ~0u, ' ');
    ExpectTriangles(ReadThroughPipe(bytes), many);

    auto error = [&](const std::string& b) -> std::string {
        try {
            ReadThroughPipe(b);
        } catch (const Error& e) {
            return e.what();
        }
        return "no error";
    };
    std::string truncated = error(bytes.substr(0, bytes.size() - 30));
    EXPECT_NE(truncated.find("binary STL ends after 2999 of 3000 facets"), std::string::npos)
        << truncated;
    std::string trailing = error(bytes + "extra");
    EXPECT_NE(trailing.find("bytes after the 3000 facets"), std::string::npos) << trailing;
    ExpectTriangles(ReadThroughPipe(kAscii), kTris);
}

}  // namespace
}  // namespace mebake::io
