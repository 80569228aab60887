// FieldPool (the coefficient pools in a mapped file): a solve whose fields live in the pool,
// evicted at every unpin, gives the same bits as one with the fields in memory, on any
// thread count; a checkpoint written from pooled fields resumes into a pool, a field at a
// time, with the same bits; evicted fields really leave resident memory; a field subdivided after pooling
// moves back into memory with its values.
#include "solve/field_pool.h"

#include "core/parallel.h"
#include "core/units.h"
#include "patch_fixture.h"
#include "solve/checkpoint.h"
#include "solve/solver.h"
#include "solve/visibility.h"

#include <gtest/gtest.h>

#include <filesystem>

namespace mebake::solve {
namespace {

namespace fs = std::filesystem;
using testing::FieldBits;
using testing::FreshDir;
using testing::SameBits;

SolveOptions Options() {
    SolveOptions opt;
    opt.settings.order = 1;
    opt.settings.max_bounces = 4;
    opt.settings.stop_fraction = 1e-6;
    return opt;
}

TEST(MappedFieldPool, SolveInThePoolGivesTheSameBits) {
    const testing::LitBox box(3, 32);
    Solver ram(box.scene, box.charts, box.vis, Options());
    ram.Run();
    const std::vector<float> want = FieldBits(ram);
    ASSERT_GE(ram.stats().batches, 2);

    for (int threads : {1, 2}) {
        ThreadLimit limit(threads);
        const std::string dir = FreshDir("fieldpool");
        FieldPool pool(dir, box.charts.size(), 0);  // every unpin evicts
        Solver mapped(box.scene, box.charts, box.vis, Options());
        mapped.SetFieldPool(&pool);
        mapped.Run();
        for (const auto& f : mapped.fields())
            EXPECT_TRUE(f.mapped());
        EXPECT_TRUE(SameBits(FieldBits(mapped), want)) << threads << " threads";
        EXPECT_EQ(mapped.stats().rays, ram.stats().rays);
        EXPECT_GT(pool.stats().evictions, 3u);
        EXPECT_EQ(pool.stats().resident_bytes, 0u) << "nothing pinned, budget 0";
        EXPECT_GT(pool.file_bytes(), 0u);
        fs::remove_all(dir);
    }
}

TEST(MappedFieldPool, CheckpointResumesIntoThePoolWithTheSameBits) {
    const testing::LitBox box(3, 32);
    Solver ram(box.scene, box.charts, box.vis, Options());
    ram.Run();
    const std::vector<float> want = FieldBits(ram);
    constexpr uint64_t kKey = 42;
    for (int stop_at : {0, 1}) {
        const std::string dir = FreshDir("fieldpool-ckpt");
        {
            FieldPool pool(dir + "/solve", box.charts.size(), 0);
            Solver first(box.scene, box.charts, box.vis, Options());
            first.SetFieldPool(&pool);
            testing::StopWithCheckpointAt(first, dir, kKey, stop_at);
            first.Run();
            ASSERT_EQ(first.stats().stop_reason, "interrupted");
        }
        // As `mebake solve --resume` does it: fields go to the pool one at a time.
        FieldPool pool(dir + "/solve", box.charts.size(), 0);
        Solver second(box.scene, box.charts, box.vis, Options());
        second.SetFieldPool(&pool);
        size_t sunk = 0;
        auto cp = LoadCheckpoint(dir, kKey, 1, 9, box.charts.size(),
                                 [&](uint32_t c, ChartField&& f) {
                                     EXPECT_EQ(c, sunk++);
                                     second.RestoreField(c, std::move(f));
                                 });
        ASSERT_TRUE(cp.has_value());
        EXPECT_TRUE(cp->fields.empty());
        EXPECT_EQ(sunk, box.charts.size()) << "the chosen checkpoint only";
        second.Restore(cp->reference, cp->next_batch, cp->stats);
        for (const auto& f : second.fields())
            EXPECT_TRUE(f.mapped());
        second.Run();
        EXPECT_TRUE(SameBits(FieldBits(second), want)) << "stopped before batch " << stop_at;
        EXPECT_EQ(second.stats().batches, ram.stats().batches);
        fs::remove_all(dir);
    }
}

TEST(MappedFieldPool, EvictedFieldsLeaveResidentMemory) {
    // 24 fields of ~2 MB each (order 2, 9 blocks: 664 bytes per node).
    constexpr size_t kCharts = 24;
    std::vector<ChartField> fields;
    for (size_t c = 0; c < kCharts; ++c) {
        ChartField f(2, 9);
        for (size_t n = 0; f.node_count() < 3000; ++n)
            if (f.node(n).leaf())
                f.Subdivide(n);
        f.Pull();
        fields.push_back(std::move(f));
    }
    const std::string dir = FreshDir("fieldpool-rss");
    FieldPool pool(dir, kCharts, 4 << 20);
    for (uint32_t c = 0; c < kCharts; ++c)
        pool.Store(c, &fields[c]);
    pool.Map(&fields);
    const uint64_t before = CurrentRssBytes();
    double sum = 0;
    for (auto& f : fields) {
        const RegionPin pin = f.Pin();
        for (size_t n = 0; n < f.node_count(); ++n)
            f.unshot(n)[0] += 1.f, sum += f.value(n)[0];
    }
    EXPECT_EQ(sum, 0);
    EXPECT_LT(CurrentRssBytes(), before + 12 * 1000 * 1000)
        << "at most the 4 MB budget and one field beyond it stay resident";
    EXPECT_GT(pool.stats().peak_resident_bytes, 4u << 20);
    // Dropped dirty pages were kept by the file: every write is still there.
    for (auto& f : fields) {
        const RegionPin pin = f.Pin();
        for (size_t n = 0; n < f.node_count(); ++n)
            ASSERT_EQ(f.unshot(n)[0], 1.f);
    }
    // Subdividing a pooled field moves it back into memory with its values.
    ChartField& f = fields[0];
    const size_t leaf = f.node_count() - 1;
    ASSERT_TRUE(f.node(leaf).leaf());
    const int32_t kid = f.Subdivide(leaf);
    EXPECT_FALSE(f.mapped());
    EXPECT_EQ(f.unshot(leaf)[0], 1.f);
    EXPECT_EQ(f.unshot(size_t(kid))[0], 1.f) << "a constant restricts to itself";
    fs::remove_all(dir);
}

}  // namespace
}  // namespace mebake::solve
