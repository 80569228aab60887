#include "output/texel_stitch.h"

#include "core/check.h"
#include "core/memory_budget.h"
#include "core/paged_file.h"
#include "core/parallel.h"
#include "output/seam_graph.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <mutex>
#include <unordered_map>

namespace mebake::output {

namespace {

constexpr double kSamplesPerTexel = 3;
constexpr uint32_t kMaxSamplesPerEdge = 256;
constexpr int kMaxIterations = 500;
constexpr double kTolerance = 1e-7;  // relative residual of the normal equations
constexpr uint32_t kTrimCharts = 4;  // charts prepared between returns of the freed heap
constexpr size_t kFileCacheBytes = size_t(256) << 10;  // each of the texel and value files
constexpr size_t kBlockSlots = 16384;  // slots read (and written) at a time by the CG


Vec2d D(Vec2f v) {
    return {double(v.x), double(v.y)};
}

// The 2 x 2 texels a bilinear filter reads at chart point p (clamped as the gutter does),
// and where p lies between them (the weights, BilinearWeights).
struct Footprint {
    std::array<uint32_t, 4> texel;
    double ax, ay;
};

std::array<double, 4> BilinearWeights(double ax, double ay) {
    return {(1 - ax) * (1 - ay), ax * (1 - ay), (1 - ax) * ay, ax * ay};
}

Footprint Bilinear(Vec2d p, uint32_t res) {
    const double x = p.x * res - 0.5, y = p.y * res - 0.5;
    const double fx = std::floor(x), fy = std::floor(y);
    const double ax = x - fx, ay = y - fy;
    auto clamp = [&](double v) {
        return uint32_t(std::clamp(v, 0.0, double(res - 1)));
    };
    const uint32_t i0 = clamp(fx), i1 = clamp(fx + 1), j0 = clamp(fy), j1 = clamp(fy + 1);
    return {{j0 * res + i0, j0 * res + i1, j1 * res + i0, j1 * res + i1},
            ax, ay};
}

struct EdgeSide {
    uint32_t chart = 0;
    Vec2f a, b;  // uv of g0, g1
    Vec3f normal;  // of the face beside the edge
    Vec3f n0, n1;  // shading normals at g0, g1
};

// A chart's outline edges and the texels their bilinear footprints read, as shaded.
struct ChartPart {
    std::vector<IdPair> keys;
    std::vector<EdgeSide> sides;
    std::vector<uint32_t> texels;  // sorted
    std::vector<float> values;     // channels per texel
};

ChartPart PrepareChart(const BakeView& view, const Atlas& atlas, uint32_t c,
                       const stream::ChartTile& tile, MapContent content) {
    ChartPart part;
    const uint32_t res = atlas.charts[c].resolution;
    for (const OutlineEdge& e : OutlineEdges(tile, view.manifest.vertex_count)) {
        EdgeSide s{c, tile.uv[e.v0], tile.uv[e.v1], FaceNormal(tile, e.triangle),
                   tile.normal[e.v0], tile.normal[e.v1]};
        // Footprints of points every 1/8 texel: every texel a seam sample can read (a sample
        // reading one not listed here is dropped; it can only graze a texel corner).
        const double len = Length(D(s.b) - D(s.a)) * res;
        const int steps = int(std::ceil(8 * len)) + 1;
        for (int k = 0; k <= steps; ++k) {
            const double t = double(k) / steps;
            const Footprint f = Bilinear(D(s.a) + (D(s.b) - D(s.a)) * t, res);
            part.texels.insert(part.texels.end(), f.texel.begin(), f.texel.end());
        }
        part.keys.push_back({e.g0, e.g1});
        part.sides.push_back(s);
    }
    std::sort(part.texels.begin(), part.texels.end());
    part.texels.erase(std::unique(part.texels.begin(), part.texels.end()), part.texels.end());
    if (part.texels.empty())
        return part;
    const auto field = view.Field(c);
    const ChartShader shader(tile, *field, view.solution.radiosity, view.scene, view.TilePath(c),
                             view.Seams(c));
    const size_t nc = size_t(MapChannels(content));
    part.values.resize(part.texels.size() * nc);
    const uint32_t g = atlas.gutter;
    for (size_t k = 0; k < part.texels.size(); ++k) {
        const uint32_t i = part.texels[k] % res, j = part.texels[k] / res;
        ShadeTexel(shader, atlas.TexelUv(c, i + g, j + g), content, &part.values[k * nc]);
    }
    return part;
}

// Rows of A: 8 (unknown, weight) entries per seam sample, side y's weights negated; the
// weights are kept as the two footprints' (ax, ay) (64 bytes a row, not 96) and made again
// when used, the same doubles. Every CG pass reads them all in order. They stay in memory,
// in blocks, up to a byte cap (the export's `export.stitch_rows` share); past it they all
// move to a temporary file behind a small page cache (core/paged_file.h) that each pass
// reads a block at a time: they are the stitch's largest part (46 MB at 50M triangles).
// In memory the passes over them were a third of the horse's export CPU: a 4 MiB cache
// that a 6.6 MB file cycles through misses every page, and every pass copied the rows in
// through the kernel (bench/RESULTS.md, "Issue 13 (session 15)").
struct SeamRow {
    uint32_t index[8];
    double frac[4];  // x's ax, ay, y's ax, ay
    std::array<double, 8> Weights() const {
        const std::array<double, 4> wx = BilinearWeights(frac[0], frac[1]);
        const std::array<double, 4> wy = BilinearWeights(frac[2], frac[3]);
        return {wx[0], wx[1], wx[2], wx[3], -wy[0], -wy[1], -wy[2], -wy[3]};
    }
};

class SeamRows {
public:
    explicit SeamRows(size_t memory_bytes) : memory_rows_(memory_bytes / sizeof(SeamRow)) {}
    uint64_t rows() const { return file_ ? file_->size() : count_; }
    bool in_memory() const { return !file_; }
    uint64_t memory_bytes() const { return uint64_t(blocks_.size()) * kBlockRows * sizeof(SeamRow); }
    void Add(const std::array<uint32_t, 8>& idx, const Footprint& fx, const Footprint& fy) {
        SeamRow r;
        std::copy(idx.begin(), idx.end(), r.index);
        r.frac[0] = fx.ax, r.frac[1] = fx.ay, r.frac[2] = fy.ax, r.frac[3] = fy.ay;
        if (!file_ && count_ >= memory_rows_)
            MoveToFile();
        if (file_) {
            file_->Push(r);
            return;
        }
        if (count_ % kBlockRows == 0) {
            blocks_.emplace_back();
            blocks_.back().reserve(kBlockRows);
        }
        blocks_.back().push_back(r);
        ++count_;
    }
    // f(row) for every row in order. Concurrent calls are safe while the rows are in memory.
    template <typename F>
    void ForEach(F&& f) {
        if (!file_) {
            for (const auto& block : blocks_)
                for (const SeamRow& row : block)
                    f(row);
            return;
        }
        const uint64_t n = rows();
        block_.resize(size_t(std::min<uint64_t>(n, kBlockRows)));
        for (uint64_t first = 0; first < n; first += kBlockRows) {
            const size_t count = size_t(std::min<uint64_t>(kBlockRows, n - first));
            file_->file().Read(first * sizeof(SeamRow), block_.data(), count * sizeof(SeamRow));
            for (size_t k = 0; k < count; ++k)
                f(block_[k]);
        }
    }

private:
    static constexpr size_t kRowCacheBytes = size_t(4) << 20;
    static constexpr uint64_t kBlockRows = 4096;  // 256 KiB

