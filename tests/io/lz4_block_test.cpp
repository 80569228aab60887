// The one LZ4 framing (io/lz4_block.h): round trips, and damage is reported, not decoded.
#include "io/lz4_block.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

namespace mebake::io {
namespace {

std::vector<uint8_t> Sample(size_t n) {
    std::vector<uint8_t> v(n);
    uint32_t x = 12345;
    for (size_t k = 0; k < n; ++k) {
        x = x * 1664525u + 1013904223u;
        v[k] = uint8_t(k % 61 == 0 ? x >> 24 : k / 64);  // compressible, not trivially
    }
    return v;
}

TEST(Lz4Block, RoundTrips) {
    for (size_t n : {size_t(0), size_t(1), size_t(1000), size_t(1) << 20}) {
        const std::vector<uint8_t> raw = Sample(n);
        std::vector<char> stored(3, 'x');  // appends after what is there
        AppendLz4(raw, &stored);
        std::vector<uint8_t> back(n);
        const auto* p = reinterpret_cast<const uint8_t*>(stored.data()) + 3;
        ASSERT_TRUE(DecodeLz4({p, stored.size() - 3}, back)) << n;
        EXPECT_EQ(back, raw);
        if (n > 1000) {
            EXPECT_LT(stored.size(), n / 2) << "compresses";
        }
    }
}

TEST(Lz4Block, DamageIsReported) {
    const std::vector<uint8_t> raw = Sample(4096);
    std::vector<char> stored;
    AppendLz4(raw, &stored);
    std::vector<uint8_t> s(stored.begin(), stored.end()), back(raw.size());
    std::vector<uint8_t> truncated(s.begin(), s.end() - 1);
    EXPECT_FALSE(DecodeLz4(truncated, back));
    std::vector<uint8_t> longer = s;
    longer.push_back(0);
    EXPECT_FALSE(DecodeLz4(longer, back)) << "trailing bytes";
    std::vector<uint8_t> wrong_size(raw.size() + 1);
    EXPECT_FALSE(DecodeLz4(s, wrong_size)) << "another raw size than recorded";
    std::vector<uint8_t> bad_prefix = s;
    bad_prefix[0] ^= 0x40;
    EXPECT_FALSE(DecodeLz4(bad_prefix, back));
}

}  // namespace
}  // namespace mebake::io
