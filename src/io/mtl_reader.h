// Wavefront .mtl material libraries: the parts a diffuse baker uses.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "core/vec.h"

namespace mebake::io {

struct MtlMaterial {
    std::string name;
    std::optional<Vec3f> kd;  // diffuse reflectance
    std::optional<Vec3f> ka;  // ambient (some files use it for emitters)
    std::optional<Vec3f> ke;  // emission
    std::optional<float> ns;  // specular exponent
    std::optional<Vec3f> ks;  // specular reflectance
};

// Parses a .mtl file. Unknown statements are ignored; malformed numbers are an input
// error naming the file and line. Throws Error(Io) if the file cannot be read.
std::vector<MtlMaterial> ReadMtl(const std::string& path);

}  // namespace mebake::io
