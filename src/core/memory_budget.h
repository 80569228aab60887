// The one memory budget (`--memory`), made once from the option and handed to every stage.
// Each stage takes its share by name; the fractions live here and nowhere else, so what a
// budget buys can be read (and printed: Shares()) in one place. Stages run one after the
// other, so shares of different stages may add up to more than the whole; shares used at
// the same time (the solve's visibility and geometry pyramids) do not.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace mebake {

struct MemoryShare {
    std::string name;  // stage.pool
    uint64_t bytes = 0;
    std::string rule;  // how it is derived from the budget
};

class MemoryBudget {
public:
    explicit MemoryBudget(uint64_t total_bytes) : total_(total_bytes) {}
    uint64_t total() const { return total_; }

    // Ingest pass 1: page cache of the spill's append-only files. A few pages per file
    // write in large blocks; more buys nothing.
    uint64_t SpillCache() const;
    // Ingest pass 2: page cache of vertex look-ups while faces are binned (the caller also
    // caps it at a few times the spilled data, so small meshes take little).
    uint64_t BinningCache() const;
    // Ingest pass 3: the bricks in core (repair, charts, parameterization). Pass 3 runs
    // alone, so it may take the whole budget; how many bricks are in flight follows from
    // it (their size does not: it decides the charts, so it is fixed).
    uint64_t Bricks() const;
    // The Embree scene of the visibility mesh (the full mesh, or a clustered proxy made at
    // ingest to fit it). Fixed, not a fraction: the proxy decides what the solve sees, so a
    // size that followed --memory would make every output depend on the budget. 64 MiB:
    // the full mesh up to 1.2M triangles, else a proxy of 670K (the default 1G's share of
    // before); it fits any budget from 256M up beside the solve's other shares.
    static constexpr uint64_t kVisibilityBytes = uint64_t(64) << 20;
    uint64_t Visibility() const { return kVisibilityBytes; }
    // Solve: the geometry pyramids resident beyond the charts pinned by the threads.
    uint64_t GeometryPyramids() const;
    // Solve: the coefficient pools (quadtree nodes, value and unshot per chart) resident
    // beyond the fields pinned by the threads and the emitters being built. At most the
    // default 1G's 64 MiB: an evicted field's pages stay in the kernel's page cache and
    // fault back in without I/O, so more buys no measurable time (bench/RESULTS.md, "Issue
    // 16 (session 9)") while the solve's peak would grow with the charts up to 1/16.
    uint64_t CoefficientPools() const;
    // Solve: a hard cap on Embree's own allocations (its memory monitor): twice the
    // visibility share (the share sizes the scene; the cap allows for Embree's build
    // peak), at most half the budget; under 256M a visibility mesh too large for it is
    // traced in pieces (solve/paged_visibility.h) instead of exceeding the budget.
    uint64_t EmbreeLimit() const;

    // Export: the page cache of each of the vertex colours' disk arrays (the running sums
    // per input vertex are looked up tile by tile). More buys little: evicted pages are
    // read back from the kernel's page cache.
    uint64_t ExportCache() const;
    // Export and render: the sampled chart borders kept between charts' stitch data
    // (seam_graph.h; each chart's is rebuilt from its neighbourhood, so a miss costs a
    // tile read, never bytes). A fixed cap: charts ask for their neighbours in chart order,
    // so a few hundred charts' borders hold the reuse (16M sphere: 4 MiB misses 1159 of
    // 4104 requests, 16 MiB 786, for 2 CPU-s of 25), and a larger cap only fills on big
    // meshes, which made the export's peak grow with the mesh (bench/RESULTS.md, issue 16
    // session 10).
    uint64_t StitchCache() const;
    // Export: the light map's texel stitch (output/texel_stitch.h): its seam samples (64 B
    // each) in memory while they fit, and the colour channels' CGs in parallel when their
    // vectors fit too; past it the samples are read from a temporary file by every CG pass
    // and the channels are solved in turn (the same texels either way).
    uint64_t StitchRows() const;

    std::vector<MemoryShare> Shares() const;

private:
    uint64_t total_;
};

// Hands the heap's free pages back to the system (glibc: malloc_trim). Freed memory stays
// resident otherwise: glibc trims only the top of each arena, above a threshold that grows
// to twice the largest block freed (up to 64 MB), and a worker thread's arena not at all.
// A stage calls it between passes, when what the last pass freed would otherwise count
// against the next pass's peak.
void ReturnFreedHeap();

// Blocks of 4 MiB and more straight from the system (mmap), returned to it when freed, and
// the heap's top trimmed above glibc's default 128 KiB. glibc's own rule raises the mmap
// threshold to the largest block freed (up to 32 MB) and the top's trim threshold to twice
// that, so after a few large arrays every later one lands in a heap that keeps what it
// frees; with two threads each keeping its own, the ingest's peak grew with the number of
// bricks (16M sphere: 218-233 MiB, 198 with this; bench/RESULTS.md, issue 16 session 11).
// It stays for the rest of the process (`mebake bake`'s solve and export): glibc cannot go
// back to its dynamic thresholds, and their ceiling set after the ingest (mmap 32 MiB, trim
// 64 MiB) raised the horse's bake peak from 171-176 to 212-216 MiB for no CPU measured
// (issue 16 session 12).
void KeepLargeBlocksOutOfTheHeap();

}  // namespace mebake
