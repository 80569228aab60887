#include "solve/solve_eta.h"

#include <algorithm>
#include <cmath>

namespace mebake::solve {

namespace {
// Priors until the batches have shown their own (measured on bunny, igea and nefertiti with
// the default rig: after the first shot 0.6-5 % of its power is left unshot, and each later
// batch leaves 5-20 % of what it found).
constexpr double kFirstShotLeft = 0.03;
constexpr double kDefaultDecay = 0.15;

int BatchesToStop(double unshot, double decay, double stop) {
    if (!(unshot > stop))
        return 0;  // the solver stops at this batch's start
    return std::max(1, int(std::ceil(std::log(stop / unshot) / std::log(decay))));
}
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
    if (first_batch_ < 0)
        first_batch_ = batch;
    // The decay is measured from the first batch start after the first shot: the first
    // shot's own drop (the share of light the surfaces send back) is steeper than the rest.
    if (ref_batch_ < 0 && batch >= 1) {
        ref_batch_ = batch;
        ref_unshot_ = unshot;
    }
    batch_ = batch;
    batch_started_ = seconds;
    int left;
    if (batch == 0) {
        left = 1 + BatchesToStop(kFirstShotLeft, kDefaultDecay, stop_);
    } else {
        const int steps = batch - ref_batch_;
        double decay = kDefaultDecay;
        if (steps >= 1 && unshot > 0 && ref_unshot_ > 0)
            decay = std::clamp(std::pow(unshot / ref_unshot_, 1.0 / steps), 0.01, 0.99);
        left = BatchesToStop(unshot, decay, stop_);
    }
    estimated_batches_ = std::max(batch, std::min(max_bounces_, batch + left));
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
