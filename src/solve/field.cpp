#include "solve/field.h"

#include "core/check.h"

#include <algorithm>
#include <cstring>

namespace mebake::solve {

ChartField::ChartField(int order, int blocks)
    : order_(order), blocks_(blocks), stride_(blocks * NumCoeffs(order)) {
    nodes_.push_back(QuadNode{});
    value_.assign(size_t(stride_), 0.f);
    unshot_.assign(size_t(stride_), 0.f);
}

float* ChartField::pending(size_t n) {
    DCHECK_LT(n, nodes_.size());
    if (pending_.empty())
        pending_.assign(value_.size(), 0.f);
    return &pending_[n * size_t(stride_)];
}

int32_t ChartField::Subdivide(size_t n) {
    CHECK(nodes_[n].leaf());
    CHECK_LT(nodes_[n].level, 30);
    const int32_t first = int32_t(nodes_.size());
    const QuadNode parent = nodes_[n];
    nodes_[n].first_child = first;
    const size_t s = size_t(stride_);
    const bool unshot = has_unshot();
    value_.resize(value_.size() + 4 * s, 0.f);
    if (unshot)
        unshot_.resize(unshot_.size() + 4 * s, 0.f);
    if (!pending_.empty())
        pending_.resize(pending_.size() + 4 * s, 0.f);
    for (int c = 0; c < 4; ++c) {
        QuadNode k;
        k.level = uint8_t(parent.level + 1);
        k.i = parent.i * 2 + uint32_t(c & 1);
        k.j = parent.j * 2 + uint32_t(c >> 1);
        nodes_.push_back(k);
        const size_t kid = size_t(first + c);
        Push(order_, c, &value_[n * s], blocks_, &value_[kid * s]);
        if (unshot)
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

void ChartField::PushDown(size_t n, const float* add) {
    const size_t s = size_t(stride_);
    if (nodes_[n].leaf()) {
        for (size_t k = 0; k < s; ++k)
            value_[n * s + k] += add[k];
        if (has_unshot())
            for (size_t k = 0; k < s; ++k)
                unshot_[n * s + k] += add[k];
        return;
    }
    float child[kMaxCoeffs * 9];
    CHECK_LE(stride_, kMaxCoeffs * 9);
    for (int c = 0; c < 4; ++c) {
        Push(order_, c, add, blocks_, child);
        PushDown(size_t(nodes_[n].first_child + c), child);
    }
}

void ChartField::PushPending() {
    const size_t s = size_t(stride_);
    float add[kMaxCoeffs * 9];
    for (size_t n = 0; n < pending_.size() / s; ++n) {
        float* p = &pending_[n * s];
        if (std::all_of(p, p + s, [](float x) { return x == 0.f; }))
            continue;
        std::memcpy(add, p, s * sizeof(float));
        std::fill(p, p + s, 0.f);
        PushDown(n, add);
    }
    std::vector<float>().swap(pending_);
    Pull();
}

void ChartField::Pull() {
    const size_t s = size_t(stride_);
    // Children always have larger indices than their parent: a reverse sweep is bottom-up.
    for (size_t n = nodes_.size(); n-- > 0;) {
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
    nodes_.shrink_to_fit();
    value_.shrink_to_fit();
    unshot_.shrink_to_fit();
}

void ChartField::ClearUnshot() {
    std::fill(unshot_.begin(), unshot_.end(), 0.f);
}

void ChartField::Assign(std::vector<QuadNode> nodes, std::vector<float> value,
                        std::vector<float> unshot) {
    CHECK_EQ(value.size(), nodes.size() * size_t(stride_));
    CHECK(unshot.empty() || unshot.size() == nodes.size() * size_t(stride_));
    nodes_ = std::move(nodes);
    value_ = std::move(value);
    unshot_ = std::move(unshot);
    pending_.clear();
    pending_.shrink_to_fit();
}

size_t ChartField::MemoryBytes() const {
    return nodes_.capacity() * sizeof(QuadNode) +
           (value_.capacity() + unshot_.capacity() + pending_.capacity()) * sizeof(float);
}

}  // namespace mebake::solve
