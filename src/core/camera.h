// The pinhole camera shared by `mebake render` (output/render.h) and the path-traced
// reference picture (reference/reference_image.h): both must send the same primary rays
// through the same pixels so that their images can be compared pixel by pixel.
//
// Pixel (px, py) counts from the top-left; with k x k stratified rays per pixel, ray
// (sx, sy) goes through the point (px + (sx + 0.5) / k, py + (sy + 0.5) / k) of the image
// plane, which spans the vertical field of view `fov` and the width's aspect ratio.
#pragma once

#include "core/vec.h"

namespace mebake {

struct Camera {
    Vec3d eye{0, 0, 1}, target{0, 0, 0}, up{0, 1, 0};
    double fov = 50;  // vertical field of view, degrees, in (0, 180)
    int width = 800, height = 600;
};

// The camera's frame and primary-ray directions. The constructor throws Error(Usage) for a
// degenerate camera (eye = target, up parallel to the view, fov outside (0, 180), size
// outside [1, 16384]).
class PinholeRays {
public:
    explicit PinholeRays(const Camera& camera);

    // Unit direction of ray (sx, sy) of k x k through pixel (px, py).
    Vec3f Direction(int px, int py, int sx, int sy, int k) const;

    const Camera& camera() const { return cam_; }

private:
    Camera cam_;
    Vec3d forward_, right_, up_;
    double tan_half_ = 0, aspect_ = 1;
};

}  // namespace mebake
