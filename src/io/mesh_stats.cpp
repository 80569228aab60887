// MeshStatsSink: the one-pass statistics behind `mebake info`, in memory bounded
// independently of the mesh size.
//
// Face areas need vertex positions, which arrive long before (PLY) or interleaved with
// (OBJ) the faces that use them. Positions are therefore spilled, in blocks of
// kBlockVertices, to an unlinked temporary file and read back through a bounded block
// cache (CLOCK replacement, pread). Scans are exported in spatial order, so a face batch
// touches a handful of blocks: each batch first gathers the blocks it needs, loads the
// missing ones with one preadv per run of consecutive blocks and pins them for the
// batch, then computes with cache hits only. A batch needing more than half the cache
// falls back to loading block by block.
//
// Definitions (what the numbers mean):
//  - degenerate face: a vertex index repeats within the face.
//  - zero-area face: distinct indices, and every fan triangle's cross product is
//    exactly (0,0,0) when computed in double from the stored float positions. This
//    catches coincident corners (duplicated positions) and exactly collinear ones; it
//    does not depend on the bounding box, which is incomplete while an OBJ streams.
//  - surface area: sum over faces of their fan triangles' areas (Neumaier-compensated,
//    in file order, so it is reproducible). Faces with a non-finite corner add nothing.
//  - bounding box: over finite positions only.
//  - faces that arrive before the vertices they name (PLY files with the face element
//    first) are counted at once, and spilled to a second temporary file so their area,
//    zero-area test and referenced vertices are settled in End(), exactly.
#include "io/mesh_stats.h"

#include "core/check.h"
#include "core/error.h"
#include "core/log.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fcntl.h>
#include <sys/stat.h>
#include <sys/uio.h>
#include <unistd.h>
#include <unordered_map>
#include <vector>

namespace mebake::io {
namespace {

constexpr int kBlockShift = 10;
constexpr uint64_t kBlockVertices = uint64_t(1) << kBlockShift;  // 12 KiB of positions
constexpr uint64_t kBlockMask = kBlockVertices - 1;
constexpr size_t kBlockBytes = kBlockVertices * sizeof(Vec3f);

// An unlinked read-write temporary file in `dir` (empty: $TMPDIR, else /tmp).
struct TempFile {
    int fd = -1;
    std::string dir;

    ~TempFile() {
        if (fd >= 0)
            ::close(fd);
    }

    void Create(const std::string& temp_dir, const char* what) {
        dir = temp_dir;
        if (dir.empty()) {
            const char* env = std::getenv("TMPDIR");
            dir = env && *env ? env : "/tmp";
        }
        fd = ::open(dir.c_str(), O_TMPFILE | O_RDWR | O_CLOEXEC, 0600);
        if (fd >= 0)
            return;
        // Filesystems without O_TMPFILE: a named file, unlinked at once.
        std::string tmpl = dir + "/mebake-" + what + "-XXXXXX";
        std::vector<char> name(tmpl.begin(), tmpl.end());
        name.push_back('\0');
        fd = ::mkostemp(name.data(), O_CLOEXEC);
        if (fd < 0)
            IoError({dir}, "cannot create a temporary file for {}: {}", what, ErrnoString(errno));
        ::unlink(name.data());
    }

    void WriteAt(const void* data, size_t n, uint64_t offset) {
        auto p = static_cast<const uint8_t*>(data);
        while (n > 0) {
            ssize_t k = ::pwrite(fd, p, n, off_t(offset));
            if (k < 0) {
                if (errno == EINTR)
                    continue;
                IoError({dir}, "writing a temporary file: {}", ErrnoString(errno));
            }
            p += k, n -= size_t(k), offset += uint64_t(k);
        }
    }

