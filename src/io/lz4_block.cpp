#include "io/lz4_block.h"

#include "core/check.h"

#include <lz4.h>

#include <algorithm>
#include <cstring>

namespace mebake::io {

void AppendLz4(std::span<const uint8_t> raw, std::vector<char>* out) {
    for (uint64_t at = 0; at < raw.size(); at += kLz4BlockMax) {
        const int n_raw = int(std::min<uint64_t>(kLz4BlockMax, raw.size() - at));
        const int bound = LZ4_compressBound(n_raw);
        const size_t base = out->size();
        out->resize(base + 4 + size_t(bound));
        const int n = LZ4_compress_default(reinterpret_cast<const char*>(raw.data() + at),
                                           out->data() + base + 4, n_raw, bound);
        CHECK_GT(n, 0);  // LZ4 cannot fail with a bound-sized buffer
        const uint32_t n32 = uint32_t(n);
        std::memcpy(out->data() + base, &n32, 4);
        out->resize(base + 4 + size_t(n));
    }
}

bool DecodeLz4(std::span<const uint8_t> stored, std::span<uint8_t> raw) {
    uint64_t in = 0, out = 0;
    while (out < raw.size()) {
        uint32_t n = 0;
        if (in + 4 > stored.size())
            return false;
        std::memcpy(&n, stored.data() + in, 4);
        in += 4;
        const int want = int(std::min<uint64_t>(kLz4BlockMax, raw.size() - out));
        if (n > stored.size() - in)
            return false;
        const int got =
            LZ4_decompress_safe(reinterpret_cast<const char*>(stored.data() + in),
                                reinterpret_cast<char*>(raw.data() + out), int(n), want);
        if (got != want)
            return false;
        in += n;
        out += uint64_t(got);
    }
    return in == stored.size();
}

}  // namespace mebake::io
