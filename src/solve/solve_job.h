// `mebake solve` as a library call: a bake directory in, solve/solution.bin and
// solve/stats.json out. Loads the scene, the charts' geometry images and the visibility
// mesh, turns small emissive surfaces into exact polygon lights, and runs the solver.
#pragma once

#include <string>

#include "solve/solver.h"

namespace mebake::solve {

struct SolveJobOptions {
    std::string dir;
    std::string scene_file;       // empty: inputs' materials + default rig
    int order = -1;               // -1: from the scene file (default 2)
    double tolerance = -1;
    int max_bounces = -1;
    double time_limit = 0;
    int threads = 0;
    uint64_t memory = uint64_t(1) << 30;
    bool radiosity = false;
    std::string stats_file;       // extra copy of the statistics (JSON)
};

SolveStats RunSolveJob(const SolveJobOptions& opt);

}  // namespace mebake::solve