    // Reads exactly the bytes described by `iov` from `offset`.
    void ReadAt(struct iovec* iov, int count, uint64_t offset) {
        while (count > 0) {
            ssize_t k = ::preadv(fd, iov, count, off_t(offset));
            if (k < 0) {
                if (errno == EINTR)
                    continue;
                IoError({dir}, "reading a temporary file: {}", ErrnoString(errno));
            }
            if (k == 0)
                IoError({dir}, "temporary file shorter than written (truncated?)");
            offset += uint64_t(k);
            size_t left = size_t(k);
            while (count > 0 && left >= iov->iov_len) {
                left -= iov->iov_len;
                ++iov, --count;
            }
            if (count > 0) {
                iov->iov_base = static_cast<uint8_t*>(iov->iov_base) + left;
                iov->iov_len -= left;
            }
        }
    }
};

// Vertex positions by global index: the block being filled in memory, full blocks in a
// spill file behind a CLOCK cache of at most `cache_bytes`.
class PositionStore {
public:
    PositionStore(std::string temp_dir, size_t cache_bytes)
        : temp_dir_(std::move(temp_dir)),
          max_slots_(std::max<size_t>(2, cache_bytes / kBlockBytes)) {
        tail_.reserve(kBlockVertices);
        tlb_.fill({~uint64_t(0), 0});
    }

    uint64_t size() const { return (tail_block_ << kBlockShift) + tail_.size(); }

    // Appends positions; `write_through` also caches each completed block (used once
    // faces interleave with vertices, as in OBJ, where they name recent vertices).
    void Append(const Vec3f* p, size_t n, bool write_through) {
        while (n > 0) {
            size_t k = std::min<size_t>(n, kBlockVertices - tail_.size());
            tail_.insert(tail_.end(), p, p + k);
            p += k, n -= k;
            if (tail_.size() == kBlockVertices)
                FlushTail(write_through);
        }
    }

    // Position of vertex v < size().
    Vec3f Get(uint64_t v) {
        uint64_t b = v >> kBlockShift;
        if (b == tail_block_)
            return tail_[v & kBlockMask];
        Tlb& t = tlb_[b % kTlb];
        if (t.block != b) {
            auto it = where_.find(b);
            uint32_t slot = it != where_.end() ? it->second : Load(b);
            t = {b, slot};
        }
        ref_[t.slot] = 1;
        return slots_[t.slot][v & kBlockMask];
    }

    // Loads and pins (until the next call) the listed spilled blocks, sorted and unique,
    // if they fit in half the cache; otherwise Get() loads on demand.
    void Prefetch(const std::vector<uint64_t>& blocks) {
        ++stamp_;
        if (blocks.size() > max_slots_ / 2)
            return;
        std::array<struct iovec, 64> iov;
        size_t i = 0;
        while (i < blocks.size()) {
            uint64_t b = blocks[i];
            auto it = where_.find(b);
            if (it != where_.end()) {
                pin_[it->second] = stamp_;
                ref_[it->second] = 1;
                ++i;
                continue;
            }
            // A run of consecutive missing blocks: one preadv into their slots.
            size_t n = 0;
            while (i + n < blocks.size() && n < iov.size() && blocks[i + n] == b + n &&
                   where_.find(b + n) == where_.end()) {
                uint32_t slot = Victim();
                Assign(slot, b + n);
                pin_[slot] = stamp_;
                iov[n] = {slots_[slot].get(), kBlockBytes};
                ++n;
            }
            file_.ReadAt(iov.data(), int(n), b * kBlockBytes);
            reads_ += 1;
            blocks_read_ += n;
            i += n;
        }
    }

    uint64_t reads() const { return reads_; }  // preadv calls
    uint64_t blocks_read() const { return blocks_read_; }

private:
    struct Tlb {
        uint64_t block;
        uint32_t slot;
    };
    static constexpr size_t kTlb = 16;

    void FlushTail(bool write_through) {
        if (file_.fd < 0)
            file_.Create(temp_dir_, "positions");
        file_.WriteAt(tail_.data(), kBlockBytes, tail_block_ * kBlockBytes);
        if (write_through) {
            uint32_t slot = Victim();
            Assign(slot, tail_block_);
            std::memcpy(slots_[slot].get(), tail_.data(), kBlockBytes);
        }
        tail_.clear();
        ++tail_block_;
    }

    uint32_t Load(uint64_t b) {
        DCHECK(b < tail_block_);
        uint32_t slot = Victim();
        Assign(slot, b);
        struct iovec iov = {slots_[slot].get(), kBlockBytes};
        file_.ReadAt(&iov, 1, b * kBlockBytes);
        reads_ += 1;
        blocks_read_ += 1;
        return slot;
    }

