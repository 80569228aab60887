// The lighting on one chart: an adaptive quadtree over the chart's unit square whose
// nodes hold polynomial coefficients (basis.h) for `blocks` scalar functions — 9 for
// vector irradiance (3 colours x 3 components), 3 for radiosity.
//
// Per node there are up to three coefficient sets:
//   value    gathered lighting; after Push() the leaves hold the complete solution and
//            interior nodes their L2 projection (Pull), which coarse emitters read;
//   unshot   the part of `value` not yet shot to other surfaces (Southwell residual);
//            absent in a field read from a solution (values only: export, render);
//   pending  lighting gathered at this node during a batch, not yet pushed to leaves:
//            allocated by the first pending() call and freed by PushPending(), so only
//            the charts being gathered hold it.
// Storage is flat arrays indexed by node, so memory follows the node count. They are
// either the field's own vectors (growing while the direct pass refines; Pull() trims their
// spare capacity) or, once refinement is done, a region of the solve's mapped coefficient
// pool (field_pool.h): then value and unshot are read and written in place through the
// mapping, and Pin() keeps the region resident. Subdividing a mapped field first copies it
// back into its own vectors (the pool's regions do not grow); values never change.
#pragma once

#include "core/mapped_cache.h"
#include "solve/basis.h"

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace mebake::solve {

struct QuadNode {
    int32_t first_child = -1;  // four consecutive nodes in basis.h quadrant order
    uint8_t level = 0;
    uint32_t i = 0, j = 0;  // covers [i, i+1] x [j, j+1] / 2^level of the chart square

    bool leaf() const { return first_child < 0; }
    double size() const { return 1.0 / double(1u << level); }
    // Chart coordinates of node-local (s, t).
    double U(double s) const { return (i + s) * size(); }
    double V(double t) const { return (j + t) * size(); }
};

class ChartField {
public:
    ChartField() = default;
    ChartField(int order, int blocks);
    // A copy is always held in memory; a move keeps the storage.
    ChartField(const ChartField& o);
    ChartField& operator=(const ChartField& o);
    ChartField(ChartField&& o) noexcept;
    ChartField& operator=(ChartField&& o) noexcept;

    int order() const { return order_; }
    int blocks() const { return blocks_; }
    int stride() const { return stride_; }  // floats per node per set
    size_t node_count() const { return count_; }
    const QuadNode& node(size_t n) const { return nodes_[n]; }

    float* value(size_t n) { return &value_[n * size_t(stride_)]; }
    float* unshot(size_t n) { return &unshot_[n * size_t(stride_)]; }
    float* pending(size_t n);
    const float* value(size_t n) const { return &value_[n * size_t(stride_)]; }
    const float* unshot(size_t n) const { return &unshot_[n * size_t(stride_)]; }

    bool has_unshot() const { return has_unshot_; }
    // Keeps a mapped field's region resident while alive (holds nothing in memory).
    RegionPin Pin() const { return cache_ ? cache_->Pin(region_) : RegionPin(); }
    bool mapped() const { return cache_ != nullptr; }

    // Makes four children of a leaf; their value and unshot are the parent's restricted
    // (Push), pending zero. Returns the first child's index.
    int32_t Subdivide(size_t n);

    // The leaf containing chart point (u, v) and the point's node-local coordinates.
    size_t LeafAt(double u, double v, double* s, double* t) const;
    // Evaluates value / unshot at (u, v) into out[blocks].
    void EvalValue(double u, double v, float* out) const;
    void EvalUnshot(double u, double v, float* out) const;

    // Pushes every pending set down to the leaves, adding it to their value and unshot,
    // then clears pending and recomputes interior nodes by Pull().
    void PushPending();
    // Interior value and unshot = projection of their children (bottom-up).
    void Pull();
    void ClearUnshot();

    // Serialization support (checkpoints, solution files, the coefficient pool).
    std::span<const QuadNode> nodes() const { return {nodes_, count_}; }
    std::span<const float> values() const { return {value_, count_ * size_t(stride_)}; }
    std::span<const float> unshots() const {
        return {unshot_, has_unshot_ ? count_ * size_t(stride_) : 0};
    }
    // An empty `unshot` makes a values-only field (has_unshot() false). In memory.
    void Assign(std::vector<QuadNode> nodes, std::vector<float> value, std::vector<float> unshot);
    // For the coefficient pool (field_pool.h): Release() frees the arrays once the pool
    // holds a copy (the field is unusable until UseRegion()); UseRegion() makes region
    // `region` of `cache` (writable, mapped) the arrays: nodes(), values() and unshots()
    // at these byte offsets.
    void Release();
    void UseRegion(MappedCache* cache, uint32_t region, size_t value_offset,
                   size_t unshot_offset);
    // Bytes in memory (a mapped field's arrays count as the pool's, not here).
    size_t MemoryBytes() const;

private:
    void InMemory();      // copies a mapped field into its own vectors
    void PointAtOwn();    // the array pointers at the own vectors

    int order_ = 0, blocks_ = 0, stride_ = 0;
    size_t count_ = 0;
    bool has_unshot_ = false;
    // The arrays: the own vectors below, or a region of cache_.
    QuadNode* nodes_ = nullptr;
    float* value_ = nullptr;
    float* unshot_ = nullptr;
    MappedCache* cache_ = nullptr;
    uint32_t region_ = 0;
    std::vector<QuadNode> own_nodes_;
    std::vector<float> own_value_, own_unshot_, pending_;
};

}  // namespace mebake::solve
