// MeshStatsSink: the one-pass statistics behind `mebake info`, in memory bounded
// independently of the mesh size.
//
// Face areas need vertex positions, which arrive long before (PLY) or interleaved with
// (OBJ) the faces that use them. Positions are therefore spilled to an unlinked temporary
// file and read back through core/paged_file.h's bounded page cache (CLOCK replacement,
// pread). Scans are exported in spatial order, so a face batch touches a handful of pages.
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
#include "core/paged_file.h"

#include <algorithm>
#include <array>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstring>
#include <vector>

namespace mebake::io {
namespace {

constexpr uint64_t kPageBytes = uint64_t(64) << 10;  // PagedFile's default page

// Faces whose area must wait for vertices that have not arrived: appended as
// (corner count, indices...) words to a temporary file, replayed in End().
class DeferredFaces {
public:
    explicit DeferredFaces(std::string temp_dir) : temp_dir_(std::move(temp_dir)) {}

    bool empty() const { return words_ == 0; }

    void Add(const uint64_t* idx, uint32_t n) {
        if (!file_)
            file_ = std::make_unique<DiskArray<uint64_t>>(PagedFile::Temporary{temp_dir_, "faces"},
                                                          kCacheBytes);
        file_->Push(n);
        file_->PushMany(idx, n);
        words_ += 1 + uint64_t(n);
    }

    // Calls fn(indices, n) for every face, in the order added.
    template <typename Fn>
    void Replay(Fn&& fn) {
        std::vector<uint64_t> face;
        for (uint64_t at = 0; at < words_;) {
            const uint32_t n = uint32_t(file_->Get(at));
            face.resize(n);
            file_->file().Read((at + 1) * sizeof(uint64_t), face.data(), n * sizeof(uint64_t));
            fn(face.data(), n);
            at += 1 + uint64_t(n);
        }
    }

private:
    static constexpr size_t kCacheBytes = size_t(1) << 20;
    std::string temp_dir_;
    std::unique_ptr<DiskArray<uint64_t>> file_;  // made by the first Add()
    uint64_t words_ = 0;
};

// The state of one Begin..End pass.
struct Pass {
    Pass(const std::string& temp_dir, size_t cache_bytes)
        : positions(PagedFile::Temporary{temp_dir, "positions"}, cache_bytes), deferred(temp_dir) {}

    DiskArray<Vec3f> positions;
    DeferredFaces deferred;
    std::chrono::steady_clock::time_point start;
    std::vector<uint64_t> referenced;  // one bit per vertex received
    bool any_finite = false;
    Vec3d lo{}, hi{};
    std::array<uint64_t, 64> small_sizes{};  // face_sizes for corners < 64
    double area = 0, area_comp = 0;          // Neumaier sum

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
    m.positions.PushMany(batch.position.data(), n);
    m.referenced.resize((m.positions.size() + 63) / 64, 0);
}

void MeshStatsSink::Faces(const FaceBatch& batch) {
    CHECK(impl_->pass);
    Pass& m = *impl_->pass;
    const uint64_t have = m.positions.size();
    const size_t count = batch.count();

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
    const uint64_t spilled = m.positions.file().size() / kPageBytes;
    const uint64_t misses = m.positions.file().misses();
    spdlog::debug("info: {} position pages spilled, {} read back", spilled, misses);
    if (misses > std::max<uint64_t>(100000, 20 * spilled))
        spdlog::warn(
            "{}: faces name vertices far apart in the file: face areas re-read {} position "
            "pages ({} spilled); a larger cache would be faster",
            stats_.header.source, misses, spilled);
    impl_->pass.reset();  // closes and so frees the temporary files
}

}  // namespace mebake::io
