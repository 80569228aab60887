// The heap's freed memory back to the system (core/memory_budget.h): what the ingest's and
// the export's peaks at 50M/100M triangles rest on (bench/RESULTS.md, issue 16 session 11).
#include "core/memory_budget.h"
#include "core/units.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>
#include <vector>

namespace mebake {
namespace {

#if defined(__SANITIZE_ADDRESS__)
constexpr bool kSystemAllocator = false;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
constexpr bool kSystemAllocator = false;
#else
constexpr bool kSystemAllocator = true;
#endif
#else
constexpr bool kSystemAllocator = true;
#endif

constexpr size_t kMiB = size_t(1) << 20;

// A block of `bytes` written to (so its pages are resident), then freed.
void TouchAndFree(size_t bytes) {
    char* p = static_cast<char*>(std::malloc(bytes));
    ASSERT_NE(p, nullptr);
    std::memset(p, 1, bytes);
    asm volatile("" : : "r"(p) : "memory");
    std::free(p);
}

TEST(FreedHeap, LargeBlocksGoBackWhenFreed) {
    if (!kSystemAllocator)
        GTEST_SKIP() << "the sanitizer's allocator is not glibc's";
    KeepLargeBlocksOutOfTheHeap();
    const uint64_t before = CurrentRssBytes();
    // glibc's own rule would put the second block on the heap (its mmap threshold rises to
    // the first block's size when that is freed) and keep it resident after its free.
    TouchAndFree(16 * kMiB);
    TouchAndFree(16 * kMiB);
    EXPECT_LT(CurrentRssBytes(), before + 4 * kMiB);
}

TEST(FreedHeap, FreedHeapGoesBack) {
    if (!kSystemAllocator)
        GTEST_SKIP() << "the sanitizer's allocator is not glibc's";
    std::vector<char*> blocks;
    for (int k = 0; k < 2048; ++k) {  // 64 MiB of 32 KiB blocks: on the heap
        blocks.push_back(static_cast<char*>(std::malloc(32 << 10)));
        std::memset(blocks.back(), 1, 32 << 10);
    }
    for (size_t k = 0; k + 1 < blocks.size(); ++k)  // the last one keeps the top in place
        std::free(blocks[k]);
    const uint64_t held = CurrentRssBytes();
    ReturnFreedHeap();
    EXPECT_LT(CurrentRssBytes() + 48 * kMiB, held);
    std::free(blocks.back());
}

}  // namespace
}  // namespace mebake