    // A free slot while the cache grows, then CLOCK: skip blocks referenced since the
    // hand last passed (clearing the mark) and blocks pinned by the current Prefetch.
    uint32_t Victim() {
        if (slots_.size() < max_slots_) {
            slots_.emplace_back(new Vec3f[kBlockVertices]);
            block_.push_back(~uint64_t(0));
            ref_.push_back(0);
            pin_.push_back(0);
            return uint32_t(slots_.size() - 1);
        }
        for (size_t tries = 0;; ++tries) {
            uint32_t h = hand_;
            hand_ = uint32_t((hand_ + 1) % slots_.size());
            if (pin_[h] == stamp_ && tries < 2 * slots_.size())
                continue;
            if (ref_[h] && tries < 2 * slots_.size()) {
                ref_[h] = 0;
                continue;
            }
            return h;
        }
    }

    void Assign(uint32_t slot, uint64_t b) {
        if (block_[slot] != ~uint64_t(0)) {
            where_.erase(block_[slot]);
            Tlb& t = tlb_[block_[slot] % kTlb];
            if (t.block == block_[slot])
                t.block = ~uint64_t(0);
        }
        block_[slot] = b;
        where_[b] = slot;
        ref_[slot] = 1;
        Tlb& t = tlb_[b % kTlb];
        if (t.block == b)
            t.block = ~uint64_t(0);
    }

    std::string temp_dir_;
    size_t max_slots_;
    TempFile file_;
    std::vector<Vec3f> tail_;  // positions of block tail_block_, not yet spilled
    uint64_t tail_block_ = 0;

    std::vector<std::unique_ptr<Vec3f[]>> slots_;
    std::vector<uint64_t> block_;  // block held by each slot
    std::vector<uint8_t> ref_;
    std::vector<uint64_t> pin_;  // stamp of the Prefetch that pinned the slot
    std::unordered_map<uint64_t, uint32_t> where_;
    std::array<Tlb, kTlb> tlb_;
    uint32_t hand_ = 0;
    uint64_t stamp_ = 0;
    uint64_t reads_ = 0, blocks_read_ = 0;
};

// Faces whose area must wait for vertices that have not arrived: appended as
// (corner count, indices...) words to a temporary file, replayed in End().
class DeferredFaces {
public:
    explicit DeferredFaces(std::string temp_dir) : temp_dir_(std::move(temp_dir)) {}

    bool empty() const { return written_ == 0 && buffer_.empty(); }

    void Add(const uint64_t* idx, uint32_t n) {
        buffer_.push_back(n);
        buffer_.insert(buffer_.end(), idx, idx + n);
        if (buffer_.size() >= kFlushWords)
            Flush();
    }

    // Calls fn(indices, n) for every face, in the order added.
    template <typename Fn>
    void Replay(Fn&& fn) {
        if (written_ == 0) {
            Parse(buffer_.data(), buffer_.size(), fn);
            return;
        }
        Flush();
        std::vector<uint64_t> chunk;
        size_t have = 0;
        uint64_t offset = 0, total = written_;
        while (offset < total || have > 0) {
            size_t want = std::max<size_t>(kFlushWords, have + 1);
            chunk.resize(want);
            size_t k = size_t(std::min<uint64_t>(want - have, (total - offset) / 8));
            if (k > 0) {
                struct iovec iov = {chunk.data() + have, k * 8};
                file_.ReadAt(&iov, 1, offset);
                offset += k * 8;
                have += k;
            }
            size_t used = Parse(chunk.data(), have, fn);
            if (used == 0 && k == 0)
                break;  // a truncated record: cannot happen
            std::memmove(chunk.data(), chunk.data() + used, (have - used) * 8);
            have -= used;
        }
    }

private:
    static constexpr size_t kFlushWords = size_t(1) << 17;  // 1 MiB

    void Flush() {
        if (buffer_.empty())
            return;
        if (file_.fd < 0)
            file_.Create(temp_dir_, "faces");
        file_.WriteAt(buffer_.data(), buffer_.size() * 8, written_);
        written_ += buffer_.size() * 8;
        buffer_.clear();
    }

    // Handles the complete records in words[0, n); returns how many words they used.
    template <typename Fn>
    static size_t Parse(const uint64_t* words, size_t n, Fn& fn) {
        size_t at = 0;
        while (at < n && at + 1 + words[at] <= n) {
            fn(words + at + 1, uint32_t(words[at]));
            at += 1 + size_t(words[at]);
        }
        return at;
    }

