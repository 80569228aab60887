#include "core/checksum.h"

#include <zlib.h>

#include <algorithm>

namespace mebake {

uint32_t Crc32(const void* data, size_t size, uint32_t crc) {
    auto p = static_cast<const Bytef*>(data);
    // crc32_z takes a size_t length; feed in bounded steps anyway for old zlibs.
    while (size > 0) {
        size_t n = std::min<size_t>(size, size_t(1) << 30);
        crc = uint32_t(crc32_z(crc, p, n));
        p += n;
        size -= n;
    }
    return crc;
}

uint64_t Fnv1a64(const void* data, size_t size, uint64_t h) {
    auto p = static_cast<const uint8_t*>(data);
    for (size_t i = 0; i < size; ++i) {
        h ^= p[i];
        h *= 0x100000001b3ull;
    }
    return h;
}

}  // namespace mebake
