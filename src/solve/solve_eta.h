// Time left in the Southwell batches of a solve (docs/method.md, "Progress and ETA").
//
// The work left is estimated from the unshot power, which the solver measures at the
// start of every batch: after the first shot it falls about geometrically (each batch
// shoots the charts holding most of it, and surfaces send back only a share), so the decay
// per batch seen so far, r = (f_b / f_1)^(1 / (b - 1)), says how many batches it takes to
// fall below the stop fraction (capped by the bounce limit); priors stand in until it is
// measured. Batches cost about the same; the time left is the batches left times the mean
// cost of the batches after the first seen so far (the first one's until there is one),
// less the share of the current batch's gathers already done.
#pragma once

#include <optional>

namespace mebake::solve {

class SolveEta {
public:
    SolveEta(double stop_fraction, int max_bounces)
        : stop_(stop_fraction), max_bounces_(max_bounces) {}

    // At the start of batch `batch` (seconds since the batches started), with the unshot
    // fraction the solver measured there.
    void BatchStart(int batch, double unshot, double seconds);
    // Estimated batches in all (>= the current one + 1).
    int EstimatedBatches() const { return estimated_batches_; }
    // Share of the batches' work done and seconds left, `within` the current batch's
    // gathers done (0..1), at `seconds` since the batches started.
    double Fraction(double within, double seconds) const;
    std::optional<double> Eta(double within, double seconds) const;

private:
    double stop_;
    int max_bounces_;
    int first_batch_ = -1, batch_ = -1;
    int ref_batch_ = -1;      // first batch start after the first shot, and its unshot
    double ref_unshot_ = 1, batch_started_ = 0;
    double first_seconds_ = 0;  // cost of the first batch seen
    double later_seconds_ = 0;  // summed cost of the batches after it
    int later_count_ = 0;
    int estimated_batches_ = 1;
};

}  // namespace mebake::solve
