#include "core/paged_file.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <random>

namespace mebake {
namespace {

std::string TempPath(const char* name) {
    return (std::filesystem::temp_directory_path() / (std::string(name) + "-" +
                                                      std::to_string(::getpid())))
        .string();
}

TEST(PagedFile, RandomWritesReadBackThroughATinyCache) {
    std::string path = TempPath("paged");
    const uint64_t n = 200000;
    std::vector<uint32_t> truth(n, 0);
    {
        // The minimum 4 pages of 64 KiB for 800 KB of data: most accesses evict.
        DiskArray<uint32_t> a(path, true, 16 << 10);
        for (uint64_t i = 0; i < n; ++i) a.Push(0);
        std::mt19937_64 rng(7);
        for (int k = 0; k < 50000; ++k) {
            uint64_t i = rng() % n;
            uint32_t v = uint32_t(rng());
            a.Set(i, v);
            truth[i] = v;
        }
        a.Flush();
        for (uint64_t i = 0; i < n; i += 997) EXPECT_EQ(a.Get(i), truth[i]) << i;
    }
    DiskArray<uint32_t> b(path, false, 64 << 10);
    ASSERT_EQ(b.size(), n);
    for (uint64_t i = 0; i < n; ++i) ASSERT_EQ(b.Get(i), truth[i]) << i;
    std::filesystem::remove(path);
}

TEST(PagedFile, UnalignedRecordsSpanPages) {
    std::string path = TempPath("paged-span");
    struct Rec {
        double a;
        float b[3];
    };
    {
        DiskArray<Rec> a(path, true, 8 << 10);
        for (int i = 0; i < 10000; ++i) a.Push(Rec{double(i), {float(i), -float(i), 0.5f}});
    }
    DiskArray<Rec> b(path, false, 8 << 10);
    for (int i = 9999; i >= 0; i -= 7) {
        Rec r = b.Get(uint64_t(i));
        EXPECT_EQ(r.a, double(i));
        EXPECT_EQ(r.b[1], -float(i));
    }
    std::filesystem::remove(path);
}

}  // namespace
}  // namespace mebake

namespace mebake {
namespace {

// A temporary array leaves nothing in its directory, and its small TLB of recent pages
// never serves a page that was evicted: random access through the minimum cache.
TEST(PagedFile, TemporaryArrayRandomAccessThroughTheMinimumCache) {
    const auto dir = std::filesystem::temp_directory_path() /
                     ("paged-temp-" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir);
    {
        DiskArray<uint64_t> a(PagedFile::Temporary{dir.string(), "test"}, 0);
        const uint64_t n = 300000;  // 2.4 MB: 37 pages through a cache of 4
        for (uint64_t i = 0; i < n; ++i) a.Push(i * 3);
        EXPECT_TRUE(std::filesystem::is_empty(dir));
        std::mt19937_64 rng(11);
        for (int k = 0; k < 100000; ++k) {
            const uint64_t i = rng() % n;
            ASSERT_EQ(a.Get(i), i * 3) << "k " << k;
            if (k % 3 == 0) {
                a.Set(i, i * 3);  // dirty pages written back on eviction, same value
            }
        }
        EXPECT_GT(a.file().misses(), 1000u);
    }
    std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace mebake
