// The solve's coefficient pools (quadtree nodes, value and unshot coefficients per chart) in
// a writable memory-mapped file, one region per chart (core/mapped_cache.h), under the
// `--memory` budget's share. A chart's field is stored when the direct pass has refined it
// (its quadtree no longer grows: gathers only add to its coefficients), its memory freed;
// Map() then points every field at its region, and the solver reads and writes
// coefficients in place through the mapping. A pass over a chart (its shot, its gather,
// its share of a checkpoint) holds ChartField::Pin(); the least recently used unpinned
// fields beyond the budget are dropped from the process, their dirty pages left to the
// kernel to write back, and fault back in from the page cache or the file when next used.
// Eviction changes resident memory and speed, never a value: the solution is the same
// bytes for any budget, thread count, and with or without the pool.
#pragma once

#include "core/mapped_cache.h"
#include "solve/field.h"

#include <cstdint>
#include <mutex>
#include <string>
#include <vector>

namespace mebake::solve {

class FieldPool {
public:
    // An unlinked file in directory `dir` for `charts` fields; budget_bytes: resident
    // fields kept beyond the pinned ones. Throws Error(Io).
    FieldPool(const std::string& dir, size_t charts, uint64_t budget_bytes);

    // Copies chart c's field into the file and frees its memory (any thread; each chart
    // once, all before Map()). Throws Error(Io) (a full disk); the field is then intact.
    void Store(uint32_t chart, ChartField* field);
    // Maps the file; every field stored from `fields` works in its region from then on.
    void Map(std::vector<ChartField>* fields);

    uint64_t file_bytes() const { return regions_.file_bytes(); }
    uint64_t budget_bytes() const { return regions_.budget_bytes(); }
    using Stats = MappedCache::Stats;
    Stats stats() const { return regions_.stats(); }

private:
    struct Slot {
        bool stored = false;
        uint32_t region = 0;
        size_t value_offset = 0, unshot_offset = 0;
    };
    MappedCache regions_;
    std::mutex mutex_;  // slots_
    std::vector<Slot> slots_;
};

}  // namespace mebake::solve
