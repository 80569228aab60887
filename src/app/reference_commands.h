// `mebake reference` and `mebake compare` as plain functions over option structs (main.cpp
// fills them): an independent path-traced reference at surface points, and the error of a
// solved bake against it (docs/accuracy.md).
#pragma once

#include <cstdint>
#include <string>

namespace mebake::app {

struct ReferenceCommand {
    std::string dir;         // ingested (optionally solved) bake directory
    std::string scene_file;  // empty: the solve's scene, else the inputs' + default rig
    int points = 1000;
    uint64_t seed = 1;
    uint64_t min_samples = 256;
    uint64_t max_samples = 1 << 16;
    double target = 0.01;  // relative standard error of B per point
    double time_limit = 0;
    int threads = 0;
    std::string output = "-";  // JSON, "-" = stdout
};
int RunReference(const ReferenceCommand& c);

struct CompareCommand {
    std::string dir;           // solved bake directory (the one the reference was made on)
    std::string reference;     // JSON written by `mebake reference`
    std::string output = "-";  // JSON summary, "-" = stdout
    bool points = false;       // also list every point's baked and reference B
    bool no_stitch = false;    // score each chart's own field at chart borders
};
int RunCompare(const CompareCommand& c);

}  // namespace mebake::app
