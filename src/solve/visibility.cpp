// Embree 3 wrapper: scene building, batched occlusion and closest-hit queries, error and
// memory reporting. See visibility.h for what it guarantees.
#include "solve/visibility.h"

#include "core/check.h"
#include "core/error.h"
#include "core/parallel.h"
#include "solve/paged_visibility.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <type_traits>
#include <xmmintrin.h>

namespace mebake::solve {
namespace {

std::atomic<int64_t> g_bytes{0};
std::atomic<int64_t> g_peak{0};
std::atomic<int64_t> g_limit{0};
// Embree reports errors on the thread that made the API call; keep the text per thread.
thread_local std::string t_last_error;

const char* ErrorName(RTCError e) {
    switch (e) {
    case RTC_ERROR_NONE:
        return "no error";
    case RTC_ERROR_UNKNOWN:
        return "unknown error";
    case RTC_ERROR_INVALID_ARGUMENT:
        return "invalid argument";
    case RTC_ERROR_INVALID_OPERATION:
        return "invalid operation";
    case RTC_ERROR_OUT_OF_MEMORY:
        return "out of memory";
    case RTC_ERROR_UNSUPPORTED_CPU:
        return "unsupported CPU";
    case RTC_ERROR_CANCELLED:
        return "cancelled";
    }
    return "unrecognized error";
}

bool MemoryMonitor(void*, ssize_t bytes, bool post) {
    if (bytes <= 0) {
        g_bytes.fetch_add(bytes, std::memory_order_relaxed);
        return true;
    }
    const int64_t now = g_bytes.fetch_add(bytes, std::memory_order_relaxed) + bytes;
    const int64_t limit = g_limit.load(std::memory_order_relaxed);
    if (limit > 0 && now > limit) {
        // Cancelled before the allocation: it never happens, so do not count it. After the
        // allocation: it did happen and will be freed (and reported) later.
        if (!post)
            g_bytes.fetch_sub(bytes, std::memory_order_relaxed);
        return false;
    }
    int64_t peak = g_peak.load(std::memory_order_relaxed);
    while (now > peak && !g_peak.compare_exchange_weak(peak, now, std::memory_order_relaxed)) {
    }
    return true;
}

void ErrorCallback(void*, RTCError code, const char* str) {
    t_last_error = fmt::format("{} ({})", str ? str : "", ErrorName(code));
}

struct Device {
    RTCDevice device = nullptr;
    Device() {
        device = rtcNewDevice(nullptr);
        if (!device)
            throw Error(ErrorKind::Io, fmt::format("Embree: cannot create a device: {}",
                                                   ErrorName(rtcGetDeviceError(nullptr))));
        rtcSetDeviceErrorFunction(device, ErrorCallback, nullptr);
        rtcSetDeviceMemoryMonitorFunction(device, MemoryMonitor, nullptr);
    }
    ~Device() { rtcReleaseDevice(device); }
};

RTCDevice GetDevice() {
    static Device device;
    return device.device;
}

void ThrowIfError(const char* what) {
    const RTCError e = rtcGetDeviceError(GetDevice());
    if (e == RTC_ERROR_NONE)
        return;
    std::string msg = t_last_error.empty() ? ErrorName(e) : t_last_error;
    t_last_error.clear();
    if (e == RTC_ERROR_OUT_OF_MEMORY && g_limit.load() > 0)
        msg += fmt::format(" [Embree memory limit {} bytes, min(128 MiB, --memory / 2): the "
                           "visibility mesh is paged in pieces under it (paged_visibility.h); "
                           "a larger --memory leaves more room]",
                           g_limit.load());
    throw Error(ErrorKind::Io, fmt::format("Embree: {} failed: {}", what, msg));
}

// Flush-to-zero and denormals-are-zero for the scope (Embree's traversal is slow on
// denormals), restoring the caller's MXCSR so other float code is unaffected.
class FlushDenormals {
public:
    FlushDenormals() : saved_(_mm_getcsr()) { _mm_setcsr(saved_ | 0x8040u); }
    ~FlushDenormals() { _mm_setcsr(saved_); }
    FlushDenormals(const FlushDenormals&) = delete;
    FlushDenormals& operator=(const FlushDenormals&) = delete;

private:
    unsigned saved_;
};

RTCBuildQuality ToEmbree(BuildQuality q) {
    switch (q) {
    case BuildQuality::kLow:
        return RTC_BUILD_QUALITY_LOW;
    case BuildQuality::kMedium:
        return RTC_BUILD_QUALITY_MEDIUM;
    case BuildQuality::kHigh:
        return RTC_BUILD_QUALITY_HIGH;
    }
    return RTC_BUILD_QUALITY_MEDIUM;
}

// The coherent hint is passed to the stream API only: with Embree 3.13.5 (Debian build, AVX-512)
// rtcOccluded16 with RTC_INTERSECT_CONTEXT_FLAG_COHERENT on a robust scene never returns for
// some bundles of segments (seen on a 180K-triangle height field); see visibility_test.
RTCIntersectContextFlags ContextFlags(const VisibilityOptions& o) {
    return o.coherent && o.method == TraceMethod::kStream ? RTC_INTERSECT_CONTEXT_FLAG_COHERENT
                                                          : RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT;
}

constexpr float kNegInf = -std::numeric_limits<float>::infinity();
constexpr size_t kChunk = 256;  // rays per stream call (on the stack: 256 * 48 bytes)

inline void FillRay(const Segment& s, RTCRay* r, unsigned id = 0) {
    r->org_x = s.ox;
    r->org_y = s.oy;
    r->org_z = s.oz;
    r->tnear = s.tnear;
    r->dir_x = s.dx;
    r->dir_y = s.dy;
    r->dir_z = s.dz;
    r->time = 0;
    r->tfar = s.tfar;
    r->mask = 0xFFFFFFFFu;  // masks are compiled in; mask 0 would miss everything
    r->id = id;  // the ray's slot in TieContext
    r->flags = 0;
}

inline void InitHit(RTCHit* h) {
    h->geomID = RTC_INVALID_GEOMETRY_ID;
    h->primID = RTC_INVALID_GEOMETRY_ID;
    h->instID[0] = RTC_INVALID_GEOMETRY_ID;
}

inline Hit ToHit(const RTCRayHit& rh) {
    Hit h;
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID)
        return h;
    h.t = rh.ray.tfar;
    h.u = rh.hit.u;
    h.v = rh.hit.v;
    h.ng_x = rh.hit.Ng_x;
    h.ng_y = rh.hit.Ng_y;
    h.ng_z = rh.hit.Ng_z;
    h.geom_id = rh.hit.geomID;
    h.prim_id = rh.hit.primID;
    return h;
}

// Closest hits with a fixed rule at equal distance: Embree commits every candidate hit
// with t <= the ray's tfar, so where two triangles meet a ray at the same t (a shared edge
// or vertex, as the direct light's rays along the normal often do) the one its traversal
// met last would win, and that depends on the BVH, so on the scene's other triangles: a
// paged piece's scene and the whole scene answered differently (the 16M sphere's solution
// differed in 10K bytes, session 10). The geometries' intersect filter (LowestAtTies)
// keeps, per ray, the lowest rank among the triangles at the least t: (geometry,
// primitive) in a whole scene, the caller's global triangle ids in a paged piece.
struct TieContext {
    RTCIntersectContext ctx;       // first: the filter gets its address
    const uint32_t* rank = nullptr;  // per primitive of geometry 0, or null: (geom, prim)
    float t[kChunk];               // per ray id: the hit kept so far
    uint64_t key[kChunk];
    void Reset(size_t n) {
        std::fill(t, t + n, std::numeric_limits<float>::infinity());
        std::fill(key, key + n, ~uint64_t(0));
    }
};
static_assert(std::is_standard_layout_v<TieContext>);

void LowestAtTies(const RTCFilterFunctionNArguments* a) {
    auto* c = reinterpret_cast<TieContext*>(a->context);
    for (unsigned i = 0; i < a->N; ++i) {
        if (a->valid[i] == 0)
            continue;
        const unsigned id = RTCRayN_id(a->ray, a->N, i);
        const float t = RTCRayN_tfar(a->ray, a->N, i);  // the candidate's distance
        const unsigned geom = RTCHitN_geomID(a->hit, a->N, i);
        const unsigned prim = RTCHitN_primID(a->hit, a->N, i);
        const uint64_t key = c->rank ? c->rank[prim] : uint64_t(geom) << 32 | prim;
        if (t == c->t[id] && key > c->key[id]) {
            a->valid[i] = 0;  // a lower-ranked triangle at the same distance stays
            continue;
        }
        c->t[id] = t;  // t <= the kept hit's (Embree's range test)
        c->key[id] = key;
    }
}

// Packets: RTCRayN / RTCRayHitN of width W, filled lane by lane.
template <int W>
struct Packet;
template <>
struct Packet<16> {
    using Ray = RTCRay16;
    using RayHit = RTCRayHit16;
    static void Occluded(const int* valid, RTCScene s, RTCIntersectContext* c, Ray* r) {
        rtcOccluded16(valid, s, c, r);
    }
    static void Intersect(const int* valid, RTCScene s, RTCIntersectContext* c, RayHit* r) {
        rtcIntersect16(valid, s, c, r);
    }
};
template <>
struct Packet<8> {
    using Ray = RTCRay8;
    using RayHit = RTCRayHit8;
    static void Occluded(const int* valid, RTCScene s, RTCIntersectContext* c, Ray* r) {
        rtcOccluded8(valid, s, c, r);
    }
    static void Intersect(const int* valid, RTCScene s, RTCIntersectContext* c, RayHit* r) {
        rtcIntersect8(valid, s, c, r);
    }
};

template <typename R>
inline void FillLane(const Segment& s, int i, R* r) {
    r->org_x[i] = s.ox;
    r->org_y[i] = s.oy;
    r->org_z[i] = s.oz;
    r->tnear[i] = s.tnear;
    r->dir_x[i] = s.dx;
    r->dir_y[i] = s.dy;
    r->dir_z[i] = s.dz;
    r->time[i] = 0;
    r->tfar[i] = s.tfar;
    r->mask[i] = 0xFFFFFFFFu;
    r->id[i] = unsigned(i);
    r->flags[i] = 0;
}

template <int W>
void OccludedPackets(RTCScene scene, RTCIntersectContext* ctx, std::span<const Segment> seg,
                     std::span<uint8_t> out) {
    alignas(64) typename Packet<W>::Ray ray;
    alignas(64) int valid[W];
    for (size_t base = 0; base < seg.size(); base += W) {
        const int n = int(std::min<size_t>(W, seg.size() - base));
        for (int i = 0; i < W; ++i) {
            valid[i] = i < n ? -1 : 0;
            // Inactive lanes still get a well-formed (empty) ray.
            FillLane(i < n ? seg[base + i] : Segment{}, i, &ray);
        }
        Packet<W>::Occluded(valid, scene, ctx, &ray);
        for (int i = 0; i < n; ++i)
            out[base + i] = ray.tfar[i] == kNegInf;
    }
}

template <int W>
void IntersectPackets(RTCScene scene, TieContext* ctx, std::span<const Segment> seg,
                      std::span<Hit> out) {
    alignas(64) typename Packet<W>::RayHit rh;
    alignas(64) int valid[W];
    for (size_t base = 0; base < seg.size(); base += W) {
        const int n = int(std::min<size_t>(W, seg.size() - base));
        for (int i = 0; i < W; ++i) {
            valid[i] = i < n ? -1 : 0;
            FillLane(i < n ? seg[base + i] : Segment{}, i, &rh.ray);
            rh.hit.geomID[i] = RTC_INVALID_GEOMETRY_ID;
            rh.hit.primID[i] = RTC_INVALID_GEOMETRY_ID;
            rh.hit.instID[0][i] = RTC_INVALID_GEOMETRY_ID;
        }
        ctx->Reset(W);
        Packet<W>::Intersect(valid, scene, &ctx->ctx, &rh);
        for (int i = 0; i < n; ++i) {
            Hit& h = out[base + i];
            h = Hit{};
            if (rh.hit.geomID[i] == RTC_INVALID_GEOMETRY_ID)
                continue;
            h.t = rh.ray.tfar[i];
            h.u = rh.hit.u[i];
            h.v = rh.hit.v[i];
            h.ng_x = rh.hit.Ng_x[i];
            h.ng_y = rh.hit.Ng_y[i];
            h.ng_z = rh.hit.Ng_z[i];
            h.geom_id = rh.hit.geomID[i];
            h.prim_id = rh.hit.primID[i];
        }
    }
}

}  // namespace

