// mkscan: writes synthetic scan-like meshes of any size as PLY, deterministic from a seed.
//
// Shapes are quad lattices split into triangles: a noisy displaced sphere built on the
// surface of an a x b x c box lattice (a "cube sphere", mapped to the sphere with
// Nowell's area-balancing cube-to-sphere formula, so there are no pole fans), or a
// terrain height field over a square. Displacement is multi-octave value noise
// (Perlin 1985 style lattice noise with smoothstep interpolation) over an integer hash,
// so output depends only on IEEE arithmetic, never on std::random distributions.
//
// Every vertex and face is a pure function of its index, so the mesh is streamed: the
// vertex element, then the face element, written in lattice order (faces reference
// nearby vertices, like a real scan export), in O(1) memory besides the small lists of
// hole cells and non-manifold spots. Counts are computed exactly before the header.
//
// Realism options for ingest tests: holes (faces of small disks removed; their interior
// vertices stay in the vertex list, unreferenced), duplicated vertices (a copy right
// after the original, each face corner picking either copy), non-manifold "fins" (an
// extra triangle on a quad diagonal, so three faces share that edge), several
// components, smooth per-vertex colours.
#include "core/error.h"
#include "core/parallel.h"
#include "core/vec.h"
#include "io/byte_stream.h"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <array>
#include <bit>
#include <cerrno>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fcntl.h>
#include <memory>
#include <string>
#include <sys/stat.h>
#include <unistd.h>
#include <unordered_set>
#include <vector>

namespace {

using mebake::Vec3d;
using mebake::io::OutputStream;

static_assert(std::endian::native == std::endian::little,
              "mkscan writes binary_little_endian PLY by memcpy");

// ---- hashing and noise ------------------------------------------------------------

// The 64-bit finalizer of MurmurHash3 (fmix64): a bijective avalanche mix.
constexpr uint64_t Mix(uint64_t h) {
    h ^= h >> 33;
    h *= 0xff51afd7ed558ccdULL;
    h ^= h >> 33;
    h *= 0xc4ceb9fe1a85ec53ULL;
    h ^= h >> 33;
    return h;
}

constexpr uint64_t Hash(uint64_t seed, uint64_t a, uint64_t b = 0, uint64_t c = 0) {
    uint64_t h = Mix(seed + 0x9e3779b97f4a7c15ULL);
    h = Mix(h ^ (a + 0x632be59bd9b4e019ULL));
    h = Mix(h ^ (b + 0x85157af5ULL));
    return Mix(h ^ (c + 0x2545f4914f6cdd1dULL));
}

// One mix round over the arguments: for per-element choices and noise lattices, where
// Hash's four rounds would dominate the run time.
constexpr uint64_t Hash1(uint64_t seed, uint64_t a, uint64_t b = 0, uint64_t c = 0) {
    return Mix(seed ^ (a * 0x9e3779b97f4a7c15ULL) ^ (b * 0xc2b2ae3d27d4eb4fULL) ^
               (c * 0x165667b19e3779f9ULL));
}

// [0, 1) from the top 53 bits.
double Unit(uint64_t h) {
    return double(h >> 11) * 0x1.0p-53;
}
// [-1, 1)
double Signed(uint64_t h) {
    return 2.0 * Unit(h) - 1.0;
}

// floor() without the libm call baseline x86-64 makes (exact for |x| < 2^63).
int64_t Floor(double x) {
    int64_t i = int64_t(x);
    return double(i) > x ? i - 1 : i;
}

double Smooth(double t) {
    return t * t * (3.0 - 2.0 * t);
}
double Lerp(double a, double b, double t) {
    return a + (b - a) * t;
}

// Value noise over Perlin's permutation-table lattice (Perlin 2002, "Improving noise":
// a shuffled 256-entry table indexed by the wrapped cell coordinates), with a random
// value per table entry. Table look-ups instead of a hash per lattice corner make it
// several times faster; the 256-cell period is far beyond the frequencies used here.
class Noise {
public:
    explicit Noise(uint64_t seed) {
        for (int i = 0; i < 256; ++i)
            perm_[i] = uint16_t(i);
        for (int i = 255; i > 0; --i)
            std::swap(perm_[i], perm_[Hash(seed, 0x9e12, uint64_t(i)) % uint64_t(i + 1)]);
        for (int i = 0; i < 256; ++i) {
            perm_[256 + i] = perm_[i];
            value_[i] = Signed(Hash(seed, 0x7a1, uint64_t(i)));
        }
    }

    double Value3(double x, double y, double z) const {
        int64_t fx = Floor(x), fy = Floor(y), fz = Floor(z);
        // Two's complement wrap: only the low 8 bits matter.
        unsigned ix = unsigned(fx) & 255, iy = unsigned(fy) & 255, iz = unsigned(fz) & 255;
        double tx = Smooth(x - double(fx)), ty = Smooth(y - double(fy)),
               tz = Smooth(z - double(fz));
        unsigned a = perm_[ix] + iy, b = perm_[ix + 1] + iy;
        unsigned aa = perm_[a] + iz, ab = perm_[a + 1] + iz;
        unsigned ba = perm_[b] + iz, bb = perm_[b + 1] + iz;
        double c00 = Lerp(value_[perm_[aa]], value_[perm_[ba]], tx);
        double c10 = Lerp(value_[perm_[ab]], value_[perm_[bb]], tx);
        double c01 = Lerp(value_[perm_[aa + 1]], value_[perm_[ba + 1]], tx);
        double c11 = Lerp(value_[perm_[ab + 1]], value_[perm_[bb + 1]], tx);
        return Lerp(Lerp(c00, c10, ty), Lerp(c01, c11, ty), tz);
    }

