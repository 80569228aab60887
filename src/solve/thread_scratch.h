// A call's scratch buffers kept per thread across calls (no malloc per call), or fresh ones
// when this thread's are in use: a trace may build a paged visibility piece, and Embree's
// build runs TBB tasks, which may be solver tasks that evaluate light on this very thread
// (paged_visibility.cpp, Acquire) while the outer call still holds its buffers.
#pragma once

#include <memory>

namespace mebake::solve {

template <class T>
class ThreadScratch {
public:
    ThreadScratch() : nested_(InUse()) {
        if (nested_) {
            own_ = std::make_unique<T>();
            buffers_ = own_.get();
        } else {
            InUse() = true;
            buffers_ = &Kept();
        }
    }
    ~ThreadScratch() {
        if (!nested_)
            InUse() = false;
    }
    ThreadScratch(const ThreadScratch&) = delete;
    ThreadScratch& operator=(const ThreadScratch&) = delete;

    T& operator*() { return *buffers_; }
    T* operator->() { return buffers_; }

private:
    static T& Kept() {
        static thread_local T kept;
        return kept;
    }
    static bool& InUse() {
        static thread_local bool in_use = false;
        return in_use;
    }
    bool nested_;
    T* buffers_ = nullptr;
    std::unique_ptr<T> own_;
};

}  // namespace mebake::solve
