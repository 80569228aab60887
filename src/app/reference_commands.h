// `mebake reference` and `mebake compare` as plain functions over option structs (main.cpp
// fills them): an independent path-traced reference at surface points, and the error of a
// solved bake against it (docs/accuracy.md).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

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
    // --image: a path-traced picture instead of points (.exr: linear radiance, coverage A and
    // standard errors se.R se.G se.B; .png: tone-mapped as render does). Camera as render's.
    std::vector<std::string> images;
    // --rule-image: the display rule on the estimated vector irradiance at the same hits
    // (reference_image.h, ReferenceImage::rule): R G B and coverage A, no standard errors.
    std::vector<std::string> rule_images;
    std::vector<double> eye, look_at, up;  // empty: render's default camera
    double fov = 50;
    std::string size = "800x600";
    int strata = 1;                  // primary rays per pixel and axis (render --samples)
    std::vector<double> background;  // radiance of missed rays; empty: the sky
    double exposure = 0;
    std::string tonemap = "filmic";
};
int RunReference(const ReferenceCommand& c);
// The --image half of RunReference (cmd_reference_image.cpp).
int RunReferenceImage(const ReferenceCommand& c);

struct CompareCommand {
    std::string dir;           // solved bake directory (the one the reference was made on)
    std::string reference;     // JSON written by `mebake reference`
    std::string output = "-";  // JSON summary, "-" = stdout
    bool points = false;       // also list every point's baked and reference B
    bool no_stitch = false;    // score each chart's own field at chart borders
    // Pictures: `compare IMAGE REFERENCE` when both are .png/.exr files (output/image_compare.h).
    std::string diff;         // false-colour difference PNG
    double diff_range = 0.1;  // display difference (sRGB 0..1) at full colour
    std::string mask;         // picture whose coverage channel A also limits the pixels
    std::string rule;         // the reference's rule picture: split the error by it
    bool borders = false;     // draw the reference's chart borders on the difference
    double exposure = 0;
    std::string tonemap = "filmic";
};
int RunCompare(const CompareCommand& c);
// The picture half of RunCompare (cmd_compare_image.cpp); true when both are pictures.
bool IsPicturePair(const CompareCommand& c);
int RunCompareImages(const CompareCommand& c);

}  // namespace mebake::app