    std::string temp_dir_;
    TempFile file_;
    std::vector<uint64_t> buffer_;
    uint64_t written_ = 0;  // bytes in the file
};

// The state of one Begin..End pass.
struct Pass {
    Pass(const std::string& temp_dir, size_t cache_bytes)
        : positions(temp_dir, cache_bytes), deferred(temp_dir) {}

    PositionStore positions;
    DeferredFaces deferred;
    std::chrono::steady_clock::time_point start;
    std::vector<uint64_t> referenced;  // one bit per vertex received
    bool faces_seen = false;
    bool any_finite = false;
    Vec3d lo{}, hi{};
    std::array<uint64_t, 64> small_sizes{};  // face_sizes for corners < 64
    double area = 0, area_comp = 0;          // Neumaier sum
    std::vector<uint64_t> blocks;            // scratch: blocks a face batch needs

    void Mark(uint64_t v) { referenced[v >> 6] |= uint64_t(1) << (v & 63); }

    void AddArea(double a) {
        double t = area + a;
        area_comp += std::abs(area) >= std::abs(a) ? (area - t) + a : (a - t) + area;
        area = t;
    }

    // Fan area of a face whose corners are all stored; returns whether every fan
    // triangle's cross product is exactly zero.
    bool FaceArea(const uint64_t* idx, uint32_t n) {
        Vec3d p0(positions.Get(idx[0]));
        Vec3d prev = Vec3d(positions.Get(idx[1])) - p0;
        double sum = 0;
        bool zero = true;
        for (uint32_t k = 2; k < n; ++k) {
            Vec3d cur = Vec3d(positions.Get(idx[k])) - p0;
            Vec3d c = Cross(prev, cur);
            if (c.x != 0 || c.y != 0 || c.z != 0)
                zero = false;
            sum += 0.5 * std::sqrt(Dot(c, c));
            prev = cur;
        }
        if (std::isfinite(sum))
            AddArea(sum);
        return zero;
    }
};

// Whether an index repeats among idx[0, n).
bool HasRepeat(const uint64_t* idx, uint32_t n, std::vector<uint64_t>& scratch) {
    if (n <= 8) {
        for (uint32_t i = 1; i < n; ++i)
            for (uint32_t j = 0; j < i; ++j)
                if (idx[i] == idx[j])
                    return true;
        return false;
    }
    scratch.assign(idx, idx + n);
    std::sort(scratch.begin(), scratch.end());
    return std::adjacent_find(scratch.begin(), scratch.end()) != scratch.end();
}

}  // namespace

struct MeshStatsSink::Impl {
    std::string temp_dir;
    size_t cache_bytes;
    std::unique_ptr<Pass> pass;  // between Begin() and End()
};

MeshStatsSink::MeshStatsSink(std::string temp_dir, size_t cache_bytes)
    : impl_(std::make_unique<Impl>(Impl{std::move(temp_dir), cache_bytes, nullptr})) {}

MeshStatsSink::~MeshStatsSink() = default;

void MeshStatsSink::Begin(const MeshHeader& header) {
    impl_->pass = std::make_unique<Pass>(impl_->temp_dir, impl_->cache_bytes);
    stats_ = MeshStats{};
    stats_.header = header;
    impl_->pass->start = std::chrono::steady_clock::now();
}

void MeshStatsSink::Vertices(const VertexBatch& batch) {
    CHECK(impl_->pass);
    Pass& m = *impl_->pass;
    CHECK_EQ(batch.first, m.positions.size());
    const size_t n = batch.size();
    for (size_t i = 0; i < n; ++i) {
        const Vec3f& p = batch.position[i];
        if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
            continue;
        Vec3d d(p);
        if (!m.any_finite) {
            m.lo = m.hi = d;
            m.any_finite = true;
        }
        for (int k = 0; k < 3; ++k) {
            m.lo[k] = std::min(m.lo[k], d[k]);
            m.hi[k] = std::max(m.hi[k], d[k]);
        }
    }
    m.positions.Append(batch.position.data(), n, m.faces_seen);
    m.referenced.resize((m.positions.size() + 63) / 64, 0);
}

void MeshStatsSink::Faces(const FaceBatch& batch) {
    CHECK(impl_->pass);
    Pass& m = *impl_->pass;
    m.faces_seen = true;
    const uint64_t have = m.positions.size();
    const size_t count = batch.count();

    // The spilled blocks this batch reads, so they load in runs before the loop below.
    m.blocks.clear();
    const uint64_t tail_block = have >> kBlockShift;
    uint64_t recent[4] = {~uint64_t(0), ~uint64_t(0), ~uint64_t(0), ~uint64_t(0)};
    for (uint64_t v : batch.index) {
        uint64_t b = v >> kBlockShift;
        // Faces alternate among a few blocks (neighbouring rows): skip recent repeats
        // so the sort below stays small.
        if (v >= have || b == tail_block || b == recent[0] || b == recent[1] || b == recent[2] ||
            b == recent[3])
            continue;
        recent[m.blocks.size() % 4] = b;
        m.blocks.push_back(b);
    }
    std::sort(m.blocks.begin(), m.blocks.end());
    m.blocks.erase(std::unique(m.blocks.begin(), m.blocks.end()), m.blocks.end());
    m.positions.Prefetch(m.blocks);

    std::vector<uint64_t> scratch;
    size_t at = 0;
    for (size_t f = 0; f < count; ++f) {
        const uint32_t n = batch.size[f];
        const uint64_t* idx = batch.index.data() + at;
        at += n;
        if (n < m.small_sizes.size()) {
            ++m.small_sizes[n];
        } else {
            ++stats_.face_sizes[n];
        }
        if (n >= 3)
            stats_.triangles += n - 2;
        bool degenerate = HasRepeat(idx, n, scratch);
        stats_.degenerate_faces += degenerate;
        if (n < 3)
            continue;  // not a polygon: no area (readers do not send these)

        bool known = true;
        for (uint32_t k = 0; k < n; ++k)
            known &= idx[k] < have;
        if (!known) {
            m.deferred.Add(idx, n);
            continue;
        }
        for (uint32_t k = 0; k < n; ++k)
            m.Mark(idx[k]);
        bool zero = m.FaceArea(idx, n);
        stats_.zero_area_faces += zero && !degenerate;
    }
    CHECK_EQ(at, batch.index.size());
}

void MeshStatsSink::End(const MeshSummary& summary) {
    CHECK(impl_->pass);
    Pass& m = *impl_->pass;
    const uint64_t have = m.positions.size();
    std::vector<uint64_t> scratch;
    m.deferred.Replay([&](const uint64_t* idx, uint32_t n) {
        for (uint32_t k = 0; k < n; ++k) {
            if (idx[k] >= have)
                InputError({stats_.header.source}, "a face names vertex {} but the mesh has {}",
                           idx[k], have);
        }
        for (uint32_t k = 0; k < n; ++k)
            m.Mark(idx[k]);
        bool zero = m.FaceArea(idx, n);
        stats_.zero_area_faces += zero && !HasRepeat(idx, n, scratch);
    });

    stats_.summary = summary;
    for (size_t n = 0; n < m.small_sizes.size(); ++n)
        if (m.small_sizes[n])
            stats_.face_sizes[uint32_t(n)] += m.small_sizes[n];
    if (m.any_finite) {
        stats_.bbox_min = m.lo;
        stats_.bbox_max = m.hi;
    }
    uint64_t marked = 0;
    for (uint64_t w : m.referenced)
        marked += uint64_t(std::popcount(w));
    stats_.unreferenced_vertices = have - marked;
    stats_.surface_area = m.area + m.area_comp;
    stats_.read_seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - m.start).count();
    const uint64_t spilled = have >> kBlockShift;
    spdlog::debug("info: {} position blocks spilled, {} read back in {} reads", spilled,
                  m.positions.blocks_read(), m.positions.reads());
    if (m.positions.blocks_read() > std::max<uint64_t>(100000, 20 * spilled))
        spdlog::warn(
            "{}: faces name vertices far apart in the file: face areas re-read {} position "
            "blocks ({} spilled); a larger cache would be faster",
            stats_.header.source, m.positions.blocks_read(), spilled);
    impl_->pass.reset();  // closes and so frees the temporary files
}

}  // namespace mebake::io
