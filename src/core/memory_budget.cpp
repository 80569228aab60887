#include "core/memory_budget.h"

#include <algorithm>

#include <malloc.h>

namespace mebake {

namespace {
constexpr uint64_t kMiB = uint64_t(1) << 20;
}

uint64_t MemoryBudget::SpillCache() const {
    return std::min<uint64_t>(total_ / 8, 12 * kMiB);
}

uint64_t MemoryBudget::BinningCache() const {
    return std::min<uint64_t>(total_ / 8, 64 * kMiB);
}

uint64_t MemoryBudget::Bricks() const {
    return total_;
}

uint64_t MemoryBudget::GeometryPyramids() const {
    return total_ / 32;
}

uint64_t MemoryBudget::CoefficientPools() const {
    return std::min<uint64_t>(total_ / 16, 64 * kMiB);
}

uint64_t MemoryBudget::EmbreeLimit() const {
    return std::min(2 * Visibility(), total_ / 2);
}

uint64_t MemoryBudget::ExportCache() const {
    return std::min<uint64_t>(total_ / 16, 64 * kMiB);
}

uint64_t MemoryBudget::StitchCache() const {
    return std::min<uint64_t>(total_ / 16, 4 * kMiB);
}

uint64_t MemoryBudget::StitchRows() const {
    return std::min<uint64_t>(total_ / 16, 64 * kMiB);
}

std::vector<MemoryShare> MemoryBudget::Shares() const {
    return {{"ingest.spill_cache", SpillCache(), "min(1/8, 12 MiB)"},
            {"ingest.binning_cache", BinningCache(), "min(1/8, 64 MiB, 4x spilled data)"},
            {"ingest.bricks", Bricks(), "all (bricks in flight: 2 if two fit at 400 B per triangle, else 1)"},
            {"solve.visibility", Visibility(), "64 MiB whatever the budget (Embree scene, sized at ingest)"},
            {"solve.embree_limit", EmbreeLimit(), "min(2x visibility, 1/2) (hard cap)"},
            {"solve.geometry_pyramids", GeometryPyramids(), "1/32 beyond pinned charts"},
            {"solve.coefficient_pools", CoefficientPools(), "min(1/16, 64 MiB) beyond pinned charts"},
            {"export.vertex_colour_cache", ExportCache(), "min(1/16, 64 MiB) per array"},
            {"export.stitch_cache", StitchCache(), "min(1/16, 4 MiB)"},
            {"export.stitch_rows", StitchRows(), "min(1/16, 64 MiB)"}};
}

void ReturnFreedHeap() {
    malloc_trim(0);
}

void KeepLargeBlocksOutOfTheHeap() {
    // Setting it also fixes the trim threshold at its default (no dynamic thresholds).
    mallopt(M_MMAP_THRESHOLD, 4 << 20);
}

}  // namespace mebake