struct VisibilityScene::Impl {
    RTCScene scene = nullptr;
    ~Impl() {
        if (scene)
            rtcReleaseScene(scene);
    }
};

VisibilityScene::VisibilityScene(const VisibilityOptions& options)
    : impl_(std::make_unique<Impl>()), options_(options) {
    RTCDevice device = GetDevice();
    impl_->scene = rtcNewScene(device);
    if (!impl_->scene)
        ThrowIfError("rtcNewScene");
    int flags = RTC_SCENE_FLAG_NONE;
    if (options.compact)
        flags |= RTC_SCENE_FLAG_COMPACT;
    if (options.robust)
        flags |= RTC_SCENE_FLAG_ROBUST;
    rtcSetSceneFlags(impl_->scene, RTCSceneFlags(flags));
    rtcSetSceneBuildQuality(impl_->scene, ToEmbree(options.quality));
    ThrowIfError("creating the scene");
}

VisibilityScene::~VisibilityScene() = default;

namespace {
// Throws InputError unless indices form triangles over nv vertices within 32-bit ranges.
void ValidateMesh(size_t nv, std::span<const uint32_t> indices, const char* name) {
    const FileLoc loc{name};
    if (indices.size() % 3 != 0)
        InputError(loc, "{} triangle indices is not a multiple of 3", indices.size());
    const size_t nt = indices.size() / 3;
    if (nv > 0xFFFFFFFEu || nt > 0xFFFFFFFEu)
        InputError(loc, "{} vertices / {} triangles exceed one geometry's 32-bit range", nv, nt);
    for (size_t i = 0; i < indices.size(); ++i) {
        if (indices[i] >= nv)
            InputError(loc, "triangle {} uses vertex {} of {}", i / 3, indices[i], nv);
    }
}
}  // namespace

