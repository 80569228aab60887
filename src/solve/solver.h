// The Master-Element solver (seed 000 sections 2-4; docs/method.md).
//
//  1. Direct pass: per chart, an adaptive quadtree is refined from the root until the
//     polynomial fitted at the Gauss points (collocation) matches the direct light at a
//     grid of control points within the tolerance; depth is capped by the texel size.
//  2. Southwell shooting in deterministic batches: the charts whose unshot power
//     (integral of rho (n . dE)+ over their real part) is within a factor of the largest
//     shoot together; every receiver chart gathers their unshot radiosity at the
//     coarsest quadtree level that meets the size/distance bound (the suitable scale),
//     from emitter samples at a level chosen the same way, with one visibility ray per
//     point pair, then pushes the gathered coefficients to its leaves.
//  3. Stops when the unshot power falls below a fraction of the first shot's power, or
//     at the bounce or time limit.
// Each batch is a task graph (shoot_graph.cpp): receivers gather in parallel, each writing
// only its own field, in a fixed order: the result is bit-identical for any thread count.
// Refined fields live in a memory-mapped pool (field_pool.h) when one is set.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "solve/cluster_tree.h"
#include "solve/direct.h"
#include "solve/field.h"
#include "solve/scene.h"
#include "solve/transfer.h"
#include "solve/geometry_cache.h"

namespace mebake::solve {

class FieldPool;
class VisibilityScene;
struct SegmentBatch;

struct SolveChart {
    GeometryPyramid geometry;  // hold geometry.Pin() while reading it
    double scale = 1;   // 3D length of the unit square's side
    int max_level = -1; // quadtree depth cap (the light-map texel); -1: the geometry's finest
    // Finest emitter samples at least this deep (the tile's emitter_resolution: a merged
    // chart keeps its parts' sample size); -1: the solver's own rule (Solver::EmitterTop).
    int emitter_level = -1;
};

struct SolveOptions {
    SolverSettings settings;
    float ray_offset = 1e-4f;       // absolute; callers add the proxy's deviation
    float scene_size = 1;           // bounding-box diagonal
    int min_level = 2;              // quadtrees start this deep
    int sky_level = 4;              // the sky is gathered from this level down (GatherSky)
    // Refinement budget of a chart of up to 128 x 128 light-map texels; a larger chart's
    // grows with its texels (Solver::NodeBudget).
    size_t max_nodes_per_chart = 8192;
    double receiver_tau = 0.5;      // gather at a node when its size / distance < tau
    double emitter_tau = 0.5;       // emitter sample size / distance
    int max_emitter_level = 5;      // finest emitter samples (32 x 32 per chart)
    // Error-driven link refinement (link_refine.h): a link also stops when its irradiance
    // bound is within link_tolerance x tolerance x 2^-batch x the receiver node's
    // irradiance (at least link_floor x the reference irradiance); 0 turns it off.
    double link_tolerance = 1;
    double link_floor = 0.02;
    double batch_fraction = 0.05;   // shoot charts with power >= this x the largest
    size_t emitter_group = 64;      // shooters built and gathered together (memory)
    bool shoot_emission = true;     // emissive materials shoot their emission in batch 0
                                    // (false when they are handled as polygon lights)
    // Cluster links (cluster_links.cpp): a shooter reaches a far group of receiver charts
    // through one link whose visibility is estimated from max(cluster_rays,
    // cluster_rays_per_chart x its charts) rays; partial visibility is refined unless the
    // link's irradiance bound is below cluster_tolerance x tolerance x the reference.
    bool cluster_links = true;
    int cluster_rays = 16;
    int cluster_rays_per_chart = 2;
    double cluster_tau = 1;         // a cluster links when its radius / distance <= this
    double cluster_tolerance = 0.01;
    // Chart-level links trace this many stratified pairs first (at most half of their
    // pairs) and the rest only when those disagree (0: one ray per pair always).
    int link_probes = 8;
    // A link about to be split probes its visibility the same way first, and a subtree
    // whose probes agree takes their answer without rays (Gatherer::SplitVisibility).
    bool split_probes = true;
    // A gather's link rays wait until this many (point, texel) pairs gather, then go to the
    // visibility together (Gatherer::Resolve; 1: link by link). The same bytes for any value.
    size_t link_defer_pairs = size_t(1) << 14;
    // --multi-emitter simplify: write each chart's classification and refinement as
    // DIR/chart-N.png here (multi_emitter_debug.h); empty: none.
    std::string multi_emitter_debug;
};

struct SolveStats {
    int batches = 0;
    uint64_t shots = 0;             // chart shots
    uint64_t rays = 0;
    std::vector<uint64_t> rays_by_kind;  // indexed by RayKind (rays.h)
    double seconds_direct = 0, seconds_indirect = 0;
    double emitted_power = 0;       // first-shot power (direct light reflected + emission)
    double unshot_power = 0;        // left when it stopped
    double shot_power = 0;          // shot by the last batch (its shooters' unshot power)
    // Per chart (the unshot tail's state, checkpointed): the unshot power the last batch
    // did not shoot (0 where it shot), and the power received by the batch before it.
    std::vector<double> chart_kept, chart_received;
    double tail_gain = 0;           // mean r / (1 - r) of AddUnshotTail(), 0 when not added
    uint64_t cluster_links = 0;     // (shooter, cluster) links accepted
    uint64_t opened_links = 0;      // (shooter, chart) pairs left to chart-level links
    std::vector<uint64_t> nodes_per_level;
    uint64_t leaves = 0;
    size_t field_bytes = 0;
    std::string stop_reason;
};

class Solver {
public:
    Solver(const Scene& scene, const std::vector<SolveChart>& charts, const VisibilityScene& vis,
           SolveOptions opt);

