// The subcommands, as plain functions over option structs. main.cpp (the only file that
// sees CLI11) fills the structs; each command returns an exit code or throws mebake::Error.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "io/mesh_stream.h"

namespace mebake::app {

struct InfoOptions {
    std::string input;                       // mesh path, "-" or a bake directory
    std::optional<io::MeshFormat> format;    // forced format for pipes
    bool json = false;                       // machine-readable output on stdout
};
int RunInfo(const InfoOptions& opt);

struct ConvertOptions {
    std::string input, output;
    std::optional<io::MeshFormat> in_format, out_format;
    bool ascii = false;         // PLY ascii output
    bool big_endian = false;    // PLY binary big-endian output
    bool no_normals = false, no_colors = false, no_uvs = false;
    bool float_colors = false;
    bool force = false;         // overwrite an existing output file
};
int RunConvert(const ConvertOptions& opt);

struct IngestCommand {
    std::vector<std::string> inputs;
    std::optional<io::MeshFormat> format;
    std::string output;
    std::string memory = "1G";
    int threads = 0;
    double texel_size = 0;
    uint32_t lightmap_resolution = 2048;
    double max_distortion = 0.05;
    bool force = false;
    bool ground = false;
    bool keep_winding = false;  // no orientation pass (stream/orient.h)
    bool merge_horizon_cells = false;  // stream/chart_builder.h
    std::string up;             // x, -x, y, ... ; empty: detected (stream/up_axis.h)
};
int RunIngest(const IngestCommand& opt);

struct SolveCommand {
    std::string dir;
    std::string scene_file;
    int order = -1;
    double tolerance = -1;
    int max_bounces = -1;
    double time_limit = 0;
    double stop_fraction = -1;        // < 0: the scene file's (default 2.5e-3)
    std::string unshot_tail;          // on | off; empty: the scene file's
    int threads = 0;
    std::string memory = "1G";
    std::string unknown = "irradiance";
    std::string multi_emitter;  // full | simplify; empty: the scene file's (default full)
    std::string multi_emitter_debug;  // directory for the per-chart simplify pictures
    std::string stats_file;
    double checkpoint_interval = 30;  // seconds between checkpoints (0: every batch; < 0: never)
    bool resume = false;              // continue from the last good checkpoint
    bool force = false;               // discard checkpoints, solve from the start
    uint32_t paged_visibility = 0;    // > 0: trace the proxy in pieces of this many triangles
    std::string paged_cache;          // resident pieces' bytes (e.g. 8M); empty: the budget's
};
int RunSolve(const SolveCommand& opt);

struct BakeCommand {
    std::vector<std::string> inputs;
    std::optional<io::MeshFormat> format;
    std::string output;        // directory, or "-" for the vertex-coloured PLY on stdout
    std::string scene_file;
    std::string memory = "1G";
    int threads = 0;
    int order = -1;
    double tolerance = -1;
    int max_bounces = -1;
    bool ground = false;
    std::string up;  // as IngestCommand::up
    uint32_t lightmap_resolution = 2048;
    double checkpoint_interval = 30;
    bool force = false;
};
// ingest + solve + export (+ a render) with defaults; see docs/usage in README. On an
// existing output directory it resumes (docs/resume.md): a finished ingest whose inputs
// and options match is kept, the solve continues from its checkpoint, exports are redone.
int RunBake(const BakeCommand& opt);

// `mebake info <bake directory>`.
int RunBakeInfo(const std::string& dir, bool json);

}  // namespace mebake::app
