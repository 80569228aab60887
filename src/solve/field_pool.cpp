#include "solve/field_pool.h"

#include "core/check.h"

#include <span>

namespace mebake::solve {

FieldPool::FieldPool(const std::string& dir, size_t charts, uint64_t budget_bytes)
    : regions_(dir, "coefficient pools", budget_bytes, /*writable=*/true), slots_(charts) {}

void FieldPool::Store(uint32_t chart, ChartField* field) {
    CHECK_LT(chart, slots_.size());
    // Node records first (their alignment is the region's), then the two float arrays.
    static_assert(alignof(QuadNode) >= alignof(float));
    const auto nodes = std::as_bytes(field->nodes());
    const auto values = std::as_bytes(field->values());
    const auto unshots = std::as_bytes(field->unshots());
    const std::span<const std::byte> pieces[] = {nodes, values, unshots};
    const uint32_t region = regions_.Add(pieces);
    {
        std::lock_guard lock(mutex_);
        Slot& s = slots_[chart];
        CHECK(!s.stored);
        s = {true, region, nodes.size(), nodes.size() + values.size()};
    }
    field->Release();
}

void FieldPool::Map(std::vector<ChartField>* fields) {
    CHECK_EQ(fields->size(), slots_.size());
    for (size_t c = 0; c < slots_.size(); ++c) {
        const Slot& s = slots_[c];
        if (s.stored)
            (*fields)[c].UseRegion(&regions_, s.region, s.value_offset, s.unshot_offset);
    }
}

}  // namespace mebake::solve
