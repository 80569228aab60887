// Tests of the streaming OFF reader: OFF, COFF, NOFF, CNOFF, STOFF and malformed input.
#include "io/mesh_format.h"
#include "text_collect_sink.h"

#include <gtest/gtest.h>

namespace mebake::io {
namespace {

using testing::Collected;

Collected Off(std::string_view text, const ReadOptions& opt = {}) {
    return testing::ReadText(ReadOff, text, opt, "test.off");
}
std::string OffError(std::string_view text) {
    return testing::ErrorOf(ReadOff, text, "bad.off");
}

const char* kCube = "OFF\n"
                    "# a unit cube\n"
                    "8 6 12\n"
                    "0 0 0\n1 0 0\n1 1 0\n0 1 0\n"
                    "0 0 1\n1 0 1\n1 1 1\n0 1 1   # trailing comment\n"
                    "\n"
                    "4 0 3 2 1\n4 4 5 6 7\n4 0 1 5 4\n"
                    "4 1 2 6 5 255 0 0\n"  // a face colour, ignored
                    "4 2 3 7 6 0.5 0.5 0.5 1\n4 3 0 4 7\n";

TEST(OffReader, Cube) {
    Collected c = Off(kCube);
    EXPECT_EQ(c.header.format, MeshFormat::Off);
    EXPECT_EQ(c.header.vertex_count, 8u);
    EXPECT_EQ(c.header.face_count, 6u);
    EXPECT_FALSE(c.header.has_colors);
    EXPECT_FALSE(c.header.has_normals);
    EXPECT_EQ(c.header.comments, std::vector<std::string>{"a unit cube"});
    ASSERT_EQ(c.position.size(), 8u);
    EXPECT_EQ(c.position[6], Vec3f(1, 1, 1));
    EXPECT_EQ(c.face_size, std::vector<uint32_t>(6, 4));
    EXPECT_EQ(c.Corner(3, 0), 1u);
    EXPECT_EQ(c.Corner(5, 3), 7u);
    EXPECT_TRUE(c.material.empty());
    EXPECT_EQ(c.summary.bytes_read, std::string_view(kCube).size());
}

TEST(OffReader, SmallBatches) {
    ReadOptions opt;
    opt.batch_vertices = 3;
    opt.batch_faces = 2;
    Collected a = Off(kCube), b = Off(kCube, opt);
    EXPECT_EQ(a.position, b.position);
    EXPECT_EQ(a.index, b.index);
    EXPECT_EQ(b.vertex_batches, 3u);
    EXPECT_EQ(b.face_batches, 3u);
}

TEST(OffReader, CountsOnTheKeywordLineOrNoKeyword) {
    Collected a = Off("OFF 3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
    EXPECT_EQ(a.face_size, std::vector<uint32_t>{3});
    Collected b = Off("3 1\n0 0 0\n1 0 0\n0 1 0\n3 2 1 0\n");
    EXPECT_EQ(b.index, (std::vector<uint64_t>{2, 1, 0}));
    Collected e = Off("OFF\n0 0 0\n");
    EXPECT_TRUE(e.position.empty());
    EXPECT_EQ(e.begins, 1);
}

TEST(OffReader, ColoursAsBytesOrFloats) {
    Collected c = Off("COFF\n4 1 0\n"
                      "0 0 0 255 0 51 255\n"
                      "1 0 0 0 255 0 0\n"
                      "1 1 0 0.5 0.25 1.5 0.5\n"  // floats, clamped
                      "0 1 0\n"                   // no colour: white, opaque
                      "4 0 1 2 3\n");
    EXPECT_TRUE(c.header.has_colors);
    EXPECT_TRUE(c.header.has_alpha);
    EXPECT_FALSE(c.header.colors_are_float);
    ASSERT_EQ(c.color.size(), 4u);
    EXPECT_EQ(c.color[0], Vec3f(1, 0, 51 / 255.0f));
    EXPECT_EQ(c.color[1], Vec3f(0, 1, 0));
    EXPECT_EQ(c.color[2], Vec3f(0.5f, 0.25f, 1));
    EXPECT_EQ(c.color[3], Vec3f(1, 1, 1));
    EXPECT_EQ(c.alpha, (std::vector<float>{1, 0, 0.5f, 1}));

    Collected f = Off("COFF\n3 1 0\n0 0 0 0.1 0.2 0.3\n1 0 0 1 1 1\n0 1 0 0 0 0\n3 0 1 2\n");
    EXPECT_TRUE(f.header.colors_are_float);
    EXPECT_FALSE(f.header.has_alpha);
    EXPECT_TRUE(f.alpha.empty());
    EXPECT_EQ(f.color[0], Vec3f(0.1f, 0.2f, 0.3f));
}

TEST(OffReader, NormalsAndTextureCoordinates) {
    Collected n = Off("NOFF\n3 1 0\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 1 0\n3 0 1 2\n");
    EXPECT_TRUE(n.header.has_normals);
    ASSERT_EQ(n.normal.size(), 3u);
    EXPECT_EQ(n.normal[2], Vec3f(0, 1, 0));

    Collected cn = Off("CNOFF\n3 1 0\n0 0 0 0 0 1 1. 0. 0. 1.\n1 0 0 0 0 1 0.0 1.0 0.0 1.0\n"
                       "0 1 0 0 1 0 0 0 1 1\n"  // integers: bytes
                       "3 0 1 2\n");
    EXPECT_TRUE(cn.header.has_normals);
    EXPECT_TRUE(cn.header.has_colors);
    EXPECT_EQ(cn.color[1], Vec3f(0, 1, 0));
    EXPECT_EQ(cn.normal[0], Vec3f(0, 0, 1));
    EXPECT_EQ(cn.color[2], Vec3f(0, 0, 1 / 255.0f));
    EXPECT_TRUE(cn.header.colors_are_float);

    Collected st = Off("STOFF\n3 1 0\n0 0 0 0 0\n1 0 0 1 0\n0 1 0 0.5 1\n3 0 1 2\n");
    EXPECT_TRUE(st.header.has_uvs);
    EXPECT_EQ(st.uv[2], Vec2f(0.5f, 1));
}

TEST(OffReader, Errors) {
    struct Case {
        std::string text, where, what;
    };
    std::string head = "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n";
    std::vector<Case> cases = {
        {"", "byte 0", "empty file"},
        {"# nothing\n", "byte 10", "no OFF header"},
        {"OFF\n", "byte 4", "file ends after the OFF keyword"},
        {"OFX\n3 1 0\n", "line 1", "expected an OFF keyword"},
        {"4OFF\n3 1 0\n", "line 1", "not supported"},
        {"OFF BINARY\n3 1 0\n", "line 1", "binary OFF"},
        {"OFF\n3\n", "line 2", "counts line"},
        {"OFF\n3 1 0 7\n", "line 2", "counts line"},
        {"OFF\n-3 1 0\n", "line 2", "vertex count"},
        {"OFF\n3 x 0\n", "line 2", "face count"},
        {"OFF\n3 1 0\n0 0 0\n1 0 0\n", "byte", "file ends after 2 of 3 vertices"},
        {head, "byte", "file ends after 0 of 1 faces"},
        {"OFF\n3 1 0\n0 0 0\n1 0\n0 1 0\n", "line 4", "missing vertex coordinate"},
        {"OFF\n3 1 0\n0 0 0\n1 0 0 5\n0 1 0\n", "line 4", "1 numbers after"},
        {"OFF\n3 1 0\n0 0 0\n1 a 0\n0 1 0\n", "line 4", "malformed number"},
        {"OFF\n3 1 0\n0 0 0\n1 nan 0\n0 1 0\n", "line 4", "not finite"},
        {"OFF\n3 1 0\n0 0 0\n1 -inf 0\n0 1 0\n", "line 4", "not finite"},
        {"COFF\n3 1 0\n0 0 0\n1 0 0 1 1\n0 1 0\n", "line 4", "2 numbers after"},
        {"COFF\n3 1 0\n0 0 0\n1 0 0 1 nan 1\n0 1 0\n", "line 4", "not finite"},
        {head + "3 0 1 3\n", "line 6", "vertex index 3 out of range"},
        {head + "3 0 -1 2\n", "line 6", "vertex index -1 out of range"},
        {head + "3 0 1\n", "line 6", "polygon ends after 2 of 3"},
        {head + "2 0 1\n", "line 6", "2 corners"},
        {head + "x 0 1 2\n", "line 6", "malformed corner count"},
        {head + "3 0 1.5 2\n", "line 6", "malformed vertex index"},
        {head + "65537 0 1 2\n", "line 6", "at most 65536"},
        {head + "99999999999999999999 0 1 2\n", "line 6", "malformed corner count"},
        {std::string("OFF\n3 1 0\n\x01\x02\x00\n", 14), "line 3", "NUL byte"},
        {"OFF\n1 0 0\n" + std::string(InputStream::kMaxLine + 1, '1'), "line 3", "longer"},
    };
    for (const auto& c : cases) {
        std::string msg = OffError(c.text);
        SCOPED_TRACE(c.text.substr(0, 60));
        EXPECT_NE(msg.find("bad.off: " + c.where), std::string::npos) << msg;
        EXPECT_NE(msg.find(c.what), std::string::npos) << msg;
    }
}

TEST(OffReader, HugeCountsAllocateNothing) {
    // A lying header must fail at the end of the data, not try to reserve memory.
    std::string msg = OffError("OFF\n4000000000000000000 4000000000000000000 0\n0 0 0\n");
    EXPECT_NE(msg.find("file ends after 1 of 4000000000000000000 vertices"), std::string::npos)
        << msg;
}

}  // namespace
}  // namespace mebake::io