uint32_t VisibilityScene::AddTriangles(std::span<const float> positions,
                                       std::span<const uint32_t> indices, const char* name) {
    CHECK(!committed_);
    if (positions.size() % 3 != 0)
        InputError(FileLoc{name}, "{} position floats is not a multiple of 3", positions.size());
    const size_t nv = positions.size() / 3, nt = indices.size() / 3;
    ValidateMesh(nv, indices, name);
    const uint32_t id = geometries_++;
    if (paged_) {
        paged_->Add(positions, indices);
        triangles_ += nt;
        return id;
    }
    if (nt == 0)
        return id;  // nothing to trace; the id stays reserved

    RTCGeometry geom = rtcNewGeometry(GetDevice(), RTC_GEOMETRY_TYPE_TRIANGLE);
    ThrowIfError("rtcNewGeometry");
    rtcSetGeometryBuildQuality(geom, ToEmbree(options_.quality));
    // Embree-owned buffers are padded for its vector loads past the last vertex.
    auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(
        geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), nv));
    auto* t = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(
        geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(uint32_t), nt));
    if (!v || !t) {
        rtcReleaseGeometry(geom);
        ThrowIfError("allocating geometry buffers");
        throw Error(ErrorKind::Io, "Embree: allocating geometry buffers failed");
    }
    std::memcpy(v, positions.data(), positions.size_bytes());
    std::memcpy(t, indices.data(), indices.size_bytes());
    rtcSetGeometryIntersectFilterFunction(geom, LowestAtTies);
    rtcCommitGeometry(geom);
    rtcAttachGeometryByID(impl_->scene, geom, id);
    rtcReleaseGeometry(geom);  // the scene holds it now
    ThrowIfError("adding a triangle mesh");
    triangles_ += nt;
    return id;
}

