#include "solve/solve_eta.h"

#include <algorithm>
#include <cmath>

namespace mebake::solve {

namespace {
// Decay per batch assumed until two batches have been measured (about the albedo of a
// scanned object with its first, all-chart batch).
constexpr double kDefaultDecay = 0.35;
}  // namespace

void SolveEta::BatchStart(int batch, double unshot, double seconds) {
    if (batch_ >= 0) {
        const double cost = seconds - batch_started_;
        if (batch_ == first_batch_)
            first_seconds_ = cost;
        else {
            later_seconds_ += cost;
            ++later_count_;
        }
    }
    if (first_batch_ < 0) {
        first_batch_ = batch;
        first_unshot_ = batch == 0 ? 1.0 : unshot;
    }
    batch_ = batch;
    batch_started_ = seconds;
    double decay = kDefaultDecay;
    const int steps = batch - (first_batch_ == 0 ? 0 : first_batch_);
    if (steps >= 1 && unshot > 0 && first_unshot_ > 0)
        decay = std::clamp(std::pow(unshot / first_unshot_, 1.0 / steps), 0.01, 0.99);
    int left = 1;
    if (unshot > stop_ && unshot > 0)
        left = std::max(1, int(std::ceil(std::log(stop_ / unshot) / std::log(decay))));
    else
        left = 0;  // this batch start is the last check: it stops here
    estimated_batches_ = std::min(max_bounces_, batch + left);
    estimated_batches_ = std::max(estimated_batches_, batch);
}

std::optional<double> SolveEta::Eta(double within, double seconds) const {
    if (batch_ < 0)
        return std::nullopt;
    const double per_batch = later_count_ > 0 ? later_seconds_ / later_count_ : first_seconds_;
    const double current = seconds - batch_started_;
    if (per_batch <= 0) {
        // Only the first batch is under way: extrapolate it from the share gathered.
        if (within <= 0)
            return std::nullopt;
        const double first_total = current / within;
        return first_total - current + first_total * (estimated_batches_ - batch_ - 1);
    }
    const int after = std::max(0, estimated_batches_ - batch_ - 1);
    const double this_left = std::max(0.0, (1 - within) * per_batch);
    return this_left + after * per_batch;
}

double SolveEta::Fraction(double within, double seconds) const {
    const auto eta = Eta(within, seconds);
    if (!eta)
        return estimated_batches_ > 0 ? double(std::max(batch_, 0)) / estimated_batches_ : 0;
    return seconds + *eta > 0 ? seconds / (seconds + *eta) : 0;
}

}  // namespace mebake::solve
