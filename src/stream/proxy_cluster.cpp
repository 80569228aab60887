#include "stream/proxy_cluster.h"

#include "core/check.h"
#include "core/parallel.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace mebake::stream {

namespace {

constexpr int kAxisBits = 21;  // cell coordinates per axis: 3 x 21 bits in one 64-bit key
constexpr uint64_t kAxisCells = uint64_t(1) << kAxisBits;
constexpr uint64_t kEmptyKey = ~uint64_t(0);
// Fixed point of the cell sums: positions relative to the box, 2^30 steps over its
// largest side, so 2^33 vertices fit in an int64 sum.
constexpr double kFixedSteps = double(uint64_t(1) << 30);
// Proxy triangles per (area / cell^2), measured: 2.45-2.7 on the scans, the mkscan sphere
// and an icosphere (1.9 on an axis-aligned plane). Set a little high so the first round
// lands ~10 % under the budget rather than over it (which costs a second round).
constexpr double kTrianglesPerCellArea = 2.7;
constexpr int kMaxRounds = 64;  // a guard against a bug, never reached

struct Cell {
    uint64_t key = kEmptyKey;
    int64_t sum[3] = {0, 0, 0};
    uint32_t count = 0;
};
struct CellIndex {
    uint64_t key = kEmptyKey;
    uint32_t index = 0;  // rank of the key among the occupied cells
};

// Open addressing, linear probing, sized to the expected cells rather than the next power
// of two (the slot is the high half of hash x capacity): this table is pass 4's largest
// allocation. Which slot a cell takes depends on the insertion order, but nothing read
// out of the table does: cells are ranked by key.
template <typename Slot>
class HashSlots {
public:
    explicit HashSlots(size_t expected) : slots_(std::max<size_t>(1024, expected + expected / 4)) {}
    size_t size() const { return size_; }
    Slot& Insert(uint64_t key) {
        if (5 * (size_ + 1) > 4 * slots_.size())  // at most 4/5 full
            Grow();
        Slot& c = slots_[Probe(slots_, key)];
        if (c.key == kEmptyKey) {
            c.key = key;
            ++size_;
        }
        return c;
    }
    const Slot& Find(uint64_t key) const {
        const Slot& c = slots_[Probe(slots_, key)];
        DCHECK(c.key == key);
        return c;
    }
    const std::vector<Slot>& slots() const { return slots_; }
    void Release() { std::vector<Slot>().swap(slots_); }

private:
    static size_t Probe(const std::vector<Slot>& slots, uint64_t key) {
        const uint64_t h = key * 0x9E3779B97F4A7C15ull;
        size_t i = size_t((static_cast<unsigned __int128>(h) * slots.size()) >> 64);
        while (slots[i].key != kEmptyKey && slots[i].key != key)
            if (++i == slots.size())
                i = 0;
        return i;
    }
    void Grow() {
        std::vector<Slot> bigger(slots_.size() + slots_.size() / 2);
        for (const Slot& c : slots_)
            if (c.key != kEmptyKey)
                bigger[Probe(bigger, c.key)] = c;
        slots_.swap(bigger);
    }
    std::vector<Slot> slots_;
    size_t size_ = 0;
};

struct Grid {
    Vec3d origin;
    double cell = 0, fixed_scale = 0;
    uint64_t Key(const Vec3f& p) const {
        uint64_t key = 0;
        for (int a = 0; a < 3; ++a) {
            double t = std::floor((double(p[a]) - origin[a]) / cell);
            uint64_t i = t <= 0 ? 0 : std::min<uint64_t>(uint64_t(t), kAxisCells - 1);
            key |= i << (kAxisBits * a);
        }
        return key;
    }
    int64_t Fixed(const Vec3f& p, int a) const {
        return std::llround((double(p[a]) - origin[a]) * fixed_scale);
    }
};

// Vertices referenced by a triangle (repair can leave unreferenced ones).
std::vector<uint8_t> UsedVertices(const ProxyMesh& part) {
    std::vector<uint8_t> used(part.positions.size(), 0);
    for (uint32_t v : part.triangles) {
        CHECK_LT(size_t(v), part.positions.size());
        used[v] = 1;
    }
    return used;
}

std::vector<uint64_t> Keys(const Grid& grid, const ProxyMesh& part) {
    std::vector<uint64_t> keys(part.positions.size());
    ParallelForRange(
        0, int64_t(keys.size()),
        [&](int64_t lo, int64_t hi) {
            for (int64_t v = lo; v < hi; ++v)
                keys[v] = grid.Key(part.positions[v]);
        },
        4096);
    return keys;
}

// Rotates so the smallest index comes first (keeps the orientation).
std::array<uint32_t, 3> Canonical(uint32_t a, uint32_t b, uint32_t c) {
    if (b < a && b < c)
        return {b, c, a};
    if (c < a && c < b)
        return {c, a, b};
    return {a, b, c};
}
// Same three cells = a duplicate, whatever the orientation; the first in this order stays.
// Canonical triangles start with their smallest index, so (t0, min, max) is the sorted
// triple.
void SortUnique(std::vector<std::array<uint32_t, 3>>& tris) {
    auto key = [](const std::array<uint32_t, 3>& t) {
        return std::array<uint32_t, 4>{t[0], std::min(t[1], t[2]), std::max(t[1], t[2]), t[1]};
    };
    std::sort(tris.begin(), tris.end(),
              [&](const auto& a, const auto& b) { return key(a) < key(b); });
    auto same = [](const auto& a, const auto& b) {
        return a[0] == b[0] && std::min(a[1], a[2]) == std::min(b[1], b[2]) &&
               std::max(a[1], a[2]) == std::max(b[1], b[2]);
    };
    tris.erase(std::unique(tris.begin(), tris.end(), same), tris.end());
}

// Hands out the parts in order, reading part k + 1 on another thread while part k is
// processed (reading and decompressing is most of pass 4's time). Two parts in memory.
class PartReader {
public:
    PartReader(uint32_t parts, const ProxyPartSource& source) : parts_(parts), source_(source) {
        if (parts_ > 0)
            Start(0);
    }
    ~PartReader() {
        try {
            group_.Wait();
        } catch (...) {  // already unwinding from another error
        }
    }
    ProxyMesh Next() {
        group_.Wait();  // rethrows the read's error
        ProxyMesh part = std::move(next_);
        if (++k_ < parts_)
            Start(k_);
        return part;
    }

private:
    void Start(uint32_t k) {
        group_.Run([this, k] { next_ = source_(k); });
    }
    uint32_t parts_, k_ = 0;
    const ProxyPartSource& source_;
    ProxyMesh next_;
    TaskGroup group_;
};

struct Round {
    bool aborted = false;               // too many cells or triangles for this cell size
    std::vector<Vec3f> representative;  // per cell, in key order
    std::vector<uint32_t> cell_count;   // input vertices per cell (a border vertex twice)
    std::vector<std::array<uint32_t, 3>> triangles;
    double deviation = 0;
    uint64_t input_triangles = 0;
};

Round RunRound(uint32_t parts, const ProxyPartSource& source, const Grid& grid, uint64_t budget) {
    Round r;
    // About twice the cells and four times the triangles a round on target has: a first
    // guess far too fine stops early instead of holding a table sized by the input.
    const size_t cell_cap = size_t(budget + 1024);
    const size_t triangle_cap = size_t(4 * budget + 1024);
    // A round on target has about budget / 2 cells (two triangles per vertex).
    HashSlots<Cell> table(size_t(budget / 2 + 1024));

    // Pass A: integer sums per cell.
    PartReader reader_a(parts, source);
    for (uint32_t k = 0; k < parts; ++k) {
        ProxyMesh part = reader_a.Next();
        const std::vector<uint8_t> used = UsedVertices(part);
        const std::vector<uint64_t> keys = Keys(grid, part);
        for (size_t v = 0; v < keys.size(); ++v) {
            if (!used[v])
                continue;
            Cell& c = table.Insert(keys[v]);
            for (int a = 0; a < 3; ++a)
                c.sum[a] += grid.Fixed(part.positions[v], a);
            ++c.count;
        }
        if (table.size() > cell_cap) {
            r.aborted = true;
            return r;
        }
    }
    // Cells in key order; the sums table gives way to a smaller key -> rank table.
    std::vector<const Cell*> cells;
    cells.reserve(table.size());
    for (const Cell& c : table.slots())
        if (c.key != kEmptyKey)
            cells.push_back(&c);
    std::sort(cells.begin(), cells.end(),
              [](const Cell* a, const Cell* b) { return a->key < b->key; });
    r.representative.resize(cells.size());
    r.cell_count.resize(cells.size());
    HashSlots<CellIndex> rank(cells.size());
    for (size_t i = 0; i < cells.size(); ++i) {
        const Cell& c = *cells[i];
        rank.Insert(c.key).index = uint32_t(i);
        r.cell_count[i] = c.count;
        for (int a = 0; a < 3; ++a)
            r.representative[i][a] =
                float(grid.origin[a] + double(c.sum[a]) / double(c.count) / grid.fixed_scale);
    }
    std::vector<const Cell*>().swap(cells);
    table.Release();

    // Pass B: triangles between three different cells.
    PartReader reader_b(parts, source);
    for (uint32_t k = 0; k < parts; ++k) {
        ProxyMesh part = reader_b.Next();
        const std::vector<uint8_t> used = UsedVertices(part);
        const std::vector<uint64_t> keys = Keys(grid, part);
        std::vector<uint32_t> cell_of(keys.size(), 0);
        for (size_t v = 0; v < keys.size(); ++v) {
            if (!used[v])
                continue;
            cell_of[v] = rank.Find(keys[v]).index;
            const Vec3f d = part.positions[v] - r.representative[cell_of[v]];
            r.deviation = std::max(r.deviation, Length(Vec3d(d)));
        }
        std::vector<std::array<uint32_t, 3>> tris;
        const size_t n = part.triangles.size() / 3;
        r.input_triangles += n;
        for (size_t t = 0; t < n; ++t) {
            uint32_t a = cell_of[part.triangles[3 * t]], b = cell_of[part.triangles[3 * t + 1]],
                     c = cell_of[part.triangles[3 * t + 2]];
            if (a != b && b != c && a != c)
                tris.push_back(Canonical(a, b, c));
        }
        SortUnique(tris);
        r.triangles.insert(r.triangles.end(), tris.begin(), tris.end());
        if (r.triangles.size() > triangle_cap) {
            r.aborted = true;
            return r;
        }
    }
    SortUnique(r.triangles);
    return r;
}

}  // namespace

