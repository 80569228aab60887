// The priority queue of the segmentation's flood: (cost, face, proxy) entries, least first.
#pragma once

#include <cstdint>
#include <cstring>
#include <vector>

namespace mebake::stream {

// A 4-ary min-heap that pops entries in the lexicographic order of (cost, face, proxy),
// ties included: the same order as std::priority_queue with that comparison, so a flood
// over it takes the same faces. Cheaper because the tree is half as deep and each entry's
// (cost, face) is one 64-bit key: a non-negative float's bits order like its value.
// Costs must be >= 0 and not NaN (the flood's costs are sums of squares).
class FloodQueue {
public:
    struct Entry {
        float cost;
        uint32_t face, proxy;
    };

    bool empty() const { return items_.empty(); }
    size_t size() const { return items_.size(); }
    Entry top() const { return Unpack(items_[0]); }
    uint32_t top_face() const { return uint32_t(items_[0].key); }

    void push(float cost, uint32_t face, uint32_t proxy) {
        uint32_t bits;
        std::memcpy(&bits, &cost, sizeof bits);
        const Item item{uint64_t(bits) << 32 | face, proxy};
        size_t i = items_.size();
        items_.push_back(item);
        while (i > 0) {  // sift up
            const size_t parent = (i - 1) / 4;
            if (!Less(item, items_[parent]))
                break;
            items_[i] = items_[parent];
            i = parent;
        }
        items_[i] = item;
    }

    void pop() {
        const Item item = items_.back();
        items_.pop_back();
        const size_t n = items_.size();
        if (n == 0)
            return;
        size_t i = 0;
        for (;;) {  // sift the last entry down from the root
            const size_t first = 4 * i + 1;
            if (first >= n)
                break;
            const size_t end = first + 4 < n ? first + 4 : n;
            size_t least = first;
            for (size_t c = first + 1; c < end; ++c)
                if (Less(items_[c], items_[least]))
                    least = c;
            if (!Less(items_[least], item))
                break;
            items_[i] = items_[least];
            i = least;
        }
        items_[i] = item;
    }

private:
    struct Item {
        uint64_t key;  // the cost's bits, then the face
        uint32_t proxy;
    };
    static bool Less(const Item& a, const Item& b) {
        return a.key < b.key || (a.key == b.key && a.proxy < b.proxy);
    }
    static Entry Unpack(const Item& item) {
        const uint32_t bits = uint32_t(item.key >> 32);
        float cost;
        std::memcpy(&cost, &bits, sizeof cost);
        return {cost, uint32_t(item.key), item.proxy};
    }

    std::vector<Item> items_;
};

}  // namespace mebake::stream
