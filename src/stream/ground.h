// The ground plane that `--ground` adds under a scan: most scanned objects stand on
// something, and a floor receives their shadow and bounces light back onto them.
#pragma once

#include "core/vec.h"
#include "io/mesh_stream.h"

namespace mebake::stream {

// Source name of the ground in the manifest's inputs (not a file).
inline constexpr const char* kGroundSource = "<ground>";
// Reflectance of the ground's default material: a neutral floor, darker than the scans'
// default 0.7 so the object stands out.
inline constexpr float kGroundAlbedo = 0.4f;

// Writes to `sink` a square grid in the plane across `up` (an axis direction, up_axis.h) at
// the box's floor along it, centred under the box, of side 3x the box's larger extent across
// up (room for a shadow cast from 40 degrees above the horizon), facing up. A grid rather
// than two triangles so that the charts of the ground stay small next to the object's.
void WriteGroundPlane(const Vec3d& bbox_min, const Vec3d& bbox_max, const Vec3d& up,
                      io::MeshSink& sink);
// Its area (the light-map texel size is chosen from the scans' area alone).
double GroundPlaneArea(const Vec3d& bbox_min, const Vec3d& bbox_max, const Vec3d& up);

}  // namespace mebake::stream