    double Value2(double x, double y) const {
        int64_t fx = Floor(x), fy = Floor(y);
        unsigned ix = unsigned(fx) & 255, iy = unsigned(fy) & 255;
        double tx = Smooth(x - double(fx)), ty = Smooth(y - double(fy));
        unsigned a = perm_[ix] + iy, b = perm_[ix + 1] + iy;
        double c0 = Lerp(value_[perm_[a]], value_[perm_[b]], tx);
        double c1 = Lerp(value_[perm_[a + 1]], value_[perm_[b + 1]], tx);
        return Lerp(c0, c1, ty);
    }

    // Fractional Brownian motion: octaves of doubling frequency and halving amplitude,
    // each shifted so their lattices do not align; normalised to about [-1, 1].
    double Fbm3(Vec3d p, int octaves) const {
        double sum = 0, amp = 1, norm = 0;
        for (int o = 0; o < octaves; ++o) {
            sum += amp * Value3(p.x, p.y, p.z);
            norm += amp;
            amp *= 0.5;
            p = p * 2.03 + Vec3d(17.31, 41.57, 73.19);
        }
        return sum / norm;
    }

    double Fbm2(double x, double y, int octaves) const {
        double sum = 0, amp = 1, norm = 0;
        for (int o = 0; o < octaves; ++o) {
            sum += amp * Value2(x, y);
            norm += amp;
            amp *= 0.5;
            x = x * 2.03 + 17.31;
            y = y * 2.03 + 41.57;
        }
        return sum / norm;
    }

private:
    uint16_t perm_[512];
    double value_[256];
};

struct Rgb {
    uint8_t r = 0, g = 0, b = 0;
};

// Rounds to the nearest byte (255.5 truncates to 255).
uint8_t ToByte(double v) {
    return uint8_t(std::clamp(v, 0.0, 255.0) + 0.5);
}

Rgb Blend(const double a[3], const double b[3], double t) {
    t = std::clamp(t, 0.0, 1.0);
    return {ToByte(Lerp(a[0], b[0], t)), ToByte(Lerp(a[1], b[1], t)), ToByte(Lerp(a[2], b[2], t))};
}

// ---- options ----------------------------------------------------------------------

struct Options {
    uint64_t triangles = 0;
    std::string shape = "sphere";
    uint64_t seed = 1;
    double noise = -1;  // < 0: the shape's default
    uint64_t holes = 0;
    double duplicates = 0;
    uint64_t nonmanifold = 0;
    uint64_t components = 1;
    bool colors = false;
    std::string format = "ply";
    std::string output = "-";
    bool quiet = false;
};

// ---- surfaces ---------------------------------------------------------------------
// A surface is a lattice of quads with vertices numbered 0..VertexCount()-1 in output
// order and quads 0..QuadCount()-1 in output order. Quad(q) gives corners in
// counter-clockwise order seen from outside. Cells(q, r) lists the quads within r cells
// of quad q on its lattice patch (a hole).

// The surface of an a x b x c box lattice, mapped onto a displaced sphere. Vertices:
// the full z=0 slice, then the rings of z=1..c-1, then the full z=c slice. Quads: the
// bottom cap, the c bands of ring quads, the top cap. Faces of a band reference two
// adjacent rings, so references stay local.
class BoxSphere {
public:
    BoxSphere(int64_t a, int64_t b, int64_t c, Vec3d center, double radius, double noise,
              uint64_t seed)
        : a_(a),
          b_(b),
          c_(c),
          center_(center),
          radius_(radius),
          noise_(noise),
          seed_(seed),
          shape_(Hash(seed, 0x5a9e)),
          color_(Hash(seed, 0xc010)) {
        slice_ = (a + 1) * (b + 1);
        ring_ = 2 * (a + b);
        cell_ = 2.0 * radius / double(std::max({a, b, c}));
    }

    static uint64_t QuadsFor(int64_t a, int64_t b, int64_t c) {
        return uint64_t(2 * (a * b + b * c + c * a));
    }
    uint64_t VertexCount() const { return uint64_t(2 * slice_ + (c_ - 1) * ring_); }
    uint64_t QuadCount() const { return QuadsFor(a_, b_, c_); }
    int64_t Width() const { return std::max({a_, b_, c_}); }

    void Quad(uint64_t q, uint64_t v[4]) const {
        int64_t r = int64_t(q);
        if (r < a_ * b_) {  // bottom cap, seen from below
            int64_t y = r / a_, x = r % a_;
            v[0] = Cap(x, y, 0);
            v[1] = Cap(x, y + 1, 0);
            v[2] = Cap(x + 1, y + 1, 0);
            v[3] = Cap(x + 1, y, 0);
            return;
        }
        r -= a_ * b_;
        if (r < c_ * ring_) {  // the ring runs counter-clockwise seen from +z
            int64_t z = r / ring_, p = r % ring_, p1 = (p + 1) % ring_;
            v[0] = Ring(p, z);
            v[1] = Ring(p1, z);
            v[2] = Ring(p1, z + 1);
            v[3] = Ring(p, z + 1);
            return;
        }
        r -= c_ * ring_;
        int64_t y = r / a_, x = r % a_;
        v[0] = Cap(x, y, c_);
        v[1] = Cap(x + 1, y, c_);
        v[2] = Cap(x + 1, y + 1, c_);
        v[3] = Cap(x, y + 1, c_);
    }

    void Cells(uint64_t q, double radius, std::vector<uint64_t>& out) const {
        int64_t r = int64_t(q), base = 0, w = a_, h = b_;
        bool wrap = false;
        if (r >= a_ * b_) {
            r -= a_ * b_;
            base = a_ * b_;
            if (r < c_ * ring_) {
                w = ring_;
                h = c_;
                wrap = true;
            } else {
                r -= c_ * ring_;
                base += c_ * ring_;
            }
        }
        Disk(r % w, r / w, w, h, wrap, radius, base, out);
    }

