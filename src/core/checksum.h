// Checksums for on-disk integrity (tiles, pyramids, checkpoints).
#pragma once

#include <cstddef>
#include <cstdint>

namespace mebake {

// CRC-32 (zlib's polynomial); chain calls by passing the previous value as `crc`.
uint32_t Crc32(const void* data, size_t size, uint32_t crc = 0);

// 64-bit FNV-1a, for hashing small keys and settings deterministically.
uint64_t Fnv1a64(const void* data, size_t size, uint64_t h = 0xcbf29ce484222325ull);

}  // namespace mebake
