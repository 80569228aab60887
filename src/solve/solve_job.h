// `mebake solve` as a library call: a bake directory in, solve/solution.bin and
// solve/stats.json out. Loads the scene, the charts' geometry images and the visibility
// mesh, turns small emissive surfaces into exact polygon lights, and runs the solver.
// Checkpoints (checkpoint.h) are written every checkpoint_interval seconds at batch
// boundaries and on SIGINT/SIGTERM (then Error(Cancelled): exit 130); `resume` continues
// from the newest good one, or reuses a finished solution made from the same tiles and
// settings (docs/resume.md).
#pragma once

#include "core/memory_budget.h"
#include "solve/solver.h"
#include "stream/bake_dir.h"

#include <string>

namespace mebake::solve {

struct SolveJobOptions {
    std::string dir;
    std::string scene_file;  // empty: inputs' materials + default rig
    int order = -1;          // -1: from the scene file (default 2)
    double tolerance = -1;
    int max_bounces = -1;
    double time_limit = 0;
    double stop_fraction = -1;  // < 0: from the scene file (default 2.5e-3)
    std::string unshot_tail;    // "on" or "off"; empty: the scene file's
    int threads = 0;
    uint64_t memory = uint64_t(1) << 30;
    bool radiosity = false;
    std::string multi_emitter;  // "full" or "simplify"; empty: the scene file's
    std::string multi_emitter_debug;  // directory for the simplify pictures; empty: none
    std::string stats_file;           // extra copy of the statistics (JSON)
    double checkpoint_interval = 30;  // seconds; 0: at every batch boundary; < 0: only on signals
    bool resume = false;              // continue from a checkpoint / keep a matching solution
    bool force = false;               // discard checkpoints and solve from the start
    // Paged visibility (paged_visibility.h), used on its own when the proxy's Embree scene
    // would exceed half the Embree cap of --memory. > 0 forces it, with pieces of at most
    // this many triangles; paged_cache > 0 sets the resident pieces' bytes (else the share).
    uint32_t paged_visibility = 0;
    uint64_t paged_cache = 0;
};

SolveStats RunSolveJob(const SolveJobOptions& opt);

// Whether the solve traces this directory's visibility mesh in pieces at this budget
// (unless forced): its Embree scene, estimated as ingest sized it (56 B per triangle of the
// full mesh, 100 B of a clustered proxy), over half the budget's Embree cap. Ingest fits
// the scene to the 64 MiB visibility share, so from --memory 256M up it never is.
bool VisibilityIsPaged(const stream::Manifest& m, const MemoryBudget& budget);

// Whether the solve builds Embree's compact BVH (triangles by index) rather than its full
// one (vertices in the leaves: ~12 % less solve CPU on the shared scans, ~30 % more Embree
// memory): compact when paged, or when the full scene (3x the estimate above) would not
// fit the 64 MiB visibility share; the same answer for any budget from 256M up.
bool VisibilityIsCompact(const stream::Manifest& m, const MemoryBudget& budget);

}  // namespace mebake::solve