ClusterResult ClusterProxy(uint32_t parts, const ProxyPartSource& source,
                           const ClusterOptions& opt) {
    CHECK_GE(opt.max_triangles, uint64_t(1));
    const Vec3d extent = opt.bbox_max - opt.bbox_min;
    const double largest = std::max({extent.x, extent.y, extent.z, 1e-30});
    Grid grid;
    grid.origin = opt.bbox_min;
    grid.fixed_scale = kFixedSteps / largest;
    // Every cell coordinate must fit its 21 bits.
    const double min_cell = largest / double(kAxisCells - 2);
    double cell =
        opt.surface_area > 0
            ? std::sqrt(kTrianglesPerCellArea * opt.surface_area / double(opt.max_triangles))
            : largest / 64;
    ClusterResult out;
    for (int round = 1;; ++round) {
        grid.cell = std::max(cell, min_cell);
        Round r = RunRound(parts, source, grid, opt.max_triangles);
        out.rounds = round;
        const uint64_t count = r.aborted ? 0 : r.triangles.size();
        if (!r.aborted && count <= opt.max_triangles) {
            // Keep only the cells some triangle uses, still in key order.
            std::vector<uint8_t> covered(r.representative.size(), 0);
            for (const auto& t : r.triangles)
                for (uint32_t c : t)
                    covered[c] = 1;
            std::vector<uint32_t> remap(r.representative.size(), 0);
            uint32_t next = 0;
            for (size_t c = 0; c < remap.size(); ++c) {
                if (covered[c]) {
                    remap[c] = next++;
                    out.mesh.positions.push_back(r.representative[c]);
                } else {
                    out.uncovered_vertices += r.cell_count[c];
                }
            }
            out.mesh.triangles.reserve(3 * r.triangles.size());
            for (const auto& t : r.triangles)
                for (uint32_t c : t)
                    out.mesh.triangles.push_back(remap[c]);
            out.cell_size = grid.cell;
            out.deviation = r.deviation;
            out.input_triangles = r.input_triangles;
            return out;
        }
        // Each round grows the cell; a cell larger than the box leaves no triangle at all.
        CHECK_LT(round, kMaxRounds);
        // Triangles go as 1/cell^2; aim 5% under the budget.
        cell =
            grid.cell *
            (r.aborted
                 ? 2.0
                 : std::max(1.05, std::sqrt(double(count) / (0.95 * double(opt.max_triangles)))));
    }
}

}  // namespace mebake::stream