    // Progress, called from worker threads: during the direct pass (batch -1) `done` counts
    // the charts refined; at the start of a batch (done 0) and after each receiver's gather
    // it counts the receiver gathers of that batch (total: charts x emitter groups).
    struct ProgressInfo {
        int batch = -1;
        uint64_t done = 0, total = 0;
        double unshot = 1;  // unshot power / first-shot power at the batch's start
        uint64_t rays = 0;  // so far in this run (0 from worker threads)
    };
    using Progress = std::function<void(const ProgressInfo&)>;
    void Run(const Progress& progress = {});

    // Checkpoints (checkpoint.h). At every batch boundary (after the direct pass and after
    // each batch) Run() calls the hook with the index of the next batch; returning false
    // stops the run there with stop_reason "interrupted". The state at a boundary is
    // fields() (pending all zero), reference(), next_batch() and stats(); Restore() puts
    // it back, and Run() then skips the direct pass and continues with the same batches
    // an uninterrupted run would shoot.
    using BatchHook = std::function<bool(int next_batch)>;
    void SetBatchHook(BatchHook hook) { batch_hook_ = std::move(hook); }
    // Once *stop is set the direct pass skips its remaining charts and Run() returns
    // "interrupted" with nothing resumable (a signal handler sets it).
    void SetStopFlag(const std::atomic<bool>* stop) { stop_ = stop; }
    void Restore(std::vector<ChartField> fields, double reference, int next_batch,
                 const SolveStats& stats);
    // The same a chart at a time (one field in memory at once with a pool): every chart's
    // RestoreField(), then Restore() of the rest.
    void RestoreField(uint32_t chart, ChartField field);
    void Restore(double reference, int next_batch, const SolveStats& stats);
    // Keeps the fields in `pool` (field_pool.h) once refined (or restored): set before
    // Run() and Restore(). Without one they stay in memory; the results are the same.
    void SetFieldPool(FieldPool* pool) { pool_ = pool; }
    double reference() const { return reference_; }
    int next_batch() const { return next_batch_; }  // -1 before the direct pass is done

    // Hold a field's Pin() while reading it (pooled fields are mapped).
    const std::vector<ChartField>& fields() const { return fields_; }
    std::vector<ChartField>& mutable_fields() { return fields_; }
    const SolveStats& stats() const { return stats_; }
    bool radiosity() const { return opt_.settings.radiosity; }

