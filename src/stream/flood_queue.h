// The priority queue of the segmentation's flood: (cost, face, proxy) entries, least first.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>
#include <vector>

namespace mebake::stream {

// Pops entries in the lexicographic order of (cost, face, proxy), ties included: the same
// order as a std::priority_queue with that comparison, so a flood over it takes the same
// faces. (cost, face) is one 64-bit key (a non-negative float's bits order like its
// value; a NaN sorts last). The flood's pops are nearly monotone (a face's cost grows
// with its distance from the proxy: ~3 % of pushes are below the last pop on the scans),
// so this is a radix heap (Ahuja et al. 1990) on the cost's bits: bucket i > 0 holds the
// entries whose highest cost bit differing from the last popped cost is bit i-1, bucket 0
// those of equal cost. A push is an append; a pop that finds bucket 0 empty moves the
// least non-empty bucket's entries down, each at most 32 times in all. Keys below the last pop go to a small binary
// heap, popped first (they are below everything in the buckets).
class FloodQueue {
public:
    struct Entry {
        float cost;
        uint32_t face, proxy;
    };

    bool empty() const { return size_ == 0; }
    size_t size() const { return size_; }

    void push(float cost, uint32_t face, uint32_t proxy) {
        uint32_t bits;
        std::memcpy(&bits, &cost, sizeof bits);
        const Item item{uint64_t(bits) << 32 | face, proxy};
        ++size_;
        if (item.key < last_) {
            below_.push_back(item);
            std::push_heap(below_.begin(), below_.end(), Greater);
        } else {
            const size_t b = Bucket(item.key);
            buckets_[b].push_back(item);
            if (b == 0)
                least_ = kUnknown;  // it may be the lesser one
        }
    }

    // The least entry; the queue must not be empty.
    Entry top() {
        Settle();
        return Unpack(below_.empty() ? buckets_[0][least_] : below_.front());
    }
    uint32_t top_face() { return top().face; }

    void pop() {
        Settle();
        if (!below_.empty()) {
            std::pop_heap(below_.begin(), below_.end(), Greater);
            below_.pop_back();
        } else {
            std::vector<Item>& b = buckets_[0];
            b[least_] = b.back();
            b.pop_back();
            least_ = kUnknown;
        }
        if (--size_ == 0)
            last_ = 0;  // nothing is queued: any key may come next
    }

private:
    struct Item {
        uint64_t key;  // the cost's bits, then the face
        uint32_t proxy;
    };
    static constexpr size_t kUnknown = ~size_t(0);

    static bool Greater(const Item& a, const Item& b) {
        return a.key > b.key || (a.key == b.key && a.proxy > b.proxy);
    }
    static Entry Unpack(const Item& item) {
        const uint32_t bits = uint32_t(item.key >> 32);
        float cost;
        std::memcpy(&cost, &bits, sizeof cost);
        return {cost, uint32_t(item.key), item.proxy};
    }
    // By the cost's bits only: equal costs share bucket 0, where the least (face, proxy) wins.
    size_t Bucket(uint64_t key) const {
        const uint32_t diff = uint32_t(key >> 32) ^ uint32_t(last_ >> 32);
        return diff == 0 ? 0 : size_t(32 - __builtin_clz(diff));
    }

    // Makes the least entry the one at least_ in bucket 0, unless below_ has entries.
    void Settle() {
        if (!below_.empty() || least_ != kUnknown)
            return;
        if (buckets_[0].empty()) {
            size_t i = 1;
            while (buckets_[i].empty())
                ++i;
            std::vector<Item>& from = buckets_[i];
            uint64_t least = from[0].key;
            for (const Item& item : from)
                least = std::min(least, item.key);
            last_ = least;
            for (const Item& item : from)
                buckets_[Bucket(item.key)].push_back(item);  // each lands below i
            from.clear();
        }
        // Bucket 0's costs all equal last_'s: the least (face, proxy) goes first.
        const std::vector<Item>& b = buckets_[0];
        least_ = 0;
        for (size_t j = 1; j < b.size(); ++j)
            if (Greater(b[least_], b[j]))
                least_ = j;
    }

    std::array<std::vector<Item>, 33> buckets_;
    std::vector<Item> below_;  // a min-heap of keys below last_
    uint64_t last_ = 0;        // the last key moved into bucket 0
    size_t least_ = kUnknown;  // bucket 0's least entry, once known
    size_t size_ = 0;
};

}  // namespace mebake::stream