uint32_t VisibilityScene::AddTrianglesShared(std::span<const float> positions, size_t vertex_count,
                                             std::span<const uint32_t> indices, const char* name) {
    CHECK(!committed_);
    // Embree reads the last vertex with a 16-byte load: one spare float past it.
    if (positions.size() < 3 * vertex_count + 1)
        InputError(FileLoc{name}, "{} position floats for {} vertices: need 3 per vertex + 1 spare",
                   positions.size(), vertex_count);
    ValidateMesh(vertex_count, indices, name);
    const size_t nt = indices.size() / 3;
    const uint32_t id = geometries_++;
    if (paged_) {  // the pieces copy what they keep
        paged_->Add(positions.first(3 * vertex_count), indices);
        triangles_ += nt;
        return id;
    }
    if (nt == 0)
        return id;

    RTCGeometry geom = rtcNewGeometry(GetDevice(), RTC_GEOMETRY_TYPE_TRIANGLE);
    ThrowIfError("rtcNewGeometry");
    rtcSetGeometryBuildQuality(geom, ToEmbree(options_.quality));
    rtcSetSharedGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, positions.data(),
                               0, 3 * sizeof(float), vertex_count);
    rtcSetSharedGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, indices.data(), 0,
                               3 * sizeof(uint32_t), nt);
    rtcSetGeometryIntersectFilterFunction(geom, LowestAtTies);
    rtcCommitGeometry(geom);
    rtcAttachGeometryByID(impl_->scene, geom, id);
    rtcReleaseGeometry(geom);
    ThrowIfError("adding a shared triangle mesh");
    triangles_ += nt;
    return id;
}

