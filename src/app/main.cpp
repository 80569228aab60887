// mebake's command line. This is the only file that includes CLI11 (slow to compile) and
// the one place where errors become messages and exit codes:
//   0 success, 1 runtime failure (bad input, I/O), 2 usage error, 130 interrupted.
#include <CLI/CLI.hpp>

#include <cstdio>
#include <exception>
#include <string>

#include "app/commands.h"
#include "app/export_commands.h"
#include "app/reference_commands.h"
#include "app/view_commands.h"
#include "core/error.h"
#include "core/log.h"
#include "core/progress.h"
#include "io/mesh_format.h"
#include "stream/bake_dir.h"

namespace {

// --up of ingest and bake (stream/up_axis.h states the rule).
constexpr const char* kUpHelp =
    "The scans' up axis x, y, z, -x, -y or -z (default: detected: the direction whose lowest "
    "1 % of vertices spans the largest support, if clearly; else +y); the default light, "
    "camera and --ground stand on it";

using mebake::io::MeshFormat;

// CLI11 validator/transform for --format.
std::optional<MeshFormat> ToFormat(const std::string& s) {
    if (s.empty()) return std::nullopt;
    auto f = mebake::io::ParseFormatName(s);
    if (!f) mebake::UsageError("unknown format '{}': expected ply, obj, off or stl", s);
    return f;
}

const CLI::Validator kFormatName = CLI::IsMember({"ply", "obj", "off", "stl"}, CLI::ignore_case);

int ExitCode(mebake::ErrorKind kind) {
    switch (kind) {
    case mebake::ErrorKind::Usage: return 2;
    case mebake::ErrorKind::Cancelled: return 130;
    default: return 1;
    }
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{
        "mebake - bakes global illumination onto huge scanned meshes.\n"
        "Meshes stream through in bounded memory; '-' reads stdin or writes stdout.",
        "mebake"};
    app.set_version_flag("--version", std::string("mebake ") + MEBAKE_VERSION);
    app.require_subcommand(1);
    app.fallthrough();  // global options (-q, --progress) may also follow the command
    int verbosity = 0;
    app.add_flag("-v,--verbose", verbosity, "More detail on stderr (repeat for trace)");
    bool quiet = false;
    app.add_flag("-q,--quiet", quiet, "Only errors on stderr");
    std::string progress = "auto";
    app.add_option("--progress", progress,
                   "Progress of long stages on stderr: auto (a line redrawn on a terminal, a "
                   "log line every 5 s otherwise), plain, json (one object per line), off")
        ->capture_default_str()
        ->check(CLI::IsMember({"auto", "plain", "json", "off"}));

    // info
    mebake::app::InfoOptions info;
    std::string info_format;
    auto* info_cmd = app.add_subcommand(
        "info", "Stream a mesh (or '-') and report counts, bounds, properties, face sizes,\n"
                "degenerate and zero-area faces, unreferenced vertices and read time.");
    info_cmd->add_option("input", info.input, "Mesh file (ply, obj, off, stl) or '-' for stdin")
        ->required();
    info_cmd->add_option("--format", info_format, "Input format when it cannot be told from a name")
        ->check(kFormatName);
    info_cmd->add_flag("--json", info.json, "Print the report as JSON on stdout");

    // convert
    mebake::app::ConvertOptions conv;
    std::string conv_in_format, conv_out_format;
    auto* conv_cmd = app.add_subcommand(
        "convert", "Stream a mesh from one format to another (ply, obj, off, stl in; ply, obj out).");
    conv_cmd->add_option("input", conv.input, "Input mesh or '-' for stdin")->required();
    conv_cmd->add_option("output", conv.output, "Output mesh or '-' for stdout")->required();
    conv_cmd->add_option("--format", conv_in_format, "Input format (for stdin)")->check(kFormatName);
    conv_cmd->add_option("--to", conv_out_format, "Output format (for stdout; default ply)")
        ->check(CLI::IsMember({"ply", "obj"}, CLI::ignore_case));
    conv_cmd->add_flag("--ascii", conv.ascii, "Write ASCII PLY (default: binary little-endian)");
    conv_cmd->add_flag("--big-endian", conv.big_endian, "Write binary big-endian PLY");
    conv_cmd->add_flag("--no-normals", conv.no_normals, "Drop vertex normals");
    conv_cmd->add_flag("--no-colors", conv.no_colors, "Drop vertex colours");
    conv_cmd->add_flag("--no-uvs", conv.no_uvs, "Drop vertex texture coordinates");
    conv_cmd->add_flag("--float-colors", conv.float_colors, "Write PLY colours as float, not uchar");
    conv_cmd->add_flag("-f,--force", conv.force, "Overwrite an existing output file");

    // ingest
    mebake::app::IngestCommand ing;
    std::string ing_format;
    auto* ing_cmd = app.add_subcommand(
        "ingest", "Stream meshes into a bake directory of chart tiles (memory bounded by --memory).");
    ing_cmd->add_option("inputs", ing.inputs, "Mesh files, or '-' for stdin; several make one scene")
        ->required();
    ing_cmd->add_option("-o,--output", ing.output, "Bake directory to write (e.g. scene.mebake)")
        ->required();
    ing_cmd->add_option("--format", ing_format, "Format of stdin")->check(kFormatName);
    ing_cmd->add_option("--memory", ing.memory, "Memory budget (e.g. 512M, 2G)")->capture_default_str();
    ing_cmd->add_option("--threads", ing.threads, "Worker threads (0: all cores)")->capture_default_str();
    auto* texel = ing_cmd->add_option("--texel-size", ing.texel_size,
                                      "Light-map texel size in scene units (default: from --lightmap-resolution)");
    ing_cmd->add_option("--lightmap-resolution", ing.lightmap_resolution,
                        "Atlas side the default texel size aims at")->capture_default_str()
        ->excludes(texel);
    ing_cmd->add_option("--max-distortion", ing.max_distortion,
                        "Jacobian (area) deviation above which a chart is split")->capture_default_str()
        ->check(CLI::Range(0.001, 1.0));
    ing_cmd->add_flag("-f,--force", ing.force, "Replace an existing bake directory");
    ing_cmd->add_flag("--ground", ing.ground,
                      "Add a ground plane under the scans (at the bounding box's floor along the up "
                      "axis, see --up; 3x the object's width, albedo 0.4)");
    ing_cmd->add_option("--up", ing.up, kUpHelp);
    ing_cmd->add_flag("--keep-winding", ing.keep_winding,
                      "Keep every component's winding as read. Default: a closed or nearly closed "
                      "component wound inwards (negative enclosed volume) is turned outwards, "
                      "unless its box contains or lies in another's (a room, a cavity)");
    ing_cmd->add_flag("--merge-horizon-cells", ing.merge_horizon_cells,
                      "Merge charts with their turning bounded on cells of 8 light-map texels "
                      "instead of an 8 x 8 grid per chart: fewer, larger charts (experimental: "
                      "lucy 237 -> 90 charts, not yet as accurate; docs/method.md, \"Merging\")");

    // solve
    mebake::app::SolveCommand sol;
    auto* sol_cmd = app.add_subcommand(
        "solve", "Compute global illumination on an ingested bake directory (Master-Element\n"
                 "vector irradiance, Southwell shooting, adaptive wavelets).");
    sol_cmd->add_option("dir", sol.dir, "Bake directory made by `mebake ingest` (or `mebake bake`'s output directory)")->required();
    sol_cmd->add_option("--scene", sol.scene_file, "Scene file (JSON): materials, lights, sky, settings");
    sol_cmd->add_option("--order", sol.order, "Wavelet order: 0 constant ... 3 cubic (default 2)")
        ->check(CLI::Range(0, 3));
    sol_cmd->add_option("--tolerance", sol.tolerance, "Relative error that triggers subdivision (default 0.02)");
    sol_cmd->add_option("--max-bounces", sol.max_bounces, "Shooting batches after the direct pass (default 16)");
    sol_cmd->add_option("--time-limit", sol.time_limit, "Stop shooting after this many seconds");
    sol_cmd->add_option("--stop-fraction", sol.stop_fraction,
                        "Stop shooting when the unshot power is below this fraction of the first "
                        "shot's (default: the scene file's solver.stop_fraction, else 0.0025)")
        ->check(CLI::Range(0.0, 0.5));
    sol_cmd->add_option("--unshot-tail", sol.unshot_tail,
                        "At that stop, add the bounces left as the last batch's light, scaled by "
                        "its received / shot power (docs/method.md, \"The unshot tail\"); "
                        "default: the scene file's solver.unshot_tail, else on")
        ->check(CLI::IsMember({"on", "off"}));
    sol_cmd->add_option("--threads", sol.threads, "Worker threads (0: all cores)")->capture_default_str();
    sol_cmd->add_option("--memory", sol.memory, "Memory budget (e.g. 512M, 2G)")->capture_default_str();
    sol_cmd->add_option("--unknown", sol.unknown, "Solve for vector irradiance or radiosity")->capture_default_str()
        ->check(CLI::IsMember({"irradiance", "radiosity"}));
    sol_cmd->add_option("--multi-emitter", sol.multi_emitter,
                        "Direct light of several polygon lights: full (every light traced everywhere) "
                        "or simplify (extremal boundaries + L2 simplification, seed 002); default: "
                        "the scene file's solver.multi_emitter, else simplify")
        ->check(CLI::IsMember({"full", "simplify"}));
    sol_cmd->add_option("--multi-emitter-debug", sol.multi_emitter_debug,
                        "With --multi-emitter simplify: write DIR/chart-N.png per chart, each "
                        "light's lit/umbra/penumbra regions and the direct light's final "
                        "quadtree by test (docs/method.md, \"Several sources\")");
    sol_cmd->add_option("--stats", sol.stats_file, "Also write the statistics (JSON) here");
    sol_cmd->add_option("--checkpoint-interval", sol.checkpoint_interval,
                        "Seconds between checkpoints (solve/checkpoint.bin; 0: every batch, "
                        "negative: only on SIGINT/SIGTERM)")->capture_default_str();
    auto* sol_resume = sol_cmd->add_flag("--resume", sol.resume,
                                         "Continue an interrupted solve from its last good checkpoint");
    sol_cmd->add_flag("-f,--force", sol.force, "Discard checkpoints and solve from the start")
        ->excludes(sol_resume);
    sol_cmd->add_option("--paged-visibility", sol.paged_visibility,
                        "Trace the visibility mesh in spatial pieces of at most this many "
                        "triangles through an LRU of Embree scenes (same results; automatic when "
                        "the mesh exceeds its share of --memory)");
    sol_cmd->add_option("--paged-cache", sol.paged_cache,
                        "With paged visibility: bytes of piece scenes kept resident (e.g. 16M; "
                        "default: the budget's share)");

    // reference, compare  (#include "app/reference_commands.h")
    mebake::app::ReferenceCommand ref;
    std::vector<double> ref_target;
    auto* ref_cmd = app.add_subcommand(
        "reference", "Independent path-traced radiosity B and vector irradiance E, with standard\n"
                     "errors, at random surface points of a bake directory (docs/accuracy.md);\n"
                     "a solved directory also gets its baked B at the same points and the error.");
    ref_cmd->add_option("dir", ref.dir, "Ingested (or solved) bake directory, or `mebake bake`'s output directory")->required();
    ref_cmd->add_option("--scene", ref.scene_file, "Scene file (default: the solve's, else the default rig)");
    ref_cmd->add_option("--points", ref.points, "Surface points (area-weighted)")->capture_default_str()
        ->check(CLI::Range(1, 10000000));
    ref_cmd->add_option("--seed", ref.seed, "Seed of the points and the paths")->capture_default_str();
    ref_cmd->add_option("--min-samples", ref.min_samples, "Paths per point in the first round")->capture_default_str()
        ->check(CLI::Range(uint64_t(2), uint64_t(1) << 40));
    ref_cmd->add_option("--samples", ref.max_samples, "Most paths per point")->capture_default_str()
        ->check(CLI::Range(uint64_t(2), uint64_t(1) << 40));
    // --target: one number is the standard-error target (as always), three are the camera's
    // look-at point of --image (as in render); --se-target sets the former beside the latter.
    ref_cmd->add_option("--target", ref_target, "Relative standard error of B to stop at (default 0.01); with --image, three numbers x,y,z are the point looked at, as in render")
        ->expected(1, 3)->delimiter(',');
    ref_cmd->add_option("--se-target", ref.target, "Relative standard error of B to stop at")
        ->check(CLI::Range(1e-6, 1.0));
    ref_cmd->add_option("--time-limit", ref.time_limit, "Stop doubling samples after about this many seconds");
    ref_cmd->add_option("--threads", ref.threads, "Worker threads (0: all cores)")->capture_default_str();
    ref_cmd->add_option("-o,--output", ref.output, "JSON output ('-' = stdout)")->capture_default_str();
    ref_cmd->add_option("--image", ref.images, "Path-trace the picture of a view instead of points: .exr (radiance, coverage A, standard errors se.*) or .png (tone-mapped as render); repeatable")->take_all();
    ref_cmd->add_option("--rule-image", ref.rule_images, "--image: also the light map's display rule (pi Le + rho (n.E)+)/pi applied to the estimated E at the same hits (.exr or .png): the bake's picture if its field were exact")->take_all();
    ref_cmd->add_option("--eye", ref.eye, "--image: camera position x,y,z (default: render's view)")->expected(3)->delimiter(',');
    ref_cmd->add_option("--up", ref.up, "--image: up direction x y z")->expected(3)->delimiter(',');
    ref_cmd->add_option("--fov", ref.fov, "--image: vertical field of view, degrees")->capture_default_str()
        ->check(CLI::Range(1.0, 179.0));
    ref_cmd->add_option("--size", ref.size, "--image: WIDTHxHEIGHT")->capture_default_str();
    ref_cmd->add_option("--aa", ref.strata, "--image: primary rays per pixel and axis (as render --samples)")->capture_default_str()
        ->check(CLI::Range(1, 16));
    ref_cmd->add_option("--background", ref.background, "--image: radiance of missed rays r g b (default: the sky)")->expected(3)->delimiter(',');
    ref_cmd->add_option("--exposure", ref.exposure, "--image: exposure in stops (EV) for PNG")->capture_default_str();
    ref_cmd->add_option("--tonemap", ref.tonemap, "--image: tone curve for PNG")->capture_default_str()
        ->check(CLI::IsMember({"filmic", "reinhard", "clamp"}));
    mebake::app::CompareCommand cmp;
    auto* cmp_cmd = app.add_subcommand(
        "compare", "Score a solved bake directory against a `mebake reference` JSON: relative RMS\n"
                   "and max error of B at the reference's points; or two pictures of the same\n"
                   "view (IMAGE REFERENCE, .png/.exr): RMS, p95, max and a difference picture\n"
                   "(docs/accuracy.md).");
    cmp_cmd->add_option("dir", cmp.dir, "Solved bake directory (or `mebake bake`'s output directory), or a picture (.png/.exr)")->required();
    cmp_cmd->add_option("reference", cmp.reference, "JSON from `mebake reference`, or the reference picture")->required();
    cmp_cmd->add_option("--diff", cmp.diff, "Pictures: write the false-colour difference here (.png; red: brighter than the reference, blue: darker)");
    cmp_cmd->add_option("--diff-range", cmp.diff_range, "Pictures: display difference (sRGB 0..1) shown at full colour")->capture_default_str();
    cmp_cmd->add_flag("--borders", cmp.borders, "Pictures: draw the chart borders of the reference's chart channel on --diff");
    cmp_cmd->add_option("--mask", cmp.mask, "Pictures: an EXR whose coverage (A) also limits the pixels compared");
    cmp_cmd->add_option("--rule", cmp.rule, "Pictures: the reference's rule picture (reference --rule-image): how much of the error is the display rule's loss");
    cmp_cmd->add_option("--exposure", cmp.exposure, "Pictures: exposure (EV) of the tone map for display values")->capture_default_str();
    cmp_cmd->add_option("--tonemap", cmp.tonemap, "Pictures: tone curve for display values")->capture_default_str()
        ->check(CLI::IsMember({"filmic", "reinhard", "clamp"}));
    cmp_cmd->add_option("-o,--output", cmp.output, "JSON summary ('-' = stdout)")->capture_default_str();
    cmp_cmd->add_flag("--points", cmp.points, "Also list each point's reference and baked B");
    cmp_cmd->add_flag("--no-stitch", cmp.no_stitch, "Score each chart's own field at chart borders (no stitching; to compare)");

    // export  (#include "app/export_commands.h")
    mebake::app::ExportCommand exp;
    auto* exp_cmd = app.add_subcommand(
        "export", "Write what a solved bake directory holds: light-map atlas (EXR/PNG), vector\n"
                  "irradiance maps (EXR), the mesh with light-map uvs (glTF .glb, PLY, OBJ),\n"
                  "per-vertex baked colours (PLY) and statistics (JSON).");
    exp_cmd->add_option("dir", exp.dir, "Solved bake directory, or the output directory of `mebake bake`")->required();
    exp_cmd->add_option("--lightmap", exp.lightmap, "Light map: .exr (linear B, W/m^2) or .png (tone-mapped); pages of a multi-page atlas get UDIM numbers (name.1001.exr ...)");
    exp_cmd->add_option("--irradiance", exp.irradiance, "Vector irradiance maps E (.exr, channels E.x.R ... E.z.B)");
    exp_cmd->add_option("--mesh", exp.mesh, "Mesh with light-map uvs: .glb (light map embedded), .ply or .obj; '-' = PLY on stdout");
    exp_cmd->add_option("--vertex-colors", exp.vertex_colors, "The input mesh with baked per-vertex colours (PLY, input vertex order); '-' = stdout");
    exp_cmd->add_option("--stats", exp.stats, "Statistics (JSON: atlas, outputs, seam metric); '-' = stdout");
    exp_cmd->add_option("--max-atlas", exp.max_atlas, "Largest atlas page side in texels (power of two)")->capture_default_str()
        ->check(CLI::Range(16u, 65536u));
    exp_cmd->add_option("--gutter", exp.gutter, "Texels of border repeated around each chart")->capture_default_str()
        ->check(CLI::Range(0u, 64u));
    exp_cmd->add_flag("--npot", exp.npot, "Atlas pages of any multiple of 4 texels (denser; default powers of two)");
    exp_cmd->add_option("--exposure", exp.exposure, "Exposure in stops (EV) for tone-mapped outputs")->capture_default_str();
    exp_cmd->add_option("--tonemap", exp.tonemap, "Tone curve for PNG and 8-bit colours")->capture_default_str()
        ->check(CLI::IsMember({"filmic", "reinhard", "clamp"}));
    exp_cmd->add_flag("--float", exp.float_output, "EXR as 32-bit float (default half); vertex colours as linear float");
    exp_cmd->add_option("--compression", exp.compression, "EXR compression")->capture_default_str()
        ->check(CLI::IsMember({"zip", "piz", "none"}));
    exp_cmd->add_flag("--unlit", exp.unlit, ".glb: KHR_materials_unlit base colour instead of an emissive light map");
    exp_cmd->add_option("--threads", exp.threads, "Worker threads (0: all cores)")->capture_default_str();
    exp_cmd->add_option("--memory", exp.memory, "Memory budget (e.g. 512M, 2G)")->capture_default_str();
    exp_cmd->add_flag("--no-stitch", exp.no_stitch, "Show each chart's own field at chart borders (no stitching; to compare)");
    exp_cmd->add_flag("-f,--force", exp.force, "Overwrite existing output files");
    std::string exp_web;
    bool exp_web_plain = false;
    exp_cmd->add_option("--web", exp_web, "Directory for the browser viewer as static files (docs/viewer.md)");
    exp_cmd->add_flag("--no-meshopt", exp_web_plain, "--web: plain glTF buffers, no EXT_meshopt_compression");

    // view  (#include "app/view_commands.h")
    mebake::app::ViewCommand vw;
    auto* vw_cmd = app.add_subcommand(
        "view", "Serve a browser viewer of a solved bake on localhost: light map, vector\n"
                "irradiance and the seed's glossy display on the GPU (docs/viewer.md).");
    vw_cmd->add_option("dir", vw.dir, "Solved bake directory, or the output directory of `mebake bake`")->required();
    vw_cmd->add_option("--port", vw.port, "TCP port on 127.0.0.1 (0: any free port)")->capture_default_str();
    vw_cmd->add_option("--chunk", vw.chunk_triangles, "Triangles per streamed mesh chunk")->capture_default_str();
    vw_cmd->add_flag("--no-meshopt", vw.no_meshopt, "Plain glTF buffers, no EXT_meshopt_compression");
    vw_cmd->add_flag("--rewrite", vw.rewrite, "Rewrite the viewer data (DIR/web) even when current");
    vw_cmd->add_option("--threads", vw.threads, "Worker threads (0: all cores)")->capture_default_str();

    // render
    mebake::app::RenderCommand ren;
    auto* ren_cmd = app.add_subcommand(
        "render", "Render a view of the baked lighting (pinhole camera, full-resolution mesh).");
    ren_cmd->add_option("dir", ren.dir, "Solved bake directory, or the output directory of `mebake bake`")->required();
    ren_cmd->add_option("-o,--output", ren.output, "Image: .exr (linear radiance) or .png (tone-mapped); '-' = EXR on stdout")->required();
    ren_cmd->add_option("--eye", ren.eye, "Camera position x,y,z (or x y z) (default: a three-quarter view from the key light's side, the object filling 85 % of the frame)")->expected(3)->delimiter(',');
    ren_cmd->add_option("--target", ren.target, "Point looked at x y z (default: the scene's centre)")->expected(3)->delimiter(',');
    ren_cmd->add_option("--up", ren.up, "Up direction x y z (default: the scene's up)")->expected(3)->delimiter(',');
    ren_cmd->add_option("--fov", ren.fov, "Vertical field of view, degrees")->capture_default_str()
        ->check(CLI::Range(1.0, 179.0));
    ren_cmd->add_option("--size", ren.size, "Image size WIDTHxHEIGHT")->capture_default_str();
    ren_cmd->add_flag("--glossy", ren.glossy, "View-dependent glossy display (seed: L ~ Le + |E| fr)");
    ren_cmd->add_option("--samples", ren.samples, "Rays per pixel and axis (antialiasing)")->capture_default_str()
        ->check(CLI::Range(1, 16));
    ren_cmd->add_option("--background", ren.background, "Radiance of missed rays r g b (default: the sky)")->expected(3)->delimiter(',');
    ren_cmd->add_option("--exposure", ren.exposure, "Exposure in stops (EV) for PNG")->capture_default_str();
    ren_cmd->add_option("--tonemap", ren.tonemap, "Tone curve for PNG")->capture_default_str()
        ->check(CLI::IsMember({"filmic", "reinhard", "clamp"}));
    ren_cmd->add_flag("--float", ren.float_output, "EXR as 32-bit float (default half)");
    ren_cmd->add_option("--threads", ren.threads, "Worker threads (0: all cores)")->capture_default_str();
    ren_cmd->add_flag("--no-stitch", ren.no_stitch, "Show each chart's own field at chart borders (no stitching; to compare)");
    ren_cmd->add_flag("-f,--force", ren.force, "Overwrite an existing image");

    // bake
    mebake::app::BakeCommand bk;
    std::string bk_format;
    auto* bk_cmd = app.add_subcommand(
        "bake", "Ingest, solve and export in one go: writes OUT/lightmap.exr and .png, "
                "OUT/baked.glb,\nOUT/vertex_colors.ply, OUT/render.png and OUT/scene.mebake; "
                "'-o -' streams the\nvertex-coloured PLY to stdout.\n"
                "Defaults without --scene: a uniform sky and a key area light from the right, 40 "
                "degrees up\n(key : sky about 3 : 1); OUT/render.png looks from a three-quarter "
                "view on the key's\nside with the object filling about 85 % of the frame. Up is --up, else "
                "detected from the\nscan (the direction it stands on most broadly, else +y). "
                "Faces of a closed scan wound\ninwards are turned outwards.");
    bk_cmd->add_option("inputs", bk.inputs, "Mesh files, or '-' for stdin")->required();
    bk_cmd->add_option("-o,--output", bk.output, "Output directory, or '-' for stdout")->required();
    bk_cmd->add_option("--format", bk_format, "Format of stdin")->check(kFormatName);
    bk_cmd->add_option("--scene", bk.scene_file, "Scene file (JSON); default: materials + default rig");
    bk_cmd->add_option("--memory", bk.memory, "Memory budget")->capture_default_str();
    bk_cmd->add_option("--threads", bk.threads, "Worker threads (0: all cores)")->capture_default_str();
    bk_cmd->add_option("--order", bk.order, "Wavelet order 0..3 (default 2)")->check(CLI::Range(0, 3));
    bk_cmd->add_option("--tolerance", bk.tolerance, "Relative error that triggers subdivision (default 0.02)");
    bk_cmd->add_option("--max-bounces", bk.max_bounces, "Shooting batches after the direct pass (default 16)");
    bk_cmd->add_option("--checkpoint-interval", bk.checkpoint_interval,
                       "Seconds between solver checkpoints (0: every batch)")->capture_default_str();
    bk_cmd->add_option("--lightmap-resolution", bk.lightmap_resolution,
                       "Atlas side the texel size aims at")->capture_default_str();
    bk_cmd->add_flag("--ground", bk.ground,
                     "Add a ground plane under the scan that receives its shadow and bounces "
                     "light (at the bounding box's floor along the up axis, see --up; 3x the object's "
                     "width, albedo 0.4)");
    bk_cmd->add_option("--up", bk.up, kUpHelp);
    bk_cmd->add_flag("-f,--force", bk.force,
                     "Start over in an existing directory (without it, a bake resumes there)");

    // An example line under every --help (README, "Use", has more).
    app.footer(
        "Examples:\n"
        "  mebake bake scan.ply -o out/          ingest + solve + export + render, defaults\n"
        "  mebake info scan.ply                  what a mesh holds\n"
        "  mebake <command> --help               every option of a command");
    info_cmd->footer("Example:\n  mebake info scan.ply\n  mebake convert scan.obj - | mebake info -");
    conv_cmd->footer("Example:\n  mebake convert scan.obj scan.ply --float-colors");
    ing_cmd->footer("Example:\n  mebake ingest a.ply b.obj -o scene.mebake --memory 2G");
    sol_cmd->footer("Example:\n  mebake solve scene.mebake --scene lights.json --order 2\n"
                    "  mebake solve scene.mebake --resume    (after an interruption)");
    ref_cmd->footer("Example:\n  mebake reference scene.mebake --points 2000 -o ref.json\n"
                    "  mebake reference scene.mebake --image ref.exr --image ref.png --size 400x300 "
                    "--time-limit 300");
    cmp_cmd->footer("Example:\n  mebake compare scene.mebake ref.json\n"
                    "  mebake compare view.exr ref.exr --diff diff.png");
    exp_cmd->footer("Example:\n  mebake export scene.mebake --lightmap lm.exr --mesh lit.glb "
                    "--vertex-colors lit.ply\n"
                    "  mebake export out/ --mesh lit.obj    (out/ made by `mebake bake`)");
    vw_cmd->footer("Example:\n  mebake view out/rock    (then open http://127.0.0.1:8080/)\n"
                   "  http://127.0.0.1:8080/?eye=0,1,3.4&target=0,1,0&fov=40&mode=glossy");
    ren_cmd->footer("Example:\n  mebake render scene.mebake --eye 0,1,3 --target 0,0,0 -o view.png "
                    "--glossy\n"
                    "  mebake render out/ -o view.png --size 1280x960    (out/ made by `mebake bake`)");
    bk_cmd->footer("Example:\n  mebake bake scan.ply -o out/    (rerun the same command to resume)\n"
                   "  tools/mkscan --triangles 1000000 | mebake bake - -o out/");

    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        // Prints the help text (exit 0) or the usage error (exit 2, whatever CLI11's code).
        return app.exit(e) == 0 ? 0 : 2;
    }