    Vec3d Position(uint64_t v) const {
        int64_t x, y, z;
        Lattice(v, x, y, z);
        // Nowell's cube-to-sphere map: s in [-1,1]^3 on the cube surface -> unit sphere.
        double sx = 2.0 * double(x) / double(a_) - 1.0;
        double sy = 2.0 * double(y) / double(b_) - 1.0;
        double sz = 2.0 * double(z) / double(c_) - 1.0;
        double x2 = sx * sx, y2 = sy * sy, z2 = sz * sz;
        Vec3d d{sx * std::sqrt(std::max(0.0, 1 - y2 / 2 - z2 / 2 + y2 * z2 / 3)),
                sy * std::sqrt(std::max(0.0, 1 - z2 / 2 - x2 / 2 + z2 * x2 / 3)),
                sz * std::sqrt(std::max(0.0, 1 - x2 / 2 - y2 / 2 + x2 * y2 / 3))};
        double len = std::sqrt(Dot(d, d));
        d = d / len;
        double disp = 0;
        if (noise_ > 0) {
            disp = noise_ * shape_.Fbm3(d * 1.6 + Vec3d(11.5, 7.25, 3.125), 6);
            disp += noise_ * 0.08 * cell_ / radius_ *
                    Signed(Hash1(seed_, 0x6a17, v));  // scanner jitter
        }
        return center_ + d * (radius_ * (1.0 + disp));
    }

    Rgb Color(const Vec3d& pos) const {
        Vec3d p = pos - center_;
        Vec3d d = p / std::sqrt(Dot(p, p));
        static constexpr double kGrey[3] = {118, 112, 106}, kOchre[3] = {176, 142, 96};
        double t = 0.5 + 0.9 * color_.Fbm3(d * 3.0, 4);
        Rgb c = Blend(kGrey, kOchre, t);
        // Darker in hollows: radius below the mean.
        double shade = std::clamp(0.75 + 2.0 * (std::sqrt(Dot(p, p)) / radius_ - 1.0), 0.45, 1.1);
        return {ToByte(c.r * shade), ToByte(c.g * shade), ToByte(c.b * shade)};
    }

private:
    uint64_t Cap(int64_t x, int64_t y, int64_t z) const {
        int64_t base = z == 0 ? 0 : slice_ + (c_ - 1) * ring_;
        return uint64_t(base + y * (a_ + 1) + x);
    }
    // Lattice point p of the perimeter: along y=0, x=a, y=b (backwards), x=0 (backwards).
    void RingPoint(int64_t p, int64_t& x, int64_t& y) const {
        if (p < a_) {
            x = p, y = 0;
        } else if (p < a_ + b_) {
            x = a_, y = p - a_;
        } else if (p < 2 * a_ + b_) {
            x = a_ - (p - a_ - b_), y = b_;
        } else {
            x = 0, y = b_ - (p - 2 * a_ - b_);
        }
    }
    uint64_t Ring(int64_t p, int64_t z) const {
        if (z == 0 || z == c_) {
            int64_t x, y;
            RingPoint(p, x, y);
            return Cap(x, y, z);
        }
        return uint64_t(slice_ + (z - 1) * ring_ + p);
    }
    void Lattice(uint64_t v, int64_t& x, int64_t& y, int64_t& z) const {
        int64_t r = int64_t(v);
        if (r < slice_) {
            z = 0, y = r / (a_ + 1), x = r % (a_ + 1);
            return;
        }
        r -= slice_;
        if (r < (c_ - 1) * ring_) {
            z = 1 + r / ring_;
            RingPoint(r % ring_, x, y);
            return;
        }
        r -= (c_ - 1) * ring_;
        z = c_, y = r / (a_ + 1), x = r % (a_ + 1);
    }

public:
    // The quads of a w x h grid (row-major from `base`) within `radius` cells of (cx,cy).
    static void Disk(int64_t cx, int64_t cy, int64_t w, int64_t h, bool wrap_x, double radius,
                     uint64_t base, std::vector<uint64_t>& out) {
        int64_t r = int64_t(std::ceil(radius));
        for (int64_t dy = -r; dy <= r; ++dy) {
            int64_t y = cy + dy;
            if (y < 0 || y >= h)
                continue;
            for (int64_t dx = -r; dx <= r; ++dx) {
                if (double(dx * dx + dy * dy) > radius * radius)
                    continue;
                int64_t x = cx + dx;
                if (wrap_x) {
                    if (2 * r + 1 > w)
                        continue;  // would wrap onto itself
                    x = (x % w + w) % w;
                } else if (x < 0 || x >= w) {
                    continue;
                }
                out.push_back(base + uint64_t(y * w + x));
            }
        }
    }

private:
    int64_t a_, b_, c_;
    Vec3d center_;
    double radius_, noise_;
    uint64_t seed_;
    Noise shape_, color_;  // displacement, colour variation
    int64_t slice_, ring_;
    double cell_;
};

// A w x h quad height field, vertices row-major. Heights sample noise in world
// coordinates, so tiles of several components line up like one terrain cut apart.
class Terrain {
public:
    Terrain(int64_t w, int64_t h, Vec3d origin, double size, double noise, uint64_t seed)
        : w_(w),
          h_(h),
          origin_(origin),
          noise_(noise),
          seed_(seed),
          shape_(Hash(seed, 0x5a9e)),
          color_(Hash(seed, 0xc010)) {
        cell_ = size / double(std::max(w, h));
        size_ = size;
        // Octaves finer than a few cells would only alias into jagged noise: stop where
        // a noise period (starting at a third of the tile, 2.03x finer each octave)
        // would span fewer than 3 cells.
        octaves_ = 2;
        double period_cells = double(std::max(w, h)) / 3.0;
        while (octaves_ < 7 && period_cells / std::pow(2.03, octaves_) >= 3.0)
            ++octaves_;
    }
    uint64_t VertexCount() const { return uint64_t((w_ + 1) * (h_ + 1)); }
    uint64_t QuadCount() const { return uint64_t(w_ * h_); }
    int64_t Width() const { return std::max(w_, h_); }

