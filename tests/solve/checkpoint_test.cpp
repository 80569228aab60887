// Solver checkpoints in process: a solve stopped at a batch boundary, written, read back
// into a new solver and resumed ends bit-identical to an uninterrupted solve (also on
// another thread count); checkpointing at every boundary changes nothing; a checkpoint
// of other settings is refused, a damaged one is named.
#include "solve/checkpoint.h"

#include "core/error.h"
#include "core/parallel.h"
#include "patch_fixture.h"
#include "solve/polygon_light.h"
#include "solve/visibility.h"

#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>

namespace mebake::solve {
namespace {

namespace fs = std::filesystem;

// The open box of patch_fixture.h, five faces: several bounces of interreflection.
struct Box : testing::LitBox {
    Box() : LitBox(5, 16) {}
};

SolveOptions Options() {
    SolveOptions opt;
    opt.settings.order = 1;
    opt.settings.max_bounces = 6;
    opt.settings.stop_fraction = 1e-6;  // run every bounce
    opt.batch_fraction = 0.5;           // several batches per bounce
    return opt;
}

using testing::FieldBits;
using testing::FreshDir;
using testing::SameBits;

constexpr uint64_t kKey = 0x1234567890abcdefull;

TEST(Checkpoint, ResumedSolveIsBitIdentical) {
    Box box;
    Solver full(box.scene, box.charts, box.vis, Options());
    int boundaries = 0;
    full.SetBatchHook([&](int) {
        ++boundaries;
        return true;
    });
    full.Run();
    ASSERT_GE(full.stats().batches, 3) << "the scene should need several batches";
    EXPECT_EQ(boundaries, full.stats().batches + 1);  // after the direct pass and each batch
    const std::vector<float> want = FieldBits(full);

    // Without a hook: the same bits (the hook only observes).
    Solver plain(box.scene, box.charts, box.vis, Options());
    plain.Run();
    EXPECT_TRUE(SameBits(FieldBits(plain), want));

    for (int stop_at : {0, 1, 2}) {
        const std::string dir = FreshDir("checkpoint");
        Solver first(box.scene, box.charts, box.vis, Options());
        testing::StopWithCheckpointAt(first, dir, kKey, stop_at);
        first.Run();
        EXPECT_EQ(first.stats().stop_reason, "interrupted");
        ASSERT_TRUE(fs::exists(CheckpointPath(dir)));

        // Resumed on another thread count.
        ThreadLimit limit(1);
        auto cp = LoadCheckpoint(dir, kKey, 1, 9, box.charts.size());
        ASSERT_TRUE(cp.has_value());
        EXPECT_EQ(cp->next_batch, stop_at);
        Solver second(box.scene, box.charts, box.vis, Options());
        second.Restore(std::move(cp->fields), cp->reference, cp->next_batch, cp->stats);
        second.Run();
        EXPECT_TRUE(SameBits(FieldBits(second), want)) << "stopped before batch " << stop_at;
        EXPECT_EQ(second.stats().batches, full.stats().batches);
        EXPECT_EQ(second.stats().shots, full.stats().shots);
        EXPECT_EQ(second.stats().rays, full.stats().rays);
        EXPECT_EQ(second.stats().stop_reason, full.stats().stop_reason);
        fs::remove_all(fs::path(dir));
    }
}

// The unshot tail at the stop (SolverSettings::unshot_tail) takes the last batch's shot
// power from the checkpoint: resumed at any boundary, the same bits and the same gain.
TEST(Checkpoint, ResumedSolveWithTheUnshotTailIsBitIdentical) {
    Box box;
    SolveOptions opt = Options();
    opt.settings.max_bounces = 16;
    opt.settings.stop_fraction = 0.02;
    opt.settings.unshot_tail = true;
    Solver full(box.scene, box.charts, box.vis, opt);
    full.Run();
    ASSERT_EQ(full.stats().stop_reason, "converged");
    ASSERT_GT(full.stats().tail_gain, 0);
    ASSERT_GE(full.stats().batches, 2);
    const std::vector<float> want = FieldBits(full);
    for (int stop_at = 1; stop_at <= full.stats().batches; ++stop_at) {
        const std::string dir = FreshDir("checkpoint-tail");
        Solver first(box.scene, box.charts, box.vis, opt);
        testing::StopWithCheckpointAt(first, dir, kKey, stop_at);
        first.Run();
        ASSERT_EQ(first.stats().stop_reason, "interrupted");
        ThreadLimit limit(1);
        auto cp = LoadCheckpoint(dir, kKey, 1, 9, box.charts.size());
        ASSERT_TRUE(cp.has_value());
        Solver second(box.scene, box.charts, box.vis, opt);
        second.Restore(std::move(cp->fields), cp->reference, cp->next_batch, cp->stats);
        second.Run();
        EXPECT_TRUE(SameBits(FieldBits(second), want)) << "stopped before batch " << stop_at;
        EXPECT_EQ(second.stats().tail_gain, full.stats().tail_gain);
        fs::remove_all(fs::path(dir));
    }
}

TEST(Checkpoint, RotationKeepsThePreviousAndDamageIsNamed) {
    Box box;
    const std::string dir = FreshDir("checkpoint-rot");
    Solver s(box.scene, box.charts, box.vis, Options());
    s.SetBatchHook([&](int next) {
        WriteCheckpoint(dir, s, kKey);
        return next < 2;
    });
    s.Run();
    auto latest = ReadCheckpoint(CheckpointPath(dir), kKey, 1, 9, box.charts.size());
    auto prev = ReadCheckpoint(PrevCheckpointPath(dir), kKey, 1, 9, box.charts.size());
    EXPECT_EQ(latest.next_batch, 2);
    EXPECT_EQ(prev.next_batch, 1);

    // Other settings: refused, not mixed.
    try {
        LoadCheckpoint(dir, kKey + 1, 1, 9, box.charts.size());
        ADD_FAILURE() << "a checkpoint of other settings was accepted";
    } catch (const Error& e) {
        EXPECT_EQ(e.kind(), ErrorKind::Usage);
        EXPECT_NE(std::string(e.what()).find("--force"), std::string::npos) << e.what();
    }

    // A flipped byte in the newest: named, and the previous one is used.
    {
        const auto size = fs::file_size(CheckpointPath(dir));
        std::fstream f(CheckpointPath(dir), std::ios::in | std::ios::out | std::ios::binary);
        // From the middle on, the first non-zero byte: chunks are aligned, and the zero
        // padding between them is no data (it moved under the middle when the fields did).
        std::streamoff at = std::streamoff(size / 2);
        f.seekg(at);
        while (f.get() == 0)
            ++at;
        f.seekp(at);
        f.put('\x5a');
    }
    try {
        ReadCheckpoint(CheckpointPath(dir), kKey, 1, 9, box.charts.size());
        ADD_FAILURE() << "a damaged checkpoint was accepted";
    } catch (const Error& e) {
        EXPECT_EQ(e.kind(), ErrorKind::Corrupt);
        EXPECT_NE(std::string(e.what()).find("checkpoint.bin"), std::string::npos) << e.what();
    }
    auto cp = LoadCheckpoint(dir, kKey, 1, 9, box.charts.size());
    ASSERT_TRUE(cp.has_value());
    EXPECT_EQ(cp->next_batch, 1);
    EXPECT_EQ(cp->path, PrevCheckpointPath(dir));
    fs::remove_all(fs::path(dir).parent_path() / fs::path(dir).filename());
}

}  // namespace
}  // namespace mebake::solve
