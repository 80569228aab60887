// Parsing and printing of sizes and durations as users type and read them.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace mebake {

// "512M", "1G", "1.5GiB", "800000" (bytes), "64k". Binary units (K = 1024).
// Returns nullopt on anything else.
std::optional<uint64_t> ParseByteSize(std::string_view text);

// 1536 -> "1.5 KiB"
std::string FormatBytes(uint64_t bytes);

// 75.2 -> "1m15s", 0.25 -> "250ms"
std::string FormatSeconds(double seconds);

// 1234567 -> "1.23M"
std::string FormatCount(double n);

// Peak resident set size of this process so far, in bytes (from getrusage).
uint64_t PeakRssBytes();
// Current resident set size, in bytes (from /proc/self/statm).
uint64_t CurrentRssBytes();

}  // namespace mebake