    mebake::InitLogging(quiet ? -1 : verbosity);
    try {
        mebake::SetProgressMode(mebake::ParseProgressMode(progress, quiet));
        if (*info_cmd) {
            info.format = ToFormat(info_format);
            return mebake::app::RunInfo(info);
        }
        if (*ing_cmd) {
            ing.format = ToFormat(ing_format);
            return mebake::app::RunIngest(ing);
        }
        // Every command that reads a bake directory also takes `mebake bake`'s output
        // directory (its scene.mebake).
        using mebake::stream::BakeDirectoryIn;
        if (*sol_cmd) {
            sol.dir = BakeDirectoryIn(sol.dir);
            return mebake::app::RunSolve(sol);
        }
        if (*bk_cmd) {
            bk.format = ToFormat(bk_format);
            return mebake::app::RunBake(bk);
        }
        if (*exp_cmd) {
            exp.dir = BakeDirectoryIn(exp.dir);
            if (!exp_web.empty()) {
                mebake::app::RunExportWeb(exp.dir, exp_web, exp.force, exp_web_plain, exp.threads);
                if (exp.lightmap.empty() && exp.irradiance.empty() && exp.mesh.empty() &&
                    exp.vertex_colors.empty() && exp.stats.empty())
                    return 0;
            }
            return mebake::app::RunExport(exp);
        }
        if (*vw_cmd) return mebake::app::RunView(vw);
        if (*ref_cmd) {
            ref.dir = BakeDirectoryIn(ref.dir);
            if (ref_target.size() == 3)
                ref.look_at = ref_target;
            else if (ref_target.size() == 1 && ref_target[0] >= 1e-6 && ref_target[0] <= 1)
                ref.target = ref_target[0];
            else if (!ref_target.empty())
                mebake::UsageError("--target: one number (standard error, 1e-6..1) or three (x,y,z)");
            return mebake::app::RunReference(ref);
        }
        if (*cmp_cmd) {
            cmp.dir = BakeDirectoryIn(cmp.dir);
            return mebake::app::RunCompare(cmp);
        }
        if (*ren_cmd) {
            ren.dir = BakeDirectoryIn(ren.dir);
            return mebake::app::RunRender(ren);
        }
        if (*conv_cmd) {
            conv.in_format = ToFormat(conv_in_format);
            conv.out_format = ToFormat(conv_out_format);
            return mebake::app::RunConvert(conv);
        }
    } catch (const mebake::Error& e) {
        std::fprintf(stderr, "mebake: error: %s\n", e.what());
        return ExitCode(e.kind());
    } catch (const std::bad_alloc&) {
        std::fprintf(stderr, "mebake: error: out of memory (try a smaller --memory budget)\n");
        return 1;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "mebake: error: %s\n", e.what());
        return 1;
    }
    return 0;
}
