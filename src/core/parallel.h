// The one place that spells tbb::. Algorithm code uses these wrappers, so the thread
// pool, cancellation and exception behaviour are decided here once.
//
// Determinism rule for callers: a parallel loop may write only to slots owned by its
// index; reductions are done afterwards in index order, never with atomics on floats.
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>
#include <tbb/task_group.h>

#include <atomic>
#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

namespace mebake {

// Limits the worker threads for the lifetime of the object (0 = all cores).
class ThreadLimit {
public:
    explicit ThreadLimit(int threads) {
        if (threads > 0)
            control_ = std::make_unique<tbb::global_control>(
                tbb::global_control::max_allowed_parallelism, size_t(threads));
    }

private:
    std::unique_ptr<tbb::global_control> control_;
};

inline int MaxThreads() { return tbb::this_task_arena::max_concurrency(); }

// Calls fn(i) for i in [begin, end). Exceptions propagate to the caller (the first one).
template <typename Fn>
void ParallelFor(int64_t begin, int64_t end, Fn&& fn, int64_t grain = 1) {
    if (end <= begin) return;
    tbb::parallel_for(tbb::blocked_range<int64_t>(begin, end, size_t(grain)),
                      [&](const tbb::blocked_range<int64_t>& r) {
                          for (int64_t i = r.begin(); i != r.end(); ++i) fn(i);
                      });
}

// Calls fn(order[k]) for every k, started in the order of k: each call takes the next entry
// from a shared counter, whichever worker runs it, so jobs listed first start first (a
// plain ParallelFor splits the range, and a long job at its end can run alone at the end).
// Results must not depend on the order, as for ParallelFor.
template <typename Fn>
void ParallelForInOrder(const std::vector<uint32_t>& order, Fn&& fn) {
    std::atomic<size_t> next{0};
    ParallelFor(0, int64_t(order.size()), [&](int64_t) { fn(order[next.fetch_add(1)]); });
}

// Calls fn(lo, hi) on disjoint sub-ranges covering [begin, end).
template <typename Fn>
void ParallelForRange(int64_t begin, int64_t end, Fn&& fn, int64_t grain = 1) {
    if (end <= begin) return;
    tbb::parallel_for(tbb::blocked_range<int64_t>(begin, end, size_t(grain)),
                      [&](const tbb::blocked_range<int64_t>& r) { fn(r.begin(), r.end()); });
}

// A group of tasks run concurrently; Wait() rethrows the first exception.
class TaskGroup {
public:
    template <typename Fn>
    void Run(Fn&& fn) {
        group_.run(std::forward<Fn>(fn));
    }
    void Wait() { group_.wait(); }

private:
    tbb::task_group group_;
};

}  // namespace mebake
