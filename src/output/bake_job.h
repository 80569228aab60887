// `mebake bake` as a library call: ingest + solve + export + a render into one output
// directory with default settings. On a directory a bake wrote before it resumes
// (docs/resume.md): a finished ingest whose inputs and options match is kept, the solve
// continues from its checkpoint, the outputs are written again.
#pragma once

#include "core/vec.h"
#include "io/mesh_stream.h"

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace mebake::output {

struct BakeJobOptions {
    std::vector<std::string> inputs;  // paths; "-" is stdin
    std::optional<io::MeshFormat> format;
    std::string output;  // directory, or "-" for the vertex-coloured PLY on stdout
    std::string scene_file;
    uint64_t memory = uint64_t(1) << 30;
    int threads = 0;
    int order = -1;
    double tolerance = -1;
    int max_bounces = -1;
    uint32_t lightmap_resolution = 2048;
    bool ground = false;  // a ground plane under the inputs (stream/ground.h)
    std::optional<Vec3d> up;  // the scans' up axis; none: detected (stream/up_axis.h)
    double checkpoint_interval = 30;
    bool force = false;
};

void RunBakeJob(const BakeJobOptions& opt);

}  // namespace mebake::output