    void Quad(uint64_t q, uint64_t v[4]) const {
        int64_t y = int64_t(q) / w_, x = int64_t(q) % w_;
        v[0] = uint64_t(y * (w_ + 1) + x);
        v[1] = v[0] + 1;
        v[2] = v[1] + uint64_t(w_ + 1);
        v[3] = v[0] + uint64_t(w_ + 1);
    }
    void Cells(uint64_t q, double radius, std::vector<uint64_t>& out) const {
        BoxSphere::Disk(int64_t(q) % w_, int64_t(q) / w_, w_, h_, false, radius, 0, out);
    }
    Vec3d Position(uint64_t v) const {
        double x = origin_.x + double(int64_t(v) % (w_ + 1)) * cell_;
        double y = origin_.y + double(int64_t(v) / (w_ + 1)) * cell_;
        return {x, y, origin_.z + Height(x, y) + Jitter(v)};
    }
    Rgb Color(const Vec3d& p) const {
        double t = (p.z - origin_.z) / (noise_ > 0 ? noise_ * size_ : 1.0);  // about [-1,1]
        static constexpr double kGrass[3] = {64, 112, 52}, kSoil[3] = {136, 112, 78},
                                kRock[3] = {150, 146, 140}, kSnow[3] = {236, 238, 242};
        double wobble = 0.15 * color_.Fbm2(p.x * 9.0 / size_, p.y * 9.0 / size_, 3);
        t += wobble;
        if (t < -0.1)
            return Blend(kGrass, kSoil, (t + 0.6) / 0.5);
        if (t < 0.3)
            return Blend(kSoil, kRock, (t + 0.1) / 0.4);
        return Blend(kRock, kSnow, (t - 0.3) / 0.3);
    }

private:
    double Height(double x, double y) const {
        if (noise_ <= 0)
            return 0;
        double f = 3.0 / size_;
        double base = shape_.Fbm2(x * f, y * f, octaves_);
        return noise_ * size_ * base;
    }
    double Jitter(uint64_t v) const {
        return noise_ > 0 ? noise_ * 0.3 * cell_ * Signed(Hash1(seed_, 0x71a, v)) : 0.0;
    }

    int64_t w_, h_;
    int octaves_;
    Vec3d origin_;
    double noise_;
    uint64_t seed_;
    Noise shape_, color_;  // displacement, colour variation
    double cell_, size_;
};

// ---- duplicated vertices ----------------------------------------------------------
// Vertex v of a component is duplicated (its copy written right after it) for exactly
// round(F * L) vertices of every block of L = 1024, chosen by a hashed partial shuffle.
// Exact per-block counts make a vertex's output index arithmetic (no table of the whole
// mesh): out(v) = v + block * D + duplicates before v within its block. Blocks are
// regenerated on demand through a small direct-mapped cache (faces look up nearby ones).
class Duplicates {
public:
    static constexpr int64_t kBlock = 1024;

    Duplicates(double fraction, uint64_t vertices, uint64_t seed)
        : vertices_(vertices), seed_(seed) {
        full_ = fraction > 0 ? int64_t(std::llround(fraction * kBlock)) : 0;
        int64_t tail = int64_t(vertices % kBlock);
        tail_ = fraction > 0 ? int64_t(std::llround(fraction * double(tail))) : 0;
        total_ = (vertices / kBlock) * uint64_t(full_) + uint64_t(tail_);
    }
    uint64_t total() const { return total_; }
    bool any() const { return total_ > 0; }
    void Release() { cache_.reset(); }

    // Output index of v (relative to the component) and whether v has a copy.
    uint64_t Out(uint64_t v, bool* dup) {
        if (total_ == 0) {
            *dup = false;
            return v;
        }
        uint64_t blk = v / kBlock;
        const Block& b = Get(blk);
        unsigned o = unsigned(v % kBlock);
        uint64_t word = b.mask[o / 64], below = word & ((uint64_t(1) << (o % 64)) - 1);
        *dup = (word >> (o % 64)) & 1;
        return v + blk * uint64_t(full_) + b.prefix[o / 64] + uint64_t(std::popcount(below));
    }

private:
    struct Block {
        uint64_t id = ~uint64_t(0);
        uint64_t mask[kBlock / 64];
        uint32_t prefix[kBlock / 64];
    };

    const Block& Get(uint64_t blk) {
        if (!cache_)
            cache_ = std::make_unique<Block[]>(kCache);
        Block& b = cache_[blk % kCache];
        if (b.id == blk)
            return b;
        b.id = blk;
        int64_t len = int64_t(std::min<uint64_t>(kBlock, vertices_ - blk * kBlock));
        int64_t want = len == kBlock ? full_ : tail_;
        uint16_t perm[kBlock];
        for (int64_t i = 0; i < len; ++i)
            perm[i] = uint16_t(i);
        std::memset(b.mask, 0, sizeof(b.mask));
        for (int64_t i = 0; i < want; ++i) {
            int64_t j = i + int64_t(Hash(seed_, 0xd0b, blk, uint64_t(i)) % uint64_t(len - i));
            std::swap(perm[i], perm[j]);
            b.mask[perm[i] / 64] |= uint64_t(1) << (perm[i] % 64);
        }
        uint32_t run = 0;
        for (int w = 0; w < kBlock / 64; ++w) {
            b.prefix[w] = run;
            run += uint32_t(std::popcount(b.mask[w]));
        }
        return b;
    }

