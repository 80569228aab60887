#include "core/task_graph.h"

#include "core/check.h"

#include <utility>

namespace mebake {

TaskGraph::Node TaskGraph::Add(std::function<void()> fn) {
    nodes_.emplace_back();
    nodes_.back().fn = std::move(fn);
    return Node(nodes_.size() - 1);
}

void TaskGraph::Precede(Node before, Node after) {
    CHECK_LT(before, nodes_.size());
    CHECK_LT(after, nodes_.size());
    CHECK_NE(before, after);
    nodes_[before].next.push_back(after);
    ++nodes_[after].predecessors;
}

void TaskGraph::Execute(Node n) {
    Item& item = nodes_[n];
    if (failed_.load())
        return;  // nothing more starts after an exception
    try {
        item.fn();
    } catch (...) {
        std::lock_guard lock(error_mutex_);
        if (!error_)
            error_ = std::current_exception();
        failed_.store(true);
        return;
    }
    for (Node s : item.next)
        if (nodes_[s].waiting.fetch_sub(1) == 1)
            group_->Run([this, s] { Execute(s); });
}

void TaskGraph::Run() {
    CHECK(!ran_);  // runs once
    ran_ = true;
    TaskGroup group;
    group_ = &group;
    for (Item& item : nodes_)
        item.waiting.store(item.predecessors);
    for (Node n = 0; n < nodes_.size(); ++n)
        if (nodes_[n].predecessors == 0)
            group.Run([this, n] { Execute(n); });
    group.Wait();
    group_ = nullptr;
    if (error_)
        std::rethrow_exception(error_);
}

}  // namespace mebake
