#include "io/chunk_file.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "core/error.h"

namespace mebake::io {
namespace {

std::string TempPath(const char* name) {
    return (std::filesystem::temp_directory_path() /
            (std::string(name) + "-" + std::to_string(::getpid())))
        .string();
}

constexpr uint32_t kKind = Tag("TEST");

void WriteSample(const std::string& path) {
    ChunkWriter w(path, kKind, 3);
    std::vector<float> big(100000);
    for (size_t i = 0; i < big.size(); ++i) big[i] = float(i % 100) * 0.5f;
    w.AddArray(Tag("BIGF"), 0, big);
    std::vector<uint32_t> small = {1, 2, 3};
    w.AddArray(Tag("SMAL"), 7, small);
    w.AddArray(Tag("RAW "), 0, big, /*compress=*/false);
    w.Finish();
}

TEST(ChunkFile, RoundTripAndSkipsNothingItKnows) {
    std::string path = TempPath("chunks");
    WriteSample(path);
    ChunkReader r(path, kKind, 1, 3);
    EXPECT_EQ(r.version(), 3u);
    auto big = r.ReadArray<float>(Tag("BIGF"));
    ASSERT_EQ(big.size(), 100000u);
    EXPECT_EQ(big[12345], float(12345 % 100) * 0.5f);
    EXPECT_EQ(r.ReadArray<uint32_t>(Tag("SMAL"), 7), (std::vector<uint32_t>{1, 2, 3}));
    EXPECT_EQ(r.ReadArray<float>(Tag("RAW ")), big);
    EXPECT_FALSE(r.Has(Tag("NONE")));
    EXPECT_THROW(r.Read(Tag("NONE")), Error);
    // Compression really happened: the file is smaller than the raw payload twice over.
    EXPECT_LT(std::filesystem::file_size(path), 2 * 400000u);
    std::filesystem::remove(path);
}

TEST(ChunkFile, EveryFlippedByteIsDetectedAndNamed) {
    std::string path = TempPath("chunks-flip");
    WriteSample(path);
    std::vector<char> good;
    {
        std::ifstream f(path, std::ios::binary);
        good.assign(std::istreambuf_iterator<char>(f), {});
    }
    // Flip bytes throughout the file: opening or reading every chunk must throw a
    // Corrupt error naming the file (never crash, never return wrong data silently).
    for (size_t at = 0; at < good.size(); at += 613) {
        std::vector<char> bad = good;
        bad[at] = char(bad[at] ^ 0x5A);
        {
            std::ofstream f(path, std::ios::binary | std::ios::trunc);
            f.write(bad.data(), std::streamsize(bad.size()));
        }
        bool detected = false;
        try {
            ChunkReader r(path, kKind, 1, 3);
            for (auto [tag, index] : r.List()) (void)r.Read(tag, index);
        } catch (const Error& e) {
            detected = true;
            EXPECT_EQ(e.kind(), ErrorKind::Corrupt) << e.what();
            EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
        }
        // Alignment padding between chunks is covered by no checksum; all else is.
        if (!detected) {
            // Only acceptable if the byte was alignment padding (all data still equal).
            ChunkReader r(path, kKind, 1, 3);
            EXPECT_EQ(r.ReadArray<uint32_t>(Tag("SMAL"), 7), (std::vector<uint32_t>{1, 2, 3}));
        }
    }
    std::filesystem::remove(path);
}

// A chunk's CRC is checked at its first read through a reader only (chunk_file.h): a chunk
// that fails keeps failing through the same reader, and a new reader checks again.
TEST(ChunkFile, AFailedChecksumIsCheckedAgainAndANewReaderChecksAgain) {
    std::string path = TempPath("chunks-once");
    WriteSample(path);
    std::vector<char> good;
    {
        std::ifstream f(path, std::ios::binary);
        good.assign(std::istreambuf_iterator<char>(f), {});
    }
    auto write = [&](const std::vector<char>& bytes) {
        std::ofstream f(path, std::ios::binary | std::ios::trunc);
        f.write(bytes.data(), std::streamsize(bytes.size()));
    };
    // A byte inside BIGF's stored data: its read fails, the header and table stay good.
    std::vector<char> bad;
    for (size_t at = 64; at < good.size() && bad.empty(); ++at) {
        std::vector<char> b = good;
        b[at] = char(b[at] ^ 0x5A);
        write(b);
        try {
            ChunkReader r(path, kKind, 1, 3);
            try {
                (void)r.Read(Tag("BIGF"));
            } catch (const Error&) {
                bad = b;
            }
        } catch (const Error&) {
        }
    }
    ASSERT_FALSE(bad.empty());
    {
        ChunkReader r(path, kKind, 1, 3);
        EXPECT_THROW(r.Read(Tag("BIGF")), Error);
        EXPECT_THROW(r.Read(Tag("BIGF")), Error);  // not remembered as checked
    }
    write(good);
    {
        ChunkReader r(path, kKind, 1, 3);
        EXPECT_EQ(r.ReadArray<float>(Tag("BIGF")).size(), 100000u);
        write(bad);  // damaged after this reader checked it: the next reader sees it
        ChunkReader fresh(path, kKind, 1, 3);
        EXPECT_THROW(fresh.Read(Tag("BIGF")), Error);
    }
    std::filesystem::remove(path);
}

TEST(ChunkFile, TruncatedAndWrongKindAreRejected) {
    std::string path = TempPath("chunks-trunc");
    WriteSample(path);
    EXPECT_THROW(ChunkReader(path, Tag("TILE"), 1, 3), Error);
    EXPECT_THROW(ChunkReader(path, kKind, 4, 5), Error);
    std::filesystem::resize_file(path, std::filesystem::file_size(path) / 2);
    EXPECT_THROW(ChunkReader(path, kKind, 1, 3), Error);
    std::filesystem::resize_file(path, 10);
    EXPECT_THROW(ChunkReader(path, kKind, 1, 3), Error);
    std::filesystem::remove(path);
    EXPECT_THROW(ChunkReader(path, kKind, 1, 3), Error);
}

}  // namespace
}  // namespace mebake::io
