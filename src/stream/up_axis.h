// The scan's up direction, for the default rig, the default camera and --ground: scans come
// y-up (most graphics formats) or z-up (photogrammetry, CAD), and a scan lit and framed on
// the wrong axis lies on its side.
//
// The rule: an object that stands on something touches it at its lowest points. For each of
// the six axis directions d, the contact points are the vertices within kContactLevel of the
// object's extent from its lowest level along d, and the support ratio is the area of their
// convex hull over the bounding box's cross-section (a flat base or a pedestal: ~0.3-1; four
// hooves: their footprint; a side, a nose or a wing tip: ~0.01). Up is the direction whose
// support ratio is the largest, when that is at least kMinSupport and kMargin times the
// runner-up's; otherwise +Y, the scene format's default (a cube, a head cut nowhere flat).
// Measured on the shared scans in bench/RESULTS.md (issue 17, session 6).
//
// Memory: one occupancy grid of kGrid^2 cells per direction; one pass over the vertices.
#pragma once

#include "core/vec.h"

#include <cstdint>
#include <optional>
#include <string>

namespace mebake::stream {

inline constexpr double kContactLevel = 0.01;
inline constexpr double kMinSupport = 0.1;
inline constexpr double kMargin = 1.5;

struct UpAxis {
    Vec3d up{0, 1, 0};
    double support = 0;     // the largest support ratio
    double runner_up = 0;   // the next largest
    bool detected = false;  // false: the default +Y
};

// From the spilled vertices [0, vertex_count) of <dir>/vertices.bin within the box.
UpAxis DetectUpAxis(const std::string& dir, uint64_t vertex_count, const Vec3d& bbox_min,
                    const Vec3d& bbox_max, size_t cache_bytes);

// "x", "-x", "y", "-y", "z", "-z" -> the unit vector; nullopt for anything else.
std::optional<Vec3d> ParseAxis(const std::string& name);
// The unit vector's name as ParseAxis reads it ("+y" etc. only for axis vectors).
std::string AxisName(const Vec3d& axis);

}  // namespace mebake::stream
