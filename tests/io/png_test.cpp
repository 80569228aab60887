// PNG writer: decodes (libpng) to the same bytes, row bands, an sRGB chunk, RGBA, writes
// through files and memory, and malformed PNGs are input errors naming the source.
#include "core/error.h"
#include "io/png_writer.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <unistd.h>
#include <zlib.h>

namespace mebake::io {
namespace {

std::vector<uint8_t> Pattern(int w, int h, int nc) {
    std::vector<uint8_t> v(size_t(w) * h * nc);
    for (size_t i = 0; i < v.size(); ++i)
        v[i] = uint8_t((i * 37 + i / 7) & 0xFF);
    return v;
}

TEST(Png, RoundTripRgbInBands) {
    const int w = 19, h = 11;
    const auto px = Pattern(w, h, 3);
    std::vector<uint8_t> bytes;
    auto out = OutputStream::ToMemory(&bytes);
    PngWriter wr(*out, w, h, 3);
    wr.WriteRows(std::span(px).subspan(0, size_t(4) * w * 3), 4);
    wr.WriteRows(std::span(px).subspan(size_t(4) * w * 3), h - 4);
    wr.Finish();
    const PngImage img = DecodePng(bytes);
    EXPECT_EQ(img.width, w);
    EXPECT_EQ(img.height, h);
    EXPECT_EQ(img.channels, 3);
    EXPECT_TRUE(img.srgb);
    EXPECT_EQ(img.pixels, px);
}

// The encoding is a setting (bench/RESULTS.md, issue 13, h-exp2): every row Paeth-filtered,
// and the pixels decode unchanged.
TEST(Png, RowsArePaethFiltered) {
    const int w = 23, h = 9;
    const auto px = Pattern(w, h, 3);
    const std::vector<uint8_t> png = EncodePng(w, h, 3, px);
    std::vector<uint8_t> idat;
    for (size_t at = 8; at + 12 <= png.size();) {  // chunks: length, type, data, crc
        const size_t n = size_t(png[at]) << 24 | size_t(png[at + 1]) << 16 |
                         size_t(png[at + 2]) << 8 | png[at + 3];
        if (std::string(png.begin() + long(at) + 4, png.begin() + long(at) + 8) == "IDAT")
            idat.insert(idat.end(), png.begin() + long(at) + 8, png.begin() + long(at + 8 + n));
        at += 12 + n;
    }
    std::vector<uint8_t> rows(size_t(h) * (1 + size_t(w) * 3));
    uLongf len = rows.size();
    ASSERT_EQ(uncompress(rows.data(), &len, idat.data(), idat.size()), Z_OK);
    ASSERT_EQ(len, rows.size());
    for (int y = 0; y < h; ++y)
        EXPECT_EQ(rows[size_t(y) * (1 + size_t(w) * 3)], 4) << "row " << y;  // 4: Paeth
    EXPECT_EQ(DecodePng(png).pixels, px);
}

TEST(Png, RgbaToAFile) {
    const auto dir =
        std::filesystem::temp_directory_path() / ("mebake-png-" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir);
    const std::string path = (dir / "a.png").string();
    const auto px = Pattern(5, 3, 4);
    WritePng(path, 5, 3, 4, px);
    const PngImage img = ReadPng(path);
    EXPECT_EQ(img.channels, 4);
    EXPECT_EQ(img.pixels, px);
    std::filesystem::remove_all(dir);
}

TEST(Png, MalformedInputIsAnInputError) {
    const auto px = Pattern(4, 4, 3);
    auto bytes = EncodePng(4, 4, 3, px);
    std::vector<uint8_t> cut(bytes.begin(), bytes.begin() + long(bytes.size() / 2));
    for (const auto& b : {cut, std::vector<uint8_t>{1, 2, 3}}) {
        try {
            DecodePng(b, "bad.png");
            FAIL() << "expected an error";
        } catch (const Error& e) {
            EXPECT_EQ(e.kind(), ErrorKind::Input);
            EXPECT_NE(std::string(e.what()).find("bad.png"), std::string::npos);
        }
    }
    bytes[40] ^= 0x55;  // inside IDAT or a CRC: libpng must notice
    EXPECT_THROW(DecodePng(bytes, "flipped.png"), Error);
}

}  // namespace
}  // namespace mebake::io
