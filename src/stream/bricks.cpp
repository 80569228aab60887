#include "stream/bricks.h"

#include "core/check.h"
#include "core/checksum.h"
#include "core/error.h"
#include "core/paged_file.h"
#include "io/lz4_block.h"


#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fcntl.h>
#include <filesystem>
#include <unistd.h>

namespace mebake::stream {

namespace {

constexpr int kLevel = 7;                        // 128^3 cells
constexpr uint32_t kCells = 1u << (3 * kLevel);  // 2M cells: 8 MB of counts
// Write buffers of all bricks together hold at most kBufferBytes (each between the two
// bounds), and a brick file is open only while a block is written: neither memory nor file
// descriptors grow with the number of bricks.
constexpr size_t kBufferBytes = size_t(8) << 20;
constexpr size_t kMinFlushBytes = size_t(16) << 10, kMaxFlushBytes = size_t(256) << 10;

uint32_t Spread3(uint32_t x) {  // 7 bits -> every third bit
    uint32_t r = 0;
    for (int i = 0; i < kLevel; ++i)
        r |= ((x >> i) & 1u) << (3 * i);
    return r;
}

struct CellMapper {
    Vec3d lo, scale;
    CellMapper(const Vec3d& bmin, const Vec3d& bmax) : lo(bmin) {
        Vec3d ext = bmax - bmin;
        double e = std::max({ext.x, ext.y, ext.z, 1e-30});
        // A cube around the box keeps cells cubic (compact bricks for flat scenes).
        scale = Vec3d(1, 1, 1) * (double(1 << kLevel) / (e * (1 + 1e-9)));
    }
    uint32_t Cell(const Vec3d& p) const {
        auto q = [&](double v, double l, double s) {
            return uint32_t(std::clamp((v - l) * s, 0.0, double((1 << kLevel) - 1)));
        };
        return Spread3(q(p.x, lo.x, scale.x)) | Spread3(q(p.y, lo.y, scale.y)) << 1 |
               Spread3(q(p.z, lo.z, scale.z)) << 2;
    }
};

// Appends blocks to a brick file: [u32 raw bytes][u32 stored bytes][u32 crc][stored bytes
// in the LZ4 framing of io/lz4_block.h].
class BrickFile {
public:
    BrickFile(std::string path, size_t flush_bytes)
        : path_(std::move(path)), flush_bytes_(flush_bytes) {}
    ~BrickFile() {
        if (fd_ >= 0)
            ::close(fd_);
    }
    void Add(const BrickFace& f) {
        buffer_.push_back(f);
        if (buffer_.size() * sizeof(BrickFace) >= flush_bytes_)
            Flush();
    }
    void Flush() {
        if (buffer_.empty())
            return;
        const int flags = O_WRONLY | O_CREAT | O_CLOEXEC | (created_ ? O_APPEND : O_TRUNC);
        fd_ = ::open(path_.c_str(), flags, 0644);
        if (fd_ < 0)
            IoError({path_}, "cannot create: {}", ErrnoString(errno));
        created_ = true;
        // A block: [raw size u32][stored size u32][CRC-32 of the stored bytes] and the
        // stored bytes in the one LZ4 framing (io/lz4_block.h).
        const size_t raw = buffer_.size() * sizeof(BrickFace);
        std::vector<char> out(12);
        io::AppendLz4({reinterpret_cast<const uint8_t*>(buffer_.data()), raw}, &out);
        const size_t n = out.size() - 12;
        const uint32_t head[3] = {uint32_t(raw), uint32_t(n), Crc32(out.data() + 12, n)};
        std::memcpy(out.data(), head, 12);
        size_t total = out.size(), done = 0;
        while (done < total) {
            ssize_t w = ::write(fd_, out.data() + done, total - done);
            if (w < 0 && errno == EINTR)
                continue;
            if (w < 0)
                IoError({path_}, "write failed: {}", ErrnoString(errno));
            done += size_t(w);
        }
        buffer_.clear();
        const int fd = fd_;
        fd_ = -1;
        if (::close(fd) != 0)
            IoError({path_}, "close failed: {}", ErrnoString(errno));
    }
    void Close() {
        Flush();
        std::vector<BrickFace>().swap(buffer_);
    }

private:
    std::string path_;
    size_t flush_bytes_;
    int fd_ = -1;
    bool created_ = false;
    std::vector<BrickFace> buffer_;
};

}  // namespace

std::string BrickPath(const std::string& dir, uint32_t brick) {
    char name[32];
    std::snprintf(name, sizeof(name), "/bricks/b%05u.faces", brick);
    return dir + name;
}

std::string OwnersPath(const std::string& dir) {
    return dir + "/owners.bin";
}

BrickPlan BinFaces(const std::string& dir, const SpillResult& spill, const BinOptions& opt) {
    BrickPlan plan;
    std::filesystem::create_directories(dir + "/bricks");
    const size_t cache = std::max<size_t>(opt.cache_bytes / 4, size_t(1) << 20);
    DiskArray<Vec3f> vertices(Spill::VerticesPath(dir), false, cache);
    DiskArray<SpillFace> faces(Spill::FacesPath(dir), false, cache);
    CHECK_EQ(vertices.size(), spill.vertex_count);
    CHECK_EQ(faces.size(), spill.face_count);
    CellMapper mapper(spill.bbox_min, spill.bbox_max);

    // 1. Cell of every face (kept on disk) and the count per cell.
    std::vector<uint32_t> count(kCells, 0);
    DiskArray<uint32_t> cells(dir + "/cells.bin", true, cache);
    for (uint64_t f = 0; f < spill.face_count; ++f) {
        SpillFace sf = faces.Get(f);
        Vec3d p[3];
        for (int c = 0; c < 3; ++c)
            p[c] = Vec3d(vertices.Get(sf.v[c]));
        uint32_t cell = mapper.Cell((p[0] + p[1] + p[2]) * (1.0 / 3));
        cells.Push(cell);
        ++count[cell];
        plan.surface_area += 0.5 * Length(Cross(p[1] - p[0], p[2] - p[0]));
        if (opt.progress && (f & 4095) == 4095)
            opt.progress->Add(4096);
    }
    cells.Flush();

    // 2. Bricks: leaves of the octree with <= max_faces faces, in Morton order, then
    // consecutive leaves merged while they fit.
    std::vector<uint64_t> prefix(size_t(kCells) + 1, 0);
    for (uint32_t c = 0; c < kCells; ++c)
        prefix[c + 1] = prefix[c] + count[c];
    std::vector<std::pair<uint32_t, uint32_t>> leaves;  // [first, end) cell ranges
    auto recurse = [&](auto&& self, uint32_t first, uint32_t size) -> void {
        uint64_t n = prefix[first + size] - prefix[first];
        if (n == 0)
            return;
        if (n <= opt.max_faces || size == 1) {
            leaves.emplace_back(first, first + size);
            return;
        }
        for (uint32_t k = 0; k < 8; ++k)
            self(self, first + k * (size / 8), size / 8);
    };
    recurse(recurse, 0, kCells);
    std::vector<uint32_t> brick_of_cell(kCells, 0);
    for (auto [first, end] : leaves) {
        uint64_t n = prefix[end] - prefix[first];
        if (plan.bricks.empty() || plan.bricks.back().face_count + n > opt.max_faces)
            plan.bricks.push_back(BrickInfo{0, first, end});
        BrickInfo& b = plan.bricks.back();
        b.face_count += n;
        b.end_cell = end;
        for (uint32_t c = first; c < end; ++c)
            brick_of_cell[c] = uint32_t(plan.bricks.size() - 1);
    }
    std::vector<uint32_t>().swap(count);
    std::vector<uint64_t>().swap(prefix);

    // 3. Distribution, and which brick(s) use each vertex.
    {
        DiskArray<uint32_t> owners(OwnersPath(dir), true, cache);
        const uint32_t none = kOwnerNone;
        for (uint64_t v = 0; v < spill.vertex_count; ++v)
            owners.Push(none);
        std::vector<BrickFile> files;
        files.reserve(plan.bricks.size());
        const size_t flush_bytes = std::clamp(
            kBufferBytes / std::max<size_t>(plan.bricks.size(), 1), kMinFlushBytes, kMaxFlushBytes);
        for (uint32_t b = 0; b < plan.bricks.size(); ++b)
            files.emplace_back(BrickPath(dir, b), flush_bytes);
        for (auto& b : plan.bricks)
            b.face_count = 0;
        for (uint64_t f = 0; f < spill.face_count; ++f) {
            SpillFace sf = faces.Get(f);
            uint32_t brick = brick_of_cell[cells.Get(f)];
            files[brick].Add(BrickFace{{sf.v[0], sf.v[1], sf.v[2]}, f, sf.material, 0});
            ++plan.bricks[brick].face_count;
            if (opt.progress && (f & 4095) == 4095)
                opt.progress->Add(4096);
            for (int c = 0; c < 3; ++c) {
                uint32_t o = owners.Get(sf.v[c]);
                if (o == kOwnerNone)
                    owners.Set(sf.v[c], brick);
                else if (o != brick && o != kOwnerShared)
                    owners.Set(sf.v[c], kOwnerShared);
            }
        }
        for (auto& file : files)
            file.Close();
        owners.Flush();
    }
    std::filesystem::remove(dir + "/cells.bin");
    return plan;
}

std::vector<BrickFace> ReadBrick(const std::string& dir, uint32_t brick) {
    std::string path = BrickPath(dir, brick);
    std::vector<BrickFace> out;
    int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) {
        if (errno == ENOENT)
            return out;  // a brick whose faces were all elsewhere
        IoError({path}, "cannot open: {}", ErrnoString(errno));
    }
    std::vector<char> block;
    uint64_t offset = 0;
    for (;;) {
        uint32_t head[3];
        ssize_t n = ::pread(fd, head, 12, off_t(offset));
        if (n == 0)
            break;
        if (n != 12) {
            ::close(fd);
            CorruptError({path, offset}, "truncated block header");
        }
        if (head[0] % sizeof(BrickFace) != 0 || head[0] > (64u << 20) || head[1] > (64u << 20)) {
            ::close(fd);
            CorruptError({path, offset}, "bad block sizes");
        }
        block.resize(head[1]);
        if (::pread(fd, block.data(), head[1], off_t(offset + 12)) != ssize_t(head[1]) ||
            Crc32(block.data(), head[1]) != head[2]) {
            ::close(fd);
            CorruptError({path, offset}, "block checksum mismatch");
        }
        size_t at = out.size();
        out.resize(at + head[0] / sizeof(BrickFace));
        if (!io::DecodeLz4({reinterpret_cast<const uint8_t*>(block.data()), head[1]},
                           {reinterpret_cast<uint8_t*>(out.data() + at), head[0]})) {
            ::close(fd);
            CorruptError({path, offset}, "block does not decompress");
        }
        offset += 12 + head[1];
    }
    ::close(fd);
    return out;
}