    void MoveToFile() {
        file_ = std::make_unique<DiskArray<SeamRow>>(
            PagedFile::Temporary{{}, "texel stitch rows"}, kRowCacheBytes);
        for (const auto& block : blocks_)
            file_->PushMany(block.data(), block.size());
        blocks_ = {};
    }

    uint64_t memory_rows_;
    uint64_t count_ = 0;  // rows in memory
    std::vector<std::vector<SeamRow>> blocks_;  // kBlockRows each, the last one filling
    std::unique_ptr<DiskArray<SeamRow>> file_;  // set once the rows outgrow memory_rows_
    std::vector<SeamRow> block_;  // the file's rows being read
};

// y = (I + lambda A^T A) x.
void ApplyNormal(SeamRows& a, const std::vector<double>& x, std::vector<double>& y) {
    y = x;
    a.ForEach([&](const SeamRow& row) {
        const std::array<double, 8> w = row.Weights();
        double ax = 0;
        for (size_t k = 0; k < 8; ++k)
            ax += w[k] * x[row.index[k]];
        for (size_t k = 0; k < 8; ++k)
            y[row.index[k]] += kSeamWeight * w[k] * ax;
    });
}

// Preconditioned conjugate gradients for (I + lambda A^T A) x = b from x = b, in place (x
// holds b on entry); returns the iterations. The preconditioned residual z = r / diag is
// made where it is used, not stored.
int SolveChannel(SeamRows& a, const std::vector<double>& diag, std::vector<double>& x) {
    const size_t n = x.size();
    std::vector<double> r(n), p(n), q(n);
    ApplyNormal(a, x, q);
    // rr = |r|^2 is summed in the loop that makes r, beside rz: each sum is one chain of
    // dependent additions (in index order, so the same doubles), and two chains in one
    // loop overlap where two loops wait on each in turn.
    double bnorm = 0, rz = 0, rr = 0;
    for (size_t i = 0; i < n; ++i) {
        r[i] = x[i] - q[i];
        p[i] = r[i] / diag[i];
        rz += r[i] * p[i];
        bnorm += x[i] * x[i];
        rr += r[i] * r[i];
    }
    const double stop = kTolerance * kTolerance * std::max(bnorm, 1e-300);
    int it = 0;
    for (; it < kMaxIterations; ++it) {
        if (rr <= stop)
            break;
        ApplyNormal(a, p, q);
        double pq = 0;
        for (size_t i = 0; i < n; ++i)
            pq += p[i] * q[i];
        if (!(pq > 0))
            break;
        const double alpha = rz / pq;
        double rz_next = 0;
        rr = 0;
        for (size_t i = 0; i < n; ++i) {
            x[i] += alpha * p[i];
            r[i] -= alpha * q[i];
            rz_next += r[i] * (r[i] / diag[i]);
            rr += r[i] * r[i];
        }
        const double beta = rz_next / rz;
        rz = rz_next;
        for (size_t i = 0; i < n; ++i)
            p[i] = r[i] / diag[i] + beta * p[i];
    }
    return it;
}

double MismatchSquares(SeamRows& a, const std::vector<double>& x) {
    double sum = 0;
    a.ForEach([&](const SeamRow& row) {
        const std::array<double, 8> w = row.Weights();
        double ax = 0;
        for (size_t k = 0; k < 8; ++k)
            ax += w[k] * x[row.index[k]];
        sum += ax * ax;
    });
    return sum;
}

// One channel's CG and the bilinear mismatch before and after it.
struct ChannelSolve {
    double before = 0, after = 0;
    int iterations = 0;
};

ChannelSolve SolveAndMeasure(SeamRows& a, const std::vector<double>& diag,
                             std::vector<double>& x) {
    ChannelSolve r;
    r.before = MismatchSquares(a, x);
    r.iterations = SolveChannel(a, diag, x);
    r.after = MismatchSquares(a, x);
    return r;
}

// A solved texel as the map stores it: B >= 0; E is signed.
float StoredValue(MapContent content, double x) {
    return content == MapContent::Radiosity ? std::max(0.f, float(x)) : float(x);
}

}  // namespace

const float* StitchedTexels::Find(uint32_t t, int channels) const {
    const auto it = std::lower_bound(texel.begin(), texel.end(), t);
    return it == texel.end() || *it != t ? nullptr
                                          : &values[size_t(it - texel.begin()) * size_t(channels)];
}

struct TexelStitch::Files {
    std::mutex mutex;  // the files' page caches
    DiskArray<uint32_t> texels{PagedFile::Temporary{{}, "texel stitch texels"}, kFileCacheBytes};
    DiskArray<float> values{PagedFile::Temporary{{}, "texel stitch values"}, kFileCacheBytes};
};

TexelStitch::TexelStitch() : files_(std::make_unique<Files>()) {}
TexelStitch::~TexelStitch() = default;
TexelStitch::TexelStitch(TexelStitch&&) noexcept = default;

StitchedTexels TexelStitch::Chart(uint32_t c) const {
    StitchedTexels t;
    if (size_t(c) + 1 >= first_.size() || first_[c] == first_[c + 1])
        return t;
    const size_t first = first_[c], n = first_[c + 1] - first, nc = size_t(channels_);
    t.texel.resize(n);
    t.values.resize(n * nc);
    const std::lock_guard lock(files_->mutex);
    files_->texels.file().Read(first * sizeof(uint32_t), t.texel.data(), n * sizeof(uint32_t));
    files_->values.file().Read(first * nc * sizeof(float), t.values.data(),
                               n * nc * sizeof(float));
    return t;
}

TexelStitch StitchTexels(const BakeView& view, const Atlas& atlas, MapContent content,
                         TexelStitchStats* stats, uint64_t memory_bytes) {
    TexelStitch st;
    st.channels_ = MapChannels(content);
    const size_t nc = size_t(st.channels_);
    // Radiosity maps stitch R, G, B (A stays 1).
    const size_t solved = content == MapContent::Radiosity ? 3 : nc;
    const std::vector<uint32_t> last = LastNeighbours(view);
    BorderPairing<EdgeSide> pairing(last);
    SeamRows rows(memory_bytes);
    st.first_.assign(1, 0);
    // The texel lists of the charts a later chart can still pair with (the rest are only
    // in the file).
    std::unordered_map<uint32_t, std::vector<uint32_t>> live;
    auto slot = [&](uint32_t chart, uint32_t texel) -> int64_t {
        const auto at = live.find(chart);
        CHECK(at != live.end());
        const std::vector<uint32_t>& t = at->second;
        const auto it = std::lower_bound(t.begin(), t.end(), texel);
        return it == t.end() || *it != texel ? -1 : st.first_[chart] + (it - t.begin());
    };
    auto add_pair = [&](const EdgeSide& x, const EdgeSide& y) {
        const uint32_t rx = atlas.charts[x.chart].resolution, ry = atlas.charts[y.chart].resolution;
        const double len = std::max(Length(D(x.b) - D(x.a)) * rx, Length(D(y.b) - D(y.a)) * ry);
        const uint32_t n = uint32_t(
            std::clamp(std::ceil(kSamplesPerTexel * len), 1.0, double(kMaxSamplesPerEdge)));
        for (uint32_t k = 0; k < n; ++k) {
            const double t = (k + 0.5) / n;
            const Footprint fx = Bilinear(D(x.a) + (D(x.b) - D(x.a)) * t, rx);
            const Footprint fy = Bilinear(D(y.a) + (D(y.b) - D(y.a)) * t, ry);
            std::array<uint32_t, 8> idx;
            bool found = true;
            for (int m = 0; m < 8 && found; ++m) {
                const int64_t at = m < 4 ? slot(x.chart, fx.texel[size_t(m)])
                                         : slot(y.chart, fy.texel[size_t(m - 4)]);
                found = at >= 0;
                if (found)
                    idx[size_t(m)] = uint32_t(at);
            }
            if (found)
                rows.Add(idx, fx, fy);
        }
    };
    TexelStitch::Files& files = *st.files_;
    ForEachTile(
        view, AllCharts(view), stream::TileParts::Mesh,
        [&](uint32_t c, stream::ChartTile& tile) {
            return PrepareChart(view, atlas, c, tile, content);
        },
        [&](uint32_t c, stream::ChartTile&, ChartPart& part) {
            CHECK_EQ(st.first_.size(), size_t(c) + 1);
            st.first_.push_back(st.first_.back() + uint32_t(part.texels.size()));
            files.texels.PushMany(part.texels.data(), part.texels.size());
            files.values.PushMany(part.values.data(), part.values.size());
            part.texels.shrink_to_fit();  // sorted and made unique in place
            live.emplace(c, std::move(part.texels));
            for (size_t i = 0; i < part.sides.size(); ++i)
                pairing.Add(c, part.keys[i], part.sides[i],
                            [&](const EdgeSide& x, const EdgeSide& y) {
                                if (!Crease(x.normal, y.normal, x.n0, y.n0, x.n1, y.n1,
                                            kStitchFoldCos))
                                    add_pair(x, y);
                            });
            pairing.Done(c);
            for (const uint32_t a : pairing.Retired(c))
                live.erase(a);
            // Each chart's tile, field and shader are freed around what the pass keeps,
            // leaving holes that stay resident: back to the system every kTrimCharts
            // charts, so what is resident does not grow with the chart count.
            if (c % kTrimCharts == kTrimCharts - 1)
                ReturnFreedHeap();
        });
    // The tiles, fields and shaders the preparation freed are still resident in the
    // workers' heaps: back to the system before the solve's vectors are made.
    ReturnFreedHeap();
    const size_t n = st.size();
    // f(slot, its channels) for every slot in order, the values read from the file a block
    // at a time (and written back when `write`).
    auto for_each_slot = [&](bool write, auto&& f) {
        std::vector<float> block;
        for (size_t first = 0; first < n; first += kBlockSlots) {
            const size_t count = std::min(kBlockSlots, n - first);
            block.resize(count * nc);
            const uint64_t at = first * nc * sizeof(float), bytes = block.size() * sizeof(float);
            files.values.file().Read(at, block.data(), bytes);
            for (size_t k = 0; k < count; ++k)
                f(first + k, &block[k * nc]);
            if (write)
                files.values.file().Write(at, block.data(), bytes);
        }
    };
    std::vector<double> diag(n, 1.0);
    rows.ForEach([&](const SeamRow& row) {
        const std::array<double, 8> w = row.Weights();
        for (size_t k = 0; k < 8; ++k)
            diag[row.index[k]] += kSeamWeight * w[k] * w[k];
    });
    TexelStitchStats s;
    s.texels = n;
    s.samples = rows.rows();
    // The channels' CGs share nothing but the rows and the diagonal: with the rows in
    // memory and room in memory_bytes for every channel's four CG vectors, they run in
    // parallel (each writes its own vectors: the same doubles as one after the other);
    // else one after the other with one set of vectors.
    const uint64_t cg_bytes = uint64_t(solved) * 4 * sizeof(double) * n;
    const bool parallel = rows.in_memory() && rows.memory_bytes() + cg_bytes <= memory_bytes;
    s.rows_in_memory = rows.in_memory();
    s.channels_in_parallel = parallel && rows.rows() > 0;
    std::vector<ChannelSolve> solves(solved);
    if (rows.rows() > 0 && parallel) {
        std::vector<std::vector<double>> xs(solved, std::vector<double>(n));
        for_each_slot(false, [&](size_t i, const float* v) {
            for (size_t ch = 0; ch < solved; ++ch)
                xs[ch][i] = v[ch];
        });
        ParallelFor(0, int64_t(solved), [&](int64_t ch) {
            solves[size_t(ch)] = SolveAndMeasure(rows, diag, xs[size_t(ch)]);
        });
        for_each_slot(true, [&](size_t i, float* v) {
            for (size_t ch = 0; ch < solved; ++ch)
                v[ch] = StoredValue(content, xs[ch][i]);
        });
    } else if (rows.rows() > 0) {
        std::vector<double> x(n);
        for (size_t ch = 0; ch < solved; ++ch) {
            for_each_slot(false, [&](size_t i, const float* v) { x[i] = v[ch]; });
            solves[ch] = SolveAndMeasure(rows, diag, x);
            for_each_slot(true, [&](size_t i, float* v) { v[ch] = StoredValue(content, x[i]); });
        }
    }
    double before = 0, after = 0;
    for (const ChannelSolve& c : solves) {  // in channel order, as the passes were made
        before += c.before;
        after += c.after;
        s.iterations = std::max(s.iterations, c.iterations);
    }
    const double count = double(std::max<size_t>(1, rows.rows() * solved));
    s.rms_before = std::sqrt(before / count);
    s.rms_after = std::sqrt(after / count);
    if (stats)
        *stats = s;
    return st;
}

}  // namespace mebake::output