    // Albedo (linear RGB) of a surface sample, from its material and vertex colour.
    Vec3f Albedo(uint32_t material, const Vec3f& color) const;


private:
    // A shooter's unshot radiosity sampled on its geometry pyramid.
    struct Emitter {
        struct Texel {
            Vec3f pos, nrm, vis;
            float area = 0;
            float radius = 0;
            Vec3f db;          // unshot radiosity (area-weighted mean over the texel)
            float db_max = 0;  // largest luminance of db within the texel
            float cone = 0;    // every sampled normal within lies within this angle of nrm
            // Its real points lie within `relief` of the plane through vis with normal nrm
            // (ReliefOf; the finest geometry texels taken as flat): the slab where a link
            // ray's end may meet only the sample's own surface (AddSegmentBetween).
            float relief = 0;
            Vec3f hull;        // a tight sphere around the texel's real points and samples
            float hull_radius = 0;
            FacetSpread spread;  // of its facets (transfer.h): its children, or `facets`
        };
        uint32_t chart = 0;
        std::vector<std::vector<Texel>> levels;  // levels[l]: (2^l)^2 texels
        // The finest texels' facets (transfer.h, FacetedTransfer): the geometry one level
        // finer, 4 per texel in quadrant order; empty when the samples are the finest level.
        struct Facet {
            Vec3f pos, nrm, vis;
            float area = 0;
        };
        std::vector<Facet> facets;
        // The finest samples' children (SolverSettings::near_emitter_split), row of 2^(top+1),
        // built as the finest samples are (BuildEmitter's sample_level; no cone or spread);
        // empty when off or when the finest samples are the finest geometry.
        std::vector<Texel> near;
        // The four facets of sample (i, j) of level l, in quadrant order: its children at
        // level l + 1, or at the finest level `facets` (which must not be empty there).
        void FacetsOf(int l, uint32_t i, uint32_t j, TexelSource f[4], Vec3f vis[4]) const;
        Vec3f center;
        float radius = 0;
        double scale = 1;
    };
    // Where a receiver chart gets one shooter's light from (cluster_links.cpp): kOpenLink
    // for the chart-level link refinement (Gatherer::Shoot), otherwise the visibility in
    // [0, 1] of a cluster link evaluated at the chart's root without rays.
    static constexpr float kOpenLink = -1;
    // Charts up to 2^kBudgetLevel texels a side get max_nodes_per_chart nodes (NodeBudget).
    static constexpr int kBudgetLevel = 7;
    struct ClusterSample {
        Vec3f pos, nrm, org;  // org: the ray origin, off the surface
    };
    class DirectSampler;  // refine_direct.cpp
    class BounceRefiner;  // refine_indirect.cpp
    class Gatherer;
    void BuildClusters();
    void LinkClusters(const Emitter& em, std::vector<float>* links, uint64_t* accepted,
                      uint64_t* opened) const;
    float ClusterVisibility(const ClusterTree::Node& node, const Emitter& em,
                            SegmentBatch* batch, bool* valid) const;
    double ReceiverTau() const;
    double LinkToleranceScale() const;  // link_refine.h: the allowance per unit irradiance
    double ReferenceIrradiance() const;
    // Returns the charts shot; *shot_power: their unshot power summed; kept[c]: chart c's
    // unshot power when it does not shoot, else 0.
    size_t ShootBatch(const std::vector<double>& power, double largest, bool first,
                      const std::vector<uint8_t>& lagging, double* shot_power,
                      std::vector<double>* kept);
    // At the stop, the bounces not shot (SolverSettings::unshot_tail), from the power each
    // chart received in the last two batches; returns the mean gain added (0: none).
    double AddUnshotTail(const std::vector<double>& received);
    void CountNodes();
    void StoreField(uint32_t chart);  // into pool_, when there is one
    void RefineDirect(uint32_t chart);
    struct SimplifiedFit;  // refine_direct.cpp (--multi-emitter simplify)
    void FitDirectLights(uint32_t chart, DirectSampler& sampler, int min_level, int max_level,
                         SimplifiedFit* simplified);
    float SimplifiedNode(const QuadNode& node, bool control, DirectSampler& sampler,
                         SimplifiedFit& sf, std::vector<float>& coeffs);
    void GatherSky(uint32_t chart, DirectLight& direct, int sky_level, int max_level);
    // refine_indirect.cpp: leaves split for the first bounce before the gather starts.
    void RefineForBounces(uint32_t chart, int max_level);
    void BuildEmitter(uint32_t chart, bool first_shot, Emitter* e) const;
    // The radiosity of sample (i, j) of an n x n level whose geometry texel is g (area > 0):
    // of the unshot field or of the whole field so far, with the chart's emission when
    // `emission` (an emitter's first shot).
    Vec3f SampleRadiosity(uint32_t chart, const ChartField& field,
                          const stream::GeometryTexel& g, uint32_t i, uint32_t j, uint32_t n,
                          bool unshot, bool emission) const;
    void Gather(uint32_t receiver, const std::vector<Emitter>& emitters,
                const std::vector<std::vector<float>>& links);
    // A chart's power at its finest emitter samples (SampleRadiosity x area, in
    // BuildEmitter's order): what it has left to shoot, or what it reflects in all.
    double FinestPower(uint32_t chart, bool unshot, bool emission) const;
    double UnshotPower(uint32_t chart, bool first_shot) const {
        return FinestPower(chart, true, first_shot);
    }
    double ReflectedPower(uint32_t chart) const { return FinestPower(chart, false, false); }
    // Charts with unshot power of at least chart_stop_fraction x their reflected power.
    std::vector<uint8_t> LaggingCharts(const std::vector<double>& unshot) const;
    float RayOffset(uint32_t chart) const;
    static Vec3f HorizonNormal(const stream::SurfaceSample& finest);
    // A quadtree node's bounding sphere, from the chart's geometry pyramid (the links' and
    // the bounce refinement's distance test).
    static void NodeSphere(const SolveChart& sc, const QuadNode& node, Vec3f* center,
                           float* radius);
    // The solver's scalar of a colour: the mean of its channels.
    static float Luminance(const Vec3f& c) { return (c.x + c.y + c.z) / 3; }
    // The level of a chart's light-map texels in its quadtree (max_level; unset: the
    // finest geometry level).
    static int TexelLevel(const SolveChart& sc) {
        return sc.max_level >= 0 ? sc.max_level : sc.geometry.finest_level();
    }
    size_t NodeBudget(const SolveChart& sc) const;
    // The charts in the direct pass's order: most light-map texels first (LargestFirst).
    std::vector<uint32_t> LargestFirst() const;
    // The finest emitter sample level of a chart (SolverSettings::emitter_texels).
    int EmitterTop(const SolveChart& sc) const;
    // The receiver point at chart coordinates (u, v), sampled (smp) from geometry level
    // `level`: visibility from the finest level, `outline` where it is not taken at the
    // point itself (a virtual point), and the horizon (HorizonNormal) when asked.
    static ReceiverPoint PointAt(const SolveChart& sc, int level, float u, float v,
                                 const stream::SurfaceSample& smp, bool horizon = true);
    void GaussPoints(const SolveChart& sc, const QuadNode& node, int ng, bool horizon,
                     std::vector<ReceiverPoint>* pts, std::vector<Vec3f>* albedo) const;
    static void ToFieldValues(std::span<const ReceiverPoint> pts, std::span<const Vec3f> albedo,
                              const std::vector<float>& e9, bool radiosity,
                              std::vector<float>* vals);

    const Scene& scene_;
    const std::vector<SolveChart>& charts_;
    const VisibilityScene& vis_;
    SolveOptions opt_;
    std::vector<ChartField> fields_;
    FieldPool* pool_ = nullptr;
    std::vector<uint8_t> emissive_;  // chart has emissive texels (shot in the first batch)
    ClusterTree clusters_;           // built when Run() starts, from the charts alone
    std::vector<ClusterSample> cluster_samples_;  // per chart: its level-1 texels
    std::vector<uint32_t> cluster_sample_first_;  // chart c: [first[c], first[c + 1])
    SolveStats stats_;
    double reference_ = 0;  // brightest direct irradiance: floor of the refinement scale
    int next_batch_ = -1;
    BatchHook batch_hook_;
    const std::atomic<bool>* stop_ = nullptr;
    const Progress* progress_ = nullptr;  // during Run()
};

}  // namespace mebake::solve