void WriteBrick(const std::string& dir, uint32_t brick, const std::vector<BrickFace>& faces) {
    std::filesystem::remove(BrickPath(dir, brick));
    BrickFile file(BrickPath(dir, brick), kMaxFlushBytes);
    for (const BrickFace& f : faces)
        file.Add(f);
    file.Close();
}

namespace {

// The vertex ids the faces use, ascending, each once. A brick that holds a whole scan uses
// nearly every id of its span (0 .. V-1): one mark per id of the span then replaces the
// sort of 3 ids per face (which ran on one core before the brick's segmentation).
std::vector<uint64_t> UsedIds(const std::vector<BrickFace>& faces) {
    std::vector<uint64_t> ids;
    if (faces.empty())
        return ids;
    uint64_t lo = faces[0].v[0], hi = lo;
    for (const auto& f : faces)
        for (uint64_t v : f.v) {
            lo = std::min(lo, v);
            hi = std::max(hi, v);
        }
    if (hi - lo < 4 * 3 * uint64_t(faces.size())) {
        std::vector<uint8_t> used(size_t(hi - lo) + 1, 0);
        for (const auto& f : faces)
            for (uint64_t v : f.v)
                used[size_t(v - lo)] = 1;
        for (size_t i = 0; i < used.size(); ++i)
            if (used[i])
                ids.push_back(lo + i);
        return ids;
    }
    ids.reserve(faces.size() * 3);
    for (const auto& f : faces)
        ids.insert(ids.end(), f.v, f.v + 3);
    std::sort(ids.begin(), ids.end());
    ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
    return ids;
}

}  // namespace

