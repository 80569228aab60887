// The order in which the ingest's parallel jobs of uneven size start (ParallelForInOrder).
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace mebake::stream {

// 0 .. n-1 by decreasing size(i), ties in index order: the largest jobs start first, so
// that a large one does not run alone at the end of a parallel loop.
template <typename Size>
std::vector<uint32_t> LargestFirst(size_t n, Size&& size) {
    std::vector<uint32_t> order(n);
    for (uint32_t i = 0; i < n; ++i)
        order[i] = i;
    std::stable_sort(order.begin(), order.end(),
                     [&](uint32_t a, uint32_t b) { return size(a) > size(b); });
    return order;
}

}  // namespace mebake::stream