    static constexpr size_t kCache = 64;
    uint64_t vertices_, seed_;
    int64_t full_ = 0, tail_ = 0;
    uint64_t total_ = 0;
    std::unique_ptr<Block[]> cache_;  // allocated while the component is being written
};

// ---- output -----------------------------------------------------------------------

class PlyOut {
public:
    PlyOut(OutputStream& out, bool ascii, bool colors) : out_(out), ascii_(ascii), colors_(colors) {
        buf_.resize(kBuf);
    }
    ~PlyOut() = default;

    void Header(uint64_t vertices, uint64_t faces, const std::vector<std::string>& comments) {
        std::string h = "ply\n";
        h += ascii_ ? "format ascii 1.0\n" : "format binary_little_endian 1.0\n";
        for (const auto& c : comments)
            h += "comment " + c + "\n";
        h += "element vertex " + std::to_string(vertices) + "\n";
        h += "property float x\nproperty float y\nproperty float z\n";
        if (colors_)
            h += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
        h += "element face " + std::to_string(faces) + "\n";
        h += "property list uchar int vertex_indices\nend_header\n";
        out_.Write(h);
    }

    void Vertex(const Vec3d& p, Rgb c) {
        Reserve(96);
        float f[3] = {float(p.x), float(p.y), float(p.z)};
        if (!ascii_) {
            std::memcpy(&buf_[n_], f, 12);
            n_ += 12;
            if (colors_) {
                buf_[n_++] = char(c.r);
                buf_[n_++] = char(c.g);
                buf_[n_++] = char(c.b);
            }
            return;
        }
        for (int i = 0; i < 3; ++i) {
            if (i)
                buf_[n_++] = ' ';
            n_ = size_t(std::to_chars(&buf_[n_], &buf_[n_] + 32, f[i]).ptr - buf_.data());
        }
        if (colors_) {
            for (uint8_t v : {c.r, c.g, c.b}) {
                buf_[n_++] = ' ';
                n_ = size_t(std::to_chars(&buf_[n_], &buf_[n_] + 4, v).ptr - buf_.data());
            }
        }
        buf_[n_++] = '\n';
    }

    void Triangle(uint64_t a, uint64_t b, uint64_t c) {
        Reserve(80);
        if (!ascii_) {
            int32_t idx[3] = {int32_t(a), int32_t(b), int32_t(c)};
            buf_[n_++] = 3;
            std::memcpy(&buf_[n_], idx, 12);
            n_ += 12;
            return;
        }
        buf_[n_++] = '3';
        for (uint64_t v : {a, b, c}) {
            buf_[n_++] = ' ';
            n_ = size_t(std::to_chars(&buf_[n_], &buf_[n_] + 24, v).ptr - buf_.data());
        }
        buf_[n_++] = '\n';
    }

    void Finish() {
        Drain();
        out_.Commit();
    }

private:
    void Reserve(size_t k) {
        if (n_ + k > buf_.size())
            Drain();
    }
    void Drain() {
        out_.Write(buf_.data(), n_);
        n_ = 0;
    }

    static constexpr size_t kBuf = size_t(256) << 10;
    OutputStream& out_;
    bool ascii_, colors_;
    std::vector<char> buf_;
    size_t n_ = 0;
};

// ---- planning and emission --------------------------------------------------------

// Everything about one component that must be known before the header.
template <typename Surface>
struct Component {
    Surface surface;
    uint64_t seed;
    std::vector<uint64_t> hole_quads;  // sorted, unique
    std::vector<uint64_t> fin_quads;   // sorted: quads whose diagonal gets a fin
    Duplicates dups;
    uint64_t vertex_base = 0;  // output index of the component's first vertex

