// `mebake ingest` through the real binary: a mesh piped through stdin gives the same
// tiles as the same file named on the command line, and a tile with one flipped byte
// makes `mebake solve` fail with exit code 1 and a message naming that tile.
#include "run.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

namespace {

namespace fs = std::filesystem;

using mebake::e2e::Capture;

const std::string kBin = MEBAKE_BINARY;
const std::string kData = MEBAKE_SHARED_DATA;

std::string Slurp(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
}

TEST(IngestE2e, StdinGivesTheSameTilesAsTheFile) {
    const std::string scan = kData + "/scans/bun_zipper_res2.ply";
    if (!fs::exists(scan))
        GTEST_SKIP() << "no " << scan << " (../shared/data is absent)";
    const fs::path tmp = fs::temp_directory_path() / "mebake_ingest_e2e_stdin";
    fs::remove_all(tmp);
    const std::string a = (tmp / "file.mebake").string(), b = (tmp / "pipe.mebake").string();
    ASSERT_EQ(Capture(kBin + " ingest " + scan + " -o " + a + " 2>&1").code, 0);
    ASSERT_EQ(Capture("cat " + scan + " | " + kBin + " ingest - -o " + b + " 2>&1").code, 0);
    size_t tiles = 0;
    for (const auto& e : fs::directory_iterator(fs::path(a) / "tiles")) {
        EXPECT_EQ(Slurp(e.path()), Slurp(fs::path(b) / "tiles" / e.path().filename()))
            << e.path().filename();
        ++tiles;
    }
    EXPECT_GT(tiles, 1u);
    fs::remove_all(tmp);
}

TEST(IngestE2e, FlippedByteInATileIsReportedByName) {
    const std::string scan = kData + "/scans/bun_zipper_res3.ply";
    if (!fs::exists(scan))
        GTEST_SKIP() << "no " << scan << " (../shared/data is absent)";
    const fs::path tmp = fs::temp_directory_path() / "mebake_ingest_e2e_corrupt";
    fs::remove_all(tmp);
    const std::string dir = (tmp / "x.mebake").string();
    ASSERT_EQ(Capture(kBin + " ingest " + scan + " -o " + dir + " 2>&1").code, 0);
    const fs::path tile = fs::path(dir) / "tiles" / "c000001.tile";
    ASSERT_TRUE(fs::exists(tile));
    std::string bytes = Slurp(tile);
    bytes[70] = char(bytes[70] ^ 0x01);  // inside the first chunk (META), read by every stage
    { std::ofstream(tile, std::ios::binary | std::ios::trunc) << bytes; }
    const auto r = Capture(kBin + " solve " + dir + " --max-bounces 0 2>&1");
    EXPECT_EQ(r.code, 1) << r.out;
    EXPECT_NE(r.out.find(tile.string()), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("checksum"), std::string::npos) << r.out;
    fs::remove_all(tmp);
}

}  // namespace