void VisibilityScene::EnablePaging(const PagingOptions& paging) {
    CHECK(!committed_ && geometries_ == 0);
    paged_ = std::make_unique<PagedVisibility>(options_, paging);
}

void VisibilityScene::Commit() {
    CHECK(!committed_);
    if (paged_) {
        paged_->Commit();
        committed_ = true;
        return;
    }
    rtcCommitScene(impl_->scene);
    ThrowIfError("building the BVH (rtcCommitScene)");
    committed_ = true;
}

void VisibilityScene::Occluded(std::span<const Segment> segments,
                               std::span<uint8_t> occluded) const {
    CHECK(committed_);
    CHECK_EQ(segments.size(), occluded.size());
    if (paged_)
        return paged_->Occluded(segments, occluded);
    FlushDenormals ftz;
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    ctx.flags = ContextFlags(options_);
    RTCScene scene = impl_->scene;
    switch (options_.method) {
    case TraceMethod::kStream: {
        RTCRay rays[kChunk];
        for (size_t base = 0; base < segments.size(); base += kChunk) {
            const size_t n = std::min(kChunk, segments.size() - base);
            for (size_t i = 0; i < n; ++i)
                FillRay(segments[base + i], &rays[i]);
            rtcOccluded1M(scene, &ctx, rays, unsigned(n), sizeof(RTCRay));
            for (size_t i = 0; i < n; ++i)
                occluded[base + i] = rays[i].tfar == kNegInf;
        }
        break;
    }
    case TraceMethod::kPacket16:
        OccludedPackets<16>(scene, &ctx, segments, occluded);
        break;
    case TraceMethod::kPacket8:
        OccludedPackets<8>(scene, &ctx, segments, occluded);
        break;
    case TraceMethod::kSingle: {
        RTCRay ray;
        for (size_t i = 0; i < segments.size(); ++i) {
            FillRay(segments[i], &ray);
            rtcOccluded1(scene, &ctx, &ray);
            occluded[i] = ray.tfar == kNegInf;
        }
        break;
    }
    }
}