    uint64_t BaseVertices() const { return surface.VertexCount(); }
    uint64_t Vertices() const { return BaseVertices() + dups.total() + fin_quads.size(); }
    uint64_t Faces() const {
        return 2 * (surface.QuadCount() - hole_quads.size()) + fin_quads.size();
    }
};

// Picks `holes` disks and `fins` fin quads on the component's surface.
template <typename Surface>
void PlanDefects(Component<Surface>& comp, uint64_t holes, uint64_t fins) {
    const Surface& s = comp.surface;
    uint64_t quads = s.QuadCount();
    // Hole radius: 1% of the grid width, at least 1.5 cells (a 3-cell-wide disk).
    double radius = std::max(1.5, double(s.Width()) / 100.0);
    uint64_t disk = uint64_t(std::ceil(3.2 * radius * radius));  // a little over pi r^2
    if (holes > 0 && holes > quads / disk)
        mebake::UsageError("{} holes of ~{} quads each would cover all {} quads of a component",
                           holes, disk, quads);
    for (uint64_t k = 0; k < holes; ++k)
        s.Cells(Hash(comp.seed, 0x401e, k) % quads, radius, comp.hole_quads);
    std::sort(comp.hole_quads.begin(), comp.hole_quads.end());
    comp.hole_quads.erase(std::unique(comp.hole_quads.begin(), comp.hole_quads.end()),
                          comp.hole_quads.end());
    if (comp.hole_quads.size() == quads)
        mebake::UsageError("--holes removes every face");

    std::unordered_set<uint64_t> taken;
    for (uint64_t k = 0; k < fins; ++k) {
        bool placed = false;
        for (uint64_t attempt = 0; attempt < 256 && !placed; ++attempt) {
            uint64_t q = Hash(comp.seed, 0xf1a, k, attempt) % quads;
            if (std::binary_search(comp.hole_quads.begin(), comp.hole_quads.end(), q))
                continue;
            if (!taken.insert(q).second)
                continue;
            comp.fin_quads.push_back(q);
            placed = true;
        }
        if (!placed)
            mebake::UsageError("cannot place {} non-manifold spots on {} quads", fins, quads);
    }
    std::sort(comp.fin_quads.begin(), comp.fin_quads.end());
}

// The diagonal a quad is split along: hashed, like the arbitrary splits of a real scan.
bool SplitAlong02(uint64_t seed, uint64_t q) {
    return (Hash1(seed, 0xd1a9, q) & 1) == 0;
}

// The quad corners that form the diagonal of quad q.
void Diagonal(uint64_t seed, const uint64_t v[4], uint64_t q, uint64_t& d0, uint64_t& d1) {
    if (SplitAlong02(seed, q)) {
        d0 = v[0], d1 = v[2];
    } else {
        d0 = v[1], d1 = v[3];
    }
}

// A fin's free vertex: above the middle of the diagonal, half a diagonal length out.
template <typename Surface>
Vec3d FinVertex(const Component<Surface>& comp, uint64_t q) {
    uint64_t v[4], d0, d1;
    comp.surface.Quad(q, v);
    Diagonal(comp.seed, v, q, d0, d1);
    Vec3d p[4];
    for (int i = 0; i < 4; ++i)
        p[i] = comp.surface.Position(v[i]);
    Vec3d n = Cross(p[2] - p[0], p[3] - p[1]);
    double nl = std::sqrt(Dot(n, n));
    Vec3d a = comp.surface.Position(d0), b = comp.surface.Position(d1);
    Vec3d diag = b - a;
    double len = std::sqrt(Dot(diag, diag));
    if (nl > 0)
        n = n / nl;
    return (a + b) * 0.5 + n * (0.5 * len);
}

template <typename Surface>
void WriteVertices(Component<Surface>& comp, bool colors, PlyOut& out) {
    const Surface& s = comp.surface;
    const uint64_t n = s.VertexCount();
    // Noise dominates, so positions are computed in parallel a chunk at a time (each a
    // pure function of its index: the output does not depend on the thread count).
    constexpr uint64_t kChunk = 1 << 16;
    std::vector<Vec3d> pos(std::min(n, kChunk));
    std::vector<Rgb> rgb(colors ? pos.size() : 0);
    Rgb none;
    bool any_dups = comp.dups.any();
    for (uint64_t first = 0; first < n; first += kChunk) {
        uint64_t count = std::min(kChunk, n - first);
        mebake::ParallelForRange(
            0, int64_t(count),
            [&](int64_t lo, int64_t hi) {
                for (int64_t i = lo; i < hi; ++i) {
                    pos[size_t(i)] = s.Position(first + uint64_t(i));
                    if (colors)
                        rgb[size_t(i)] = s.Color(pos[size_t(i)]);
                }
            },
            4096);
        for (uint64_t i = 0; i < count; ++i) {
            Rgb c = colors ? rgb[i] : none;
            out.Vertex(pos[i], c);
            if (any_dups) {
                bool dup;
                comp.dups.Out(first + i, &dup);
                if (dup)
                    out.Vertex(pos[i], c);
            }
        }
    }
    static constexpr Rgb kFin{200, 40, 40};
    for (uint64_t q : comp.fin_quads)
        out.Vertex(FinVertex(comp, q), kFin);
}

template <typename Surface>
void WriteFaces(Component<Surface>& comp, PlyOut& out) {
    const Surface& s = comp.surface;
    uint64_t quads = s.QuadCount();
    size_t hole = 0, fin = 0;
    uint64_t fin_base = comp.vertex_base + comp.BaseVertices() + comp.dups.total();
    bool any_dups = comp.dups.any();
    uint64_t v[4], o[4];
    for (uint64_t q = 0; q < quads; ++q) {
        if (hole < comp.hole_quads.size() && comp.hole_quads[hole] == q) {
            ++hole;
            continue;
        }
        s.Quad(q, v);
        if (any_dups) {
            uint64_t pick = Hash1(comp.seed, 0xc0b1, q);
            for (int i = 0; i < 4; ++i) {
                bool dup;
                o[i] = comp.vertex_base + comp.dups.Out(v[i], &dup);
                if (dup && ((pick >> i) & 1))
                    ++o[i];
            }
        } else {
            for (int i = 0; i < 4; ++i)
                o[i] = comp.vertex_base + v[i];
        }
        bool along02 = SplitAlong02(comp.seed, q);
        if (along02) {
            out.Triangle(o[0], o[1], o[2]);
            out.Triangle(o[0], o[2], o[3]);
        } else {
            out.Triangle(o[0], o[1], o[3]);
            out.Triangle(o[1], o[2], o[3]);
        }
        if (fin < comp.fin_quads.size() && comp.fin_quads[fin] == q) {
            // The fin uses the same vertex copies as the quad's own triangles, so the
            // diagonal edge really has three faces.
            uint64_t d0 = along02 ? o[0] : o[1], d1 = along02 ? o[2] : o[3];
            out.Triangle(d0, d1, fin_base + fin);
            ++fin;
        }
    }
}

// Box dimensions a <= b, c near the cube side whose 4(ab+bc+ca) triangles come
// closest to `target`; ties go to the most cube-like box.
void SphereDims(uint64_t target, int64_t& a, int64_t& b, int64_t& c) {
    double s = std::sqrt(double(target) / 12.0);
    int64_t lo = std::max<int64_t>(1, int64_t(s * 0.7)), hi = int64_t(std::ceil(s * 1.4)) + 1;
    uint64_t best_err = ~uint64_t(0);
    double best_ratio = 1e300;
    for (int64_t i = lo; i <= hi; ++i) {
        for (int64_t j = i; j <= hi; ++j) {
            double cc = (double(target) / 4.0 - double(i * j)) / double(i + j);
            int64_t k = std::max<int64_t>(1, std::llround(cc));
            if (k < lo || k > hi)
                continue;
            uint64_t tris = 2 * BoxSphere::QuadsFor(i, j, k);
            uint64_t err = tris > target ? tris - target : target - tris;
            double ratio = double(std::max({i, j, k})) / double(std::min({i, j, k}));
            if (err < best_err || (err == best_err && ratio < best_ratio)) {
                best_err = err, best_ratio = ratio;
                a = i, b = j, c = k;
            }
        }
    }
}

// Grid w x h (w >= h) whose 2wh triangles come closest to `target`, squarest on ties.
void TerrainDims(uint64_t target, int64_t& w, int64_t& h) {
    double s = std::sqrt(double(target) / 2.0);
    int64_t lo = std::max<int64_t>(1, int64_t(s * 0.85)), hi = int64_t(std::ceil(s * 1.15)) + 1;
    uint64_t best_err = ~uint64_t(0);
    int64_t best_skew = INT64_MAX;
    for (int64_t i = lo; i <= hi; ++i) {
        int64_t j = std::max<int64_t>(1, std::llround(double(target) / 2.0 / double(i)));
        if (j > i)
            continue;
        uint64_t tris = uint64_t(2 * i * j);
        uint64_t err = tris > target ? tris - target : target - tris;
        if (err < best_err || (err == best_err && i - j < best_skew)) {
            best_err = err, best_skew = i - j;
            w = i, h = j;
        }
    }
}

// OutputStream writes a named file through a temporary renamed over it, which for a
// device or FIFO (-o /dev/null, a named pipe) would replace the device with a regular
// file. Such targets are opened in place and written as stdout instead.
std::unique_ptr<OutputStream> OpenOutput(const std::string& path) {
    struct stat st {};
    if (path != "-" && ::stat(path.c_str(), &st) == 0 && !S_ISREG(st.st_mode)) {
        if (S_ISDIR(st.st_mode))
            mebake::IoError({path}, "is a directory");
        int fd = ::open(path.c_str(), O_WRONLY | O_CLOEXEC);
        if (fd < 0)
            mebake::IoError({path}, "cannot open: {}", mebake::ErrnoString(errno));
        if (::dup2(fd, 1) < 0)
            mebake::IoError({path}, "dup2: {}", mebake::ErrnoString(errno));
        ::close(fd);
        return OutputStream::Open("-");
    }
    if (path == "-") {
        // A larger pipe buffer means fewer context switches with the reader (best effort;
        // Linux caps it at /proc/sys/fs/pipe-max-size).
        if (::fstat(1, &st) == 0 && S_ISFIFO(st.st_mode))
            ::fcntl(1, F_SETPIPE_SZ, 1 << 20);
    }
    return OutputStream::Open(path);
}

template <typename Surface>
int Generate(const Options& opt, std::vector<Component<Surface>>& comps,
             const std::string& command_line) {
    auto t0 = std::chrono::steady_clock::now();
    uint64_t vertices = 0, faces = 0, holes = 0, dups = 0, fins = 0;
    for (auto& c : comps) {
        c.vertex_base = vertices;
        vertices += c.Vertices();
        faces += c.Faces();
        holes += 2 * c.hole_quads.size();
        dups += c.dups.total();
        fins += c.fin_quads.size();
    }
    // PLY indices here are `int`.
    if (vertices > uint64_t(INT32_MAX) || faces > uint64_t(INT32_MAX))
        mebake::UsageError("{} vertices / {} faces exceed the int32 indices of this PLY layout",
                           vertices, faces);

    bool ascii = opt.format == "ply-ascii";
    if (opt.output == "-" && !ascii && ::isatty(1) == 1)
        mebake::UsageError("refusing to write binary PLY to a terminal; use -o FILE or a pipe");
    auto stream = OpenOutput(opt.output);
    PlyOut out(*stream, ascii, opt.colors);
    out.Header(vertices, faces,
               {"generated by " + command_line,
                "mkscan: synthetic scan-like mesh; no third-party content"});
    for (auto& c : comps) {
        WriteVertices(c, opt.colors, out);
        c.dups.Release();
    }
    for (auto& c : comps) {
        WriteFaces(c, out);
        c.dups.Release();
    }
    out.Finish();

    double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (!opt.quiet) {
        double off = 100.0 * (double(faces) - double(opt.triangles)) / double(opt.triangles);
        std::fprintf(stderr,
                     "mkscan: %s, %llu component(s): %llu triangles (target %llu, %+.3f%%), "
                     "%llu vertices; holes removed %llu triangles, %llu duplicated vertices, "
                     "%llu non-manifold fins; %.1f MB in %.2f s\n",
                     opt.shape.c_str(), (unsigned long long)comps.size(), (unsigned long long)faces,
                     (unsigned long long)opt.triangles, off, (unsigned long long)vertices,
                     (unsigned long long)holes, (unsigned long long)dups, (unsigned long long)fins,
                     double(stream->offset()) / 1e6, secs);
    }
    return 0;
}

// The share of `total` that component k of n gets (the first total % n get one more).
uint64_t Share(uint64_t total, uint64_t n, uint64_t k) {
    return total / n + (k < total % n ? 1 : 0);
}

int Run(const Options& opt, const std::string& command_line) {
    uint64_t n = opt.components;
    if (n == 0)
        mebake::UsageError("--components must be at least 1");
    uint64_t cols = uint64_t(std::ceil(std::sqrt(double(n))));
    if (opt.shape == "sphere") {
        double noise = opt.noise < 0 ? 0.12 : opt.noise;
        std::vector<Component<BoxSphere>> comps;
        comps.reserve(n);
        for (uint64_t k = 0; k < n; ++k) {
            uint64_t target = Share(opt.triangles, n, k);
            if (target < 12)
                mebake::UsageError("a sphere needs at least 12 triangles, got {}", target);
            int64_t a = 1, b = 1, c = 1;
            SphereDims(target, a, b, c);
            uint64_t seed = Hash(opt.seed, 0x5eed, k);
            Vec3d center{3.0 * double(k % cols), 3.0 * double(k / cols), 0.0};
            BoxSphere s(a, b, c, center, 1.0, noise, seed);
            comps.push_back(
                {s, seed, {}, {}, Duplicates(opt.duplicates, s.VertexCount(), seed), 0});
            PlanDefects(comps.back(), Share(opt.holes, n, k), Share(opt.nonmanifold, n, k));
        }
        return Generate(opt, comps, command_line);
    }
    double noise = opt.noise < 0 ? 0.15 : opt.noise;
    std::vector<Component<Terrain>> comps;
    comps.reserve(n);
    for (uint64_t k = 0; k < n; ++k) {
        uint64_t target = Share(opt.triangles, n, k);
        if (target < 2)
            mebake::UsageError("a terrain tile needs at least 2 triangles");
        int64_t w = 1, h = 1;
        TerrainDims(target, w, h);
        uint64_t seed = Hash(opt.seed, 0x5eed, k);
        // One noise field for all tiles (seeded by --seed), tiles 10% apart.
        Vec3d origin{1.1 * double(k % cols), 1.1 * double(k / cols), 0.0};
        Terrain t(w, h, origin, 1.0, noise, Hash(opt.seed, 0x7e44));
        comps.push_back({t, seed, {}, {}, Duplicates(opt.duplicates, t.VertexCount(), seed), 0});
        PlanDefects(comps.back(), Share(opt.holes, n, k), Share(opt.nonmanifold, n, k));
    }
    return Generate(opt, comps, command_line);
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{
        "mkscan - writes a synthetic scan-like mesh (binary PLY) of any size, deterministic\n"
        "from --seed, streamed in constant memory. Exact counts are reported on stderr."};
    Options opt;
    app.add_option("-n,--triangles", opt.triangles, "Target triangle count (met within ~1%)")
        ->required()
        ->check(CLI::Range(uint64_t(2), uint64_t(2000000000)));
    app.add_option("--shape", opt.shape,
                   "sphere: a noisy displaced cube-sphere; terrain: a height field")
        ->check(CLI::IsMember({"sphere", "terrain"}))
        ->capture_default_str();
    app.add_option("--seed", opt.seed, "Seed for every random choice")->capture_default_str();
    app.add_option("--noise", opt.noise,
                   "Displacement amplitude relative to the radius (sphere, default 0.12) or the "
                   "tile width (terrain, default 0.15); 0 gives a smooth shape")
        ->check(CLI::Range(0.0, 0.5));
    app.add_option("--holes", opt.holes, "Number of small holes (faces of disks removed)")
        ->check(CLI::Range(uint64_t(0), uint64_t(1000000)));
    app.add_option("--duplicates", opt.duplicates,
                   "Fraction of vertices written twice, faces using either copy")
        ->check(CLI::Range(0.0, 1.0));
    app.add_option("--nonmanifold", opt.nonmanifold,
                   "Number of extra faces on an existing edge (three faces on one edge)")
        ->check(CLI::Range(uint64_t(0), uint64_t(10000000)));
    app.add_option("--components", opt.components, "Separate spheres or terrain tiles")
        ->check(CLI::Range(uint64_t(1), uint64_t(10000)));
    app.add_flag("--colors", opt.colors, "Per-vertex colours (uchar red, green, blue)");
    app.add_option("--format", opt.format, "ply (binary little-endian) or ply-ascii")
        ->check(CLI::IsMember({"ply", "ply-ascii"}))
        ->capture_default_str();
    app.add_option("-o,--output", opt.output, "Output file, '-' for stdout")->capture_default_str();
    app.add_flag("-q,--quiet", opt.quiet, "No summary on stderr");
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        return app.exit(e) == 0 ? 0 : 2;
    }

    // The header records how the file was made, output path aside.
    std::string cmd = "mkscan --triangles " + std::to_string(opt.triangles) + " --shape " +
                      opt.shape + " --seed " + std::to_string(opt.seed);
    if (opt.noise >= 0)
        cmd += fmt::format(" --noise {}", opt.noise);
    if (opt.holes)
        cmd += " --holes " + std::to_string(opt.holes);
    if (opt.duplicates > 0)
        cmd += fmt::format(" --duplicates {}", opt.duplicates);
    if (opt.nonmanifold)
        cmd += " --nonmanifold " + std::to_string(opt.nonmanifold);
    if (opt.components != 1)
        cmd += " --components " + std::to_string(opt.components);
    if (opt.colors)
        cmd += " --colors";
    if (opt.format != "ply")
        cmd += " --format " + opt.format;

    try {
        return Run(opt, cmd);
    } catch (const mebake::Error& e) {
        std::fprintf(stderr, "mkscan: error: %s\n", e.what());
        return e.kind() == mebake::ErrorKind::Usage ? 2 : 1;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "mkscan: error: %s\n", e.what());
        return 1;
    }
}
