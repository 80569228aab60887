// SolveEta (solve/solve_eta.h): the batches left from the decay of the unshot power, and the
// time left from the cost of the batches seen so far.
#include "solve/solve_eta.h"

#include <gtest/gtest.h>

using mebake::solve::SolveEta;

// Unshot power that halves every batch, 10 s per batch after a first one of 30 s.
TEST(SolveEta, GeometricDecayAndSteadyBatchesGiveTheExactTimeLeft) {
    const double stop = 1e-3;
    SolveEta eta(stop, 64);
    // f_b = 0.5^b: the first b with f_b < 1e-3 is 10, where the solver stops.
    double t = 0;
    eta.BatchStart(0, 1.0, t);
    t += 30;
    eta.BatchStart(1, 0.5, t);
    t += 10;
    eta.BatchStart(2, 0.25, t);
    EXPECT_EQ(eta.EstimatedBatches(), 10);
    // At the start of batch 2: batches 2..9 left, 10 s each.
    ASSERT_TRUE(eta.Eta(0, t).has_value());
    EXPECT_NEAR(*eta.Eta(0, t), 80, 1e-9);
    // Half way through batch 2.
    EXPECT_NEAR(*eta.Eta(0.5, t + 5), 75, 1e-9);
    EXPECT_NEAR(eta.Fraction(0.5, t + 5), (t + 5) / (t + 5 + 75), 1e-12);
}

TEST(SolveEta, TheBounceLimitCapsTheBatches) {
    SolveEta eta(1e-6, 4);
    eta.BatchStart(0, 1.0, 0);
    eta.BatchStart(1, 0.5, 10);
    EXPECT_EQ(eta.EstimatedBatches(), 4);
    EXPECT_NEAR(*eta.Eta(0, 10), 3 * 10, 1e-9);  // batches 1, 2, 3 at the first one's cost
}

TEST(SolveEta, FirstBatchIsExtrapolatedFromItsGathers) {
    SolveEta eta(1e-3, 16);
    eta.BatchStart(0, 1.0, 0);
    EXPECT_FALSE(eta.Eta(0, 0).has_value());  // nothing to go by yet
    // Priors: 3 % left after the first shot, then 0.15 per batch: 0.03, 0.0045, 0.000675,
    // so the solver stops at the start of batch 3.
    ASSERT_EQ(eta.EstimatedBatches(), 3);
    // A quarter of the first batch in 5 s: 15 s more for it, then two more at 20 s each.
    EXPECT_NEAR(*eta.Eta(0.25, 5), 15 + 20.0 * 2, 1e-9);
}

TEST(SolveEta, AResumedSolveMeasuresItsDecayFromWhereItStarted) {
    SolveEta eta(1e-3, 64);
    eta.BatchStart(5, 0.1, 0);  // resumed at batch 5
    eta.BatchStart(6, 0.05, 10);
    // Halving from 0.05: 0.05 * 0.5^k < 1e-3 first at k = 6.
    EXPECT_EQ(eta.EstimatedBatches(), 12);
}
