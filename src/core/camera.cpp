#include "core/camera.h"

#include "core/error.h"

#include <cmath>
#include <numbers>

namespace mebake {

PinholeRays::PinholeRays(const Camera& cam) : cam_(cam) {
    if (cam.width < 1 || cam.height < 1 || cam.width > 16384 || cam.height > 16384)
        UsageError("--size {}x{}: each side must be 1 to 16384 pixels", cam.width, cam.height);
    if (!(cam.fov > 0 && cam.fov < 180))
        UsageError("--fov {}: expected (0, 180) degrees", cam.fov);
    forward_ = Normalize(cam.target - cam.eye);
    right_ = Normalize(Cross(forward_, cam.up));
    if (!(Dot(forward_, forward_) > 0) || !(Dot(right_, right_) > 0))
        UsageError("camera: eye and target must differ and up must not be parallel to the view");
    up_ = Cross(right_, forward_);
    tan_half_ = std::tan(cam.fov * 0.5 * std::numbers::pi / 180);
    aspect_ = double(cam.width) / cam.height;
}

Vec3f PinholeRays::Direction(int px, int py, int sx, int sy, int k) const {
    const double x = (px + (sx + 0.5) / k) / cam_.width * 2 - 1;
    const double y = 1 - (double(py) + (sy + 0.5) / k) / cam_.height * 2;
    const Vec3d d = forward_ + right_ * (x * tan_half_ * aspect_) + up_ * (y * tan_half_);
    return Vec3f(Normalize(d));
}

}  // namespace mebake
