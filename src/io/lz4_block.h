// The one LZ4 framing of mebake's files: a stream of blocks, each [stored size u32][LZ4
// payload] holding at most kLz4BlockMax raw bytes (LZ4 works on int-sized blocks). The raw
// size is recorded by the caller: the chunk table of chunk_file.h, the block header of the
// ingest's brick files (stream/bricks.cpp).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

namespace mebake::io {

inline constexpr uint64_t kLz4BlockMax = uint64_t(1) << 30;

// Appends raw as blocks to out.
void AppendLz4(std::span<const uint8_t> raw, std::vector<char>* out);

// Decodes the blocks of `stored` into raw (sized to the recorded raw size); false when they
// do not decode to exactly raw.size() bytes using all of `stored` (a damaged file).
bool DecodeLz4(std::span<const uint8_t> stored, std::span<uint8_t> raw);

}  // namespace mebake::io
