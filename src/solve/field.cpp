#include "solve/field.h"

#include "core/check.h"

#include <algorithm>
#include <cstring>
#include <utility>

namespace mebake::solve {

ChartField::ChartField(int order, int blocks)
    : order_(order), blocks_(blocks), stride_(blocks * NumCoeffs(order)), count_(1),
      has_unshot_(true) {
    own_nodes_.push_back(QuadNode{});
    own_value_.assign(size_t(stride_), 0.f);
    own_unshot_.assign(size_t(stride_), 0.f);
    PointAtOwn();
}

ChartField::ChartField(const ChartField& o)
    : order_(o.order_), blocks_(o.blocks_), stride_(o.stride_), count_(o.count_),
      has_unshot_(o.has_unshot_), own_nodes_(o.nodes().begin(), o.nodes().end()),
      own_value_(o.values().begin(), o.values().end()),
      own_unshot_(o.unshots().begin(), o.unshots().end()), pending_(o.pending_) {
    PointAtOwn();
}

ChartField& ChartField::operator=(const ChartField& o) {
    if (this != &o)
        *this = ChartField(o);
    return *this;
}

ChartField::ChartField(ChartField&& o) noexcept {
    *this = std::move(o);
}

ChartField& ChartField::operator=(ChartField&& o) noexcept {
    if (this == &o)
        return *this;
    order_ = o.order_;
    blocks_ = o.blocks_;
    stride_ = o.stride_;
    count_ = std::exchange(o.count_, 0);
    has_unshot_ = std::exchange(o.has_unshot_, false);
    // Moving a vector keeps its buffer, so the array pointers stay valid.
    nodes_ = std::exchange(o.nodes_, nullptr);
    value_ = std::exchange(o.value_, nullptr);
    unshot_ = std::exchange(o.unshot_, nullptr);
    cache_ = std::exchange(o.cache_, nullptr);
    region_ = o.region_;
    own_nodes_ = std::move(o.own_nodes_);
    own_value_ = std::move(o.own_value_);
    own_unshot_ = std::move(o.own_unshot_);
    pending_ = std::move(o.pending_);
    return *this;
}

void ChartField::PointAtOwn() {
    nodes_ = own_nodes_.data();
    value_ = own_value_.data();
    unshot_ = has_unshot_ ? own_unshot_.data() : nullptr;
}

void ChartField::InMemory() {
    if (!cache_)
        return;
    const RegionPin pin = Pin();
    own_nodes_.assign(nodes().begin(), nodes().end());
    own_value_.assign(values().begin(), values().end());
    own_unshot_.assign(unshots().begin(), unshots().end());
    cache_ = nullptr;
    PointAtOwn();
}

void ChartField::Release() {
    CHECK(!cache_ && pending_.empty());
    std::vector<QuadNode>().swap(own_nodes_);
    std::vector<float>().swap(own_value_);
    std::vector<float>().swap(own_unshot_);
    nodes_ = nullptr;
    value_ = unshot_ = nullptr;
}

void ChartField::UseRegion(MappedCache* cache, uint32_t region, size_t value_offset,
                           size_t unshot_offset) {
    CHECK(pending_.empty() && !cache_);
    std::byte* base = cache->MutableData(region);
    CHECK_EQ(reinterpret_cast<uintptr_t>(base) % alignof(QuadNode), 0u);
    cache_ = cache;
    region_ = region;
    nodes_ = reinterpret_cast<QuadNode*>(base);
    value_ = reinterpret_cast<float*>(base + value_offset);
    unshot_ = has_unshot_ ? reinterpret_cast<float*>(base + unshot_offset) : nullptr;
    std::vector<QuadNode>().swap(own_nodes_);
    std::vector<float>().swap(own_value_);
    std::vector<float>().swap(own_unshot_);
}

float* ChartField::pending(size_t n) {
    DCHECK_LT(n, count_);
    if (pending_.empty())
        pending_.assign(count_ * size_t(stride_), 0.f);
    return &pending_[n * size_t(stride_)];
}

int32_t ChartField::Subdivide(size_t n) {
    InMemory();  // a pool's region does not grow
    CHECK(nodes_[n].leaf());
    CHECK_LT(nodes_[n].level, 30);
    const int32_t first = int32_t(count_);
    const QuadNode parent = nodes_[n];
    own_nodes_[n].first_child = first;
    const size_t s = size_t(stride_);
    own_value_.resize(own_value_.size() + 4 * s, 0.f);
    if (has_unshot_)
        own_unshot_.resize(own_unshot_.size() + 4 * s, 0.f);
    if (!pending_.empty())
        pending_.resize(pending_.size() + 4 * s, 0.f);
    for (int c = 0; c < 4; ++c) {
        QuadNode k;
        k.level = uint8_t(parent.level + 1);
        k.i = parent.i * 2 + uint32_t(c & 1);
        k.j = parent.j * 2 + uint32_t(c >> 1);
        own_nodes_.push_back(k);
    }
    count_ += 4;
    PointAtOwn();
    for (int c = 0; c < 4; ++c) {
        const size_t kid = size_t(first + c);
        Push(order_, c, &value_[n * s], blocks_, &value_[kid * s]);
        if (has_unshot_)
            Push(order_, c, &unshot_[n * s], blocks_, &unshot_[kid * s]);
    }
    return first;
}

size_t ChartField::LeafAt(double u, double v, double* s, double* t) const {
    u = std::clamp(u, 0.0, 1.0);
    v = std::clamp(v, 0.0, 1.0);
    size_t n = 0;
    double x = u, y = v;  // node-local
    while (!nodes_[n].leaf()) {
        int qs = x >= 0.5 ? 1 : 0, qt = y >= 0.5 ? 1 : 0;
        x = x * 2 - qs;
        y = y * 2 - qt;
        n = size_t(nodes_[n].first_child + qs + 2 * qt);
    }
    *s = std::clamp(x, 0.0, 1.0);
    *t = std::clamp(y, 0.0, 1.0);
    return n;
}

void ChartField::EvalValue(double u, double v, float* out) const {
    double s, t;
    size_t n = LeafAt(u, v, &s, &t);
    EvalCoeffs(order_, value(n), blocks_, s, t, out);
}

void ChartField::EvalUnshot(double u, double v, float* out) const {
    CHECK(has_unshot());
    double s, t;
    size_t n = LeafAt(u, v, &s, &t);
    EvalCoeffs(order_, unshot(n), blocks_, s, t, out);
}

void ChartField::PushPending() {
    // One sweep down the tree: a node's pending set goes to its leaf's value and unshot, or
    // restricted (Push) into its children's pending sets, which come after it (Subdivide
    // appends them). One Push per node and child instead of one per (pending ancestor,
    // node) as pushing each pending set down its own subtree did (before session 22); the
    // sums round in another order.
    const size_t s = size_t(stride_);
    float child[kMaxCoeffs * 9];
    CHECK_LE(stride_, kMaxCoeffs * 9);
    for (size_t n = 0; n < pending_.size() / s; ++n) {
        const float* p = &pending_[n * s];
        if (std::all_of(p, p + s, [](float x) { return x == 0.f; }))
            continue;
        if (nodes_[n].leaf()) {
            for (size_t k = 0; k < s; ++k)
                value_[n * s + k] += p[k];
            if (has_unshot())
                for (size_t k = 0; k < s; ++k)
                    unshot_[n * s + k] += p[k];
            continue;
        }
        for (int c = 0; c < 4; ++c) {
            Push(order_, c, p, blocks_, child);
            float* kid = &pending_[size_t(nodes_[n].first_child + c) * s];
            for (size_t k = 0; k < s; ++k)
                kid[k] += child[k];
        }
    }
    std::vector<float>().swap(pending_);
    Pull();
}

void ChartField::Pull() {
    const size_t s = size_t(stride_);
    // Children always have larger indices than their parent: a reverse sweep is bottom-up.
    for (size_t n = count_; n-- > 0;) {
        if (nodes_[n].leaf())
            continue;
        const size_t c0 = size_t(nodes_[n].first_child);
        const float* kv[4] = {&value_[c0 * s], &value_[(c0 + 1) * s], &value_[(c0 + 2) * s],
                              &value_[(c0 + 3) * s]};
        const float* ku[4] = {};
        if (has_unshot())
            for (int c = 0; c < 4; ++c)
                ku[c] = &unshot_[(c0 + size_t(c)) * s];
        solve::Pull(order_, kv, blocks_, &value_[n * s]);
        if (has_unshot())
            solve::Pull(order_, ku, blocks_, &unshot_[n * s]);
    }
    own_nodes_.shrink_to_fit();
    own_value_.shrink_to_fit();
    own_unshot_.shrink_to_fit();
    if (!cache_)
        PointAtOwn();
}

void ChartField::ClearUnshot() {
    if (has_unshot_)
        std::fill(unshot_, unshot_ + count_ * size_t(stride_), 0.f);
}

void ChartField::Assign(std::vector<QuadNode> nodes, std::vector<float> value,
                        std::vector<float> unshot) {
    CHECK_EQ(value.size(), nodes.size() * size_t(stride_));
    CHECK(unshot.empty() || unshot.size() == nodes.size() * size_t(stride_));
    cache_ = nullptr;
    count_ = nodes.size();
    has_unshot_ = !unshot.empty();
    own_nodes_ = std::move(nodes);
    own_value_ = std::move(value);
    own_unshot_ = std::move(unshot);
    PointAtOwn();
    std::vector<float>().swap(pending_);
}

size_t ChartField::MemoryBytes() const {
    return own_nodes_.capacity() * sizeof(QuadNode) +
           (own_value_.capacity() + own_unshot_.capacity() + pending_.capacity()) * sizeof(float);
}

}  // namespace mebake::solve
