// Places a flat chart in the unit square by a rotation, a uniform scale and a translation
// (a similarity: no shear, no anisotropic scale, no mirror, so a near-isometric map stays
// near-isometric). The rotation is found with rotating calipers on the convex hull
// (Toussaint, "Solving geometric problems with the rotating calipers", 1983).
#pragma once

#include "core/vec.h"

#include <span>
#include <vector>

namespace mebake::stream {

enum class SquareFitObjective {
    // Minimize the longer side of the bounding rectangle: the largest uniform scale that
    // fits the square, hence the smallest virtual part. The default.
    kMinLongerSide,
    // Minimize the bounding rectangle's area (classic; one side is flush with a hull edge).
    kMinArea,
};

struct SquareFit {
    // q = R p, R the rotation with first row (cos_angle, sin_angle) and second row
    // (-sin_angle, cos_angle); then uv = q * scale + offset.
    double cos_angle = 1, sin_angle = 0;
    double scale = 1;
    Vec2d offset;
    double width = 0, height = 0;  // bounding rectangle of R p, input units

    Vec2d Apply(const Vec2d& p) const {
        const Vec2d q(cos_angle * p.x + sin_angle * p.y, -sin_angle * p.x + cos_angle * p.y);
        return q * scale + offset;
    }
};

// Convex hull, counter-clockwise, without repeated or collinear points (Andrew's monotone
// chain). Fewer than 3 points when the input is degenerate.
std::vector<Vec2d> ConvexHull(std::span<const Vec2d> points);

// The similarity mapping `points` into [margin, 1 - margin]^2 with the longer side of the
// rotated bounding rectangle spanning [margin, 1 - margin] and the shorter one centred.
// margin must be in [0, 0.5).
SquareFit FitUnitSquare(std::span<const Vec2d> points, double margin,
                        SquareFitObjective objective = SquareFitObjective::kMinLongerSide);

}  // namespace mebake::stream
