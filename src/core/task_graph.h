// A directed acyclic graph of tasks run on the thread pool (core/parallel.h): every node
// runs once, after all of its predecessors, and nodes whose predecessors are done run
// concurrently, with no barrier between phases. Results stay deterministic when every
// piece of data is written by nodes that the edges order among themselves (the solver's
// batch graph: solve/shoot_graph.cpp).
#pragma once

#include "core/parallel.h"

#include <atomic>
#include <cstdint>
#include <deque>
#include <exception>
#include <functional>
#include <mutex>
#include <vector>

namespace mebake {

class TaskGraph {
public:
    using Node = uint32_t;

    Node Add(std::function<void()> fn);
    // `after` runs only once `before` has finished.
    void Precede(Node before, Node after);
    // Runs the graph and waits for it. After an exception no further node starts; the
    // first exception is rethrown. Runs once.
    void Run();

    size_t node_count() const { return nodes_.size(); }

private:
    struct Item {
        std::function<void()> fn;
        std::vector<Node> next;
        uint32_t predecessors = 0;
        std::atomic<uint32_t> waiting{0};
    };
    void Execute(Node n);

    std::deque<Item> nodes_;  // a deque: items hold atomics and never move
    TaskGroup* group_ = nullptr;  // during Run()
    bool ran_ = false;
    std::atomic<bool> failed_{false};
    std::mutex error_mutex_;
    std::exception_ptr error_;
};

}  // namespace mebake
