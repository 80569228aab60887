#include "stream/arap.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>

namespace mebake::stream {
namespace {

// The batch gives each lane the bits ArapTarget gives it alone, whatever its neighbours
// in the batch do: near-isometries (a few Newton steps), strong stretch and shrink (the
// clamp on both sides), reflections (q <= r: no Newton), pure similarities (r = 0), a
// zero Jacobian (q = 0: the identity), NaNs, and the authalic weights 0, 0.5 and 1.
TEST(ArapTarget, BatchGivesEachLaneTheBitsOfOneCall) {
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> unit(-1, 1);
    std::uniform_real_distribution<double> log_scale(-3, 3);
    std::uniform_int_distribution<int> kind(0, 7);
    const double nan = std::numeric_limits<double>::quiet_NaN();
    const double hi = std::sqrt(1.5), lo = 1 / hi;
    size_t checked = 0, stepped = 0;
    for (int round = 0; round < 4000; ++round) {
        ArapJacobians j;
        for (size_t l = 0; l < kArapBatch; ++l) {
            double a = 1 + 0.05 * unit(rng), b = 0.05 * unit(rng), c = 0.05 * unit(rng),
                   d = 1 + 0.05 * unit(rng);
            switch (kind(rng)) {
            case 0: {  // stretched along one axis, shrunk along the other
                const double s = std::exp(log_scale(rng));
                a *= s;
                d /= s * std::exp(0.3 * unit(rng));
                break;
            }
            case 1:  // a reflection
                d = -d;
                break;
            case 2:  // a similarity: r = 0 exactly
                c = -b;
                d = a;
                break;
            case 3:
                a = b = c = d = 0;
                break;
            case 4:
                if (round % 50 == 0)
                    a = nan;
                break;
            case 5:  // anything
                a = 3 * unit(rng);
                b = 3 * unit(rng);
                c = 3 * unit(rng);
                d = 3 * unit(rng);
                break;
            default:
                break;
            }
            j.a[l] = a;
            j.b[l] = b;
            j.c[l] = c;
            j.d[l] = d;
        }
        for (const double w : {0.0, 0.5, 1.0}) {
            std::array<std::array<double, 4>, kArapBatch> got;
            ArapTargetBatch(j, w, lo, hi, &got);
            for (size_t l = 0; l < kArapBatch; ++l) {
                const std::array<double, 4> want = ArapTarget(j.a[l], j.b[l], j.c[l], j.d[l], w, lo, hi);
                ASSERT_EQ(std::memcmp(want.data(), got[l].data(), sizeof want), 0)
                    << "round " << round << " lane " << l << " w " << w << ": " << j.a[l] << " "
                    << j.b[l] << " " << j.c[l] << " " << j.d[l];
                ++checked;
                stepped += w > 0 && want != std::array<double, 4>{1, 0, 0, 1};
            }
        }
    }
    EXPECT_GT(stepped, checked / 3);
}

}  // namespace
}  // namespace mebake::stream
