#include "solve/link_refine.h"

#include "solve/basis.h"
#include "solve/field.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace mebake::solve {

double LinkIrradianceBound(double db_max, double area, double gap) {
    // |E| <= B_max x (projected solid angle) / pi; the solid angle of a region within the
    // receiver's half-space is at most 2 pi, and at most A / d^2 when d > 0.
    const double solid = gap > 0 ? std::min(2 * std::numbers::pi, area / (gap * gap))
                                 : 2 * std::numbers::pi;
    return db_max * solid / std::numbers::pi;
}

double NodeIrradiance(const ChartField& field, size_t node) {
    // c_00 of each block is the block's mean over the node (basis.h).
    const int n = NumCoeffs(field.order());
    const float* v = field.value(node);
    double sum = 0;
    if (field.blocks() == 9) {
        for (int c = 0; c < 3; ++c) {
            const double x = v[(3 * c) * n], y = v[(3 * c + 1) * n], z = v[(3 * c + 2) * n];
            sum += std::sqrt(x * x + y * y + z * z);
        }
    } else {
        for (int c = 0; c < field.blocks(); ++c)
            sum += std::max(0.f, v[c * n]);
    }
    return sum / 3;
}

LinkTolerance::LinkTolerance(const ChartField& field, double scale, double floor_irradiance) {
    if (scale <= 0)
        return;
    allowed_.resize(field.node_count());
    for (size_t n = 0; n < allowed_.size(); ++n)
        allowed_[n] = float(scale * std::max(NodeIrradiance(field, n), floor_irradiance));
}

}  // namespace mebake::solve