void VisibilityScene::OccludedParallel(std::span<const Segment> segments,
                                       std::span<uint8_t> occluded) const {
    CHECK_EQ(segments.size(), occluded.size());
    constexpr int64_t kBlock = 1024;
    const int64_t blocks = (int64_t(segments.size()) + kBlock - 1) / kBlock;
    ParallelFor(0, blocks, [&](int64_t b) {
        const size_t lo = size_t(b * kBlock);
        const size_t n = std::min<size_t>(kBlock, segments.size() - lo);
        Occluded(segments.subspan(lo, n), occluded.subspan(lo, n));
    });
}

void VisibilityScene::Intersect(std::span<const Segment> segments, std::span<Hit> hits) const {
    CHECK(committed_);
    CHECK_EQ(segments.size(), hits.size());
    if (paged_)
        return paged_->Intersect(segments, hits);
    IntersectRanked(segments, hits, {});
}

void VisibilityScene::IntersectRanked(std::span<const Segment> segments, std::span<Hit> hits,
                                      std::span<const uint32_t> rank) const {
    CHECK(committed_ && !paged_);
    CHECK_EQ(segments.size(), hits.size());
    CHECK(rank.empty() || (geometries_ == 1 && rank.size() == triangles_));
    FlushDenormals ftz;
    TieContext tc;
    rtcInitIntersectContext(&tc.ctx);
    tc.ctx.flags = ContextFlags(options_);
    tc.rank = rank.empty() ? nullptr : rank.data();
    RTCScene scene = impl_->scene;
    switch (options_.method) {
    case TraceMethod::kStream: {
        RTCRayHit rays[kChunk];
        for (size_t base = 0; base < segments.size(); base += kChunk) {
            const size_t n = std::min(kChunk, segments.size() - base);
            for (size_t i = 0; i < n; ++i) {
                FillRay(segments[base + i], &rays[i].ray, unsigned(i));
                InitHit(&rays[i].hit);
            }
            tc.Reset(n);
            rtcIntersect1M(scene, &tc.ctx, rays, unsigned(n), sizeof(RTCRayHit));
            for (size_t i = 0; i < n; ++i)
                hits[base + i] = ToHit(rays[i]);
        }
        break;
    }
    case TraceMethod::kPacket16:
        IntersectPackets<16>(scene, &tc, segments, hits);
        break;
    case TraceMethod::kPacket8:
        IntersectPackets<8>(scene, &tc, segments, hits);
        break;
    case TraceMethod::kSingle: {
        RTCRayHit rh;
        for (size_t i = 0; i < segments.size(); ++i) {
            FillRay(segments[i], &rh.ray);
            InitHit(&rh.hit);
            tc.Reset(1);
            rtcIntersect1(scene, &tc.ctx, &rh);
            hits[i] = ToHit(rh);
        }
        break;
    }
    }
}

int64_t EmbreeMemoryBytes() {
    return g_bytes.load();
}
int64_t EmbreePeakMemoryBytes() {
    return g_peak.load();
}
void SetEmbreeMemoryLimit(int64_t bytes) {
    g_limit.store(std::max<int64_t>(bytes, 0));
}

EmbreeMemoryCap::EmbreeMemoryCap(uint64_t bytes) : previous_(g_limit.load()) {
    SetEmbreeMemoryLimit(int64_t(bytes));
}
EmbreeMemoryCap::~EmbreeMemoryCap() {
    SetEmbreeMemoryLimit(previous_);
}

}  // namespace mebake::solve
