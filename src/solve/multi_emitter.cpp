// L2 measures of the multi-emitter simplification (multi_emitter.h; seed 002, section 5).
#include "solve/multi_emitter.h"

#include "core/check.h"
#include "solve/basis.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <ctime>

namespace mebake::solve {

float GaussL2Error(int order, int n, const float* coeffs, int blocks, const float* values) {
    CHECK_LE(n, kMaxGauss);
    CHECK_LE(blocks, 64);
    std::array<float, kMaxGauss * kMaxGauss * 64> fit;
    EvalGauss(order, n, coeffs, blocks, fit.data());
    std::array<float, kMaxGauss * kMaxGauss * 64> diff;
    for (int k = 0; k < n * n * blocks; ++k)
        diff[size_t(k)] = fit[size_t(k)] - values[k];
    return GaussL2Norm(n, blocks, diff.data());
}

float GaussResidualMax(int order, int n, const float* coeffs, int blocks, const float* values) {
    CHECK_LE(n, kMaxGauss);
    CHECK_LE(blocks, 64);
    std::array<float, kMaxGauss * kMaxGauss * 64> fit;
    EvalGauss(order, n, coeffs, blocks, fit.data());
    float worst = 0;
    for (int k = 0; k < n * n * blocks; ++k)
        worst = std::max(worst, std::abs(fit[size_t(k)] - values[k]));
    return worst;
}

float GaussL2Norm(int n, int blocks, const float* values) {
    CHECK_LE(blocks, 64);
    std::array<double, 64> sum{};
    for (int p = 0; p < n * n; ++p) {
        double s, t, w;
        GaussPoint2D(n, p, &s, &t, &w);
        for (int b = 0; b < blocks; ++b)
            sum[size_t(b)] += w * double(values[p * blocks + b]) * values[p * blocks + b];
    }
    double worst = 0;
    for (int b = 0; b < blocks; ++b)
        worst = std::max(worst, sum[size_t(b)]);
    return float(std::sqrt(worst));
}

uint32_t KnownCode(std::span<const uint8_t> known) {
    uint32_t code = 0;
    if (known.size() <= 15) {
        for (size_t l = 0; l < known.size(); ++l)
            code |= uint32_t(known[l] == 2 ? 1 : known[l] == 3 ? 2 : 0) << (2 * l);
        return code;
    }
    code = 2166136261u;  // FNV-1a
    for (uint8_t k : known)
        code = (code ^ k) * 16777619u;
    return code | 0x80000000u;
}

double ThreadCpuSeconds() {
    timespec ts{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

}  // namespace mebake::solve