TriMesh LoadBrick(const std::string& dir, uint32_t brick, size_t cache_bytes,
                  std::vector<uint8_t>* on_cut) {
    std::vector<BrickFace> faces = ReadBrick(dir, brick);
    const std::vector<uint64_t> ids = UsedIds(faces);

    TriMesh m;
    m.vertex_id = ids;
    m.position.resize(ids.size());
    on_cut->assign(ids.size(), 0);
    DiskArray<Vec3f> positions(Spill::VerticesPath(dir), false, cache_bytes / 3);
    DiskArray<SpillColor> colors(Spill::ColorsPath(dir), false, cache_bytes / 3);
    DiskArray<uint32_t> owners(OwnersPath(dir), false, cache_bytes / 3);
    bool any_color = false;
    std::vector<SpillColor> col(ids.size());
    for (size_t i = 0; i < ids.size(); ++i) {
        m.position[i] = positions.Get(ids[i]);
        col[i] = colors.Get(ids[i]);
        any_color |= col[i].a != 0;
        (*on_cut)[i] = owners.Get(ids[i]) == kOwnerShared;
    }
    if (any_color) {
        m.albedo.resize(ids.size());
        for (size_t i = 0; i < ids.size(); ++i)
            m.albedo[i] = col[i].a ? Vec3f(col[i].r / 255.f, col[i].g / 255.f, col[i].b / 255.f)
                                   : Vec3f(-1, -1, -1);
    }
    // Local index of a global id: a binary search inside one bucket of ids by their high
    // bits (about one id per bucket) instead of over all of them, a cache miss per step.
    const uint64_t lo = ids.empty() ? 0 : ids.front(), span = ids.empty() ? 0 : ids.back() - lo;
    int shift = 0;
    while ((span >> shift) >= std::max<size_t>(ids.size(), 1))
        ++shift;
    std::vector<uint32_t> bucket((span >> shift) + 2, 0);
    for (uint64_t id : ids)
        ++bucket[((id - lo) >> shift) + 1];
    for (size_t b = 1; b < bucket.size(); ++b)
        bucket[b] += bucket[b - 1];
    m.triangles.reserve(faces.size());
    for (const auto& f : faces) {
        std::array<uint32_t, 3> t;
        for (int c = 0; c < 3; ++c) {
            const uint64_t b = (f.v[c] - lo) >> shift;
            t[size_t(c)] = uint32_t(std::lower_bound(ids.begin() + bucket[b],
                                                     ids.begin() + bucket[b + 1], f.v[c]) -
                                    ids.begin());
        }
        m.triangles.push_back(t);
        m.face_id.push_back(f.face_id);
        m.material.push_back(f.material);
    }
    return m;
}

}  // namespace mebake::stream
