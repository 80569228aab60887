// The vertex-coloured PLY that `mebake export --vertex-colors` writes, opened by MeshLab's
// own loader: meshlabserver (Debian `meshlab`, run under xvfb-run since it needs an OpenGL
// context) loads it and saves it again with vertex colours; the copy must hold the same
// vertices, faces and 8-bit colours. Skips when meshlabserver or xvfb-run are absent
// (scripts/test.sh installs them when it can).
#include "io/byte_stream.h"
#include "io/mesh_format.h"
#include "run.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <string>
#include <unistd.h>

namespace mebake {
namespace {

namespace fs = std::filesystem;

using e2e::Shell;

struct Collect : io::MeshSink {
    std::vector<Vec3f> position, color;
    std::vector<uint64_t> index;
    void Begin(const io::MeshHeader&) override {}
    void Vertices(const io::VertexBatch& b) override {
        position.insert(position.end(), b.position.begin(), b.position.end());
        color.insert(color.end(), b.color.begin(), b.color.end());
    }
    void Faces(const io::FaceBatch& b) override {
        index.insert(index.end(), b.index.begin(), b.index.end());
    }
    void End(const io::MeshSummary&) override {}
};

Collect Read(const std::string& path) {
    Collect c;
    auto in = io::InputStream::Open(path);
    io::ReadMesh(*in, io::MeshFormat::Ply, c);
    return c;
}

TEST(MeshLab, LoadsTheVertexColouredPly) {
    if (Shell("command -v meshlabserver > /dev/null && command -v xvfb-run > /dev/null") != 0)
        GTEST_SKIP() << "meshlabserver or xvfb-run is absent (Debian packages meshlab, xvfb)";
    const fs::path dir = fs::temp_directory_path() / ("mebake-meshlab-" + std::to_string(getpid()));
    fs::remove_all(dir);
    fs::create_directories(dir);
    const std::string mb = std::string("'") + MEBAKE_BINARY + "' -q ";
    const std::string bake = (dir / "t.mebake").string(), ours = (dir / "vc.ply").string(),
                      theirs = (dir / "ml.ply").string();
    const std::string mesh = std::string(MEBAKE_SOURCE_DIR) + "/data/samples/terrain.ply";
    ASSERT_EQ(Shell(mb + "ingest '" + mesh + "' -o '" + bake + "' --lightmap-resolution 128"), 0);
    ASSERT_EQ(Shell(mb + "solve '" + bake + "' --max-bounces 1"), 0);
    ASSERT_EQ(Shell(mb + "export '" + bake + "' --vertex-colors '" + ours + "'"), 0);
    ASSERT_EQ(Shell("cd '" + dir.string() + "' && xvfb-run -a meshlabserver -i '" + ours +
                    "' -o '" + theirs + "' -m vc > meshlab.log 2>&1"),
              0)
        << "meshlabserver failed; see " << dir / "meshlab.log";
    const Collect a = Read(ours), b = Read(theirs);
    ASSERT_GT(a.position.size(), 0u);
    ASSERT_EQ(a.position.size(), b.position.size());
    ASSERT_EQ(a.index, b.index);
    ASSERT_EQ(a.color.size(), a.position.size());
    ASSERT_EQ(b.color.size(), b.position.size()) << "MeshLab saw no vertex colours";
    size_t lit = 0;
    for (size_t v = 0; v < a.position.size(); ++v) {
        ASSERT_EQ(a.position[v].x, b.position[v].x) << "vertex " << v;
        for (int k = 0; k < 3; ++k)
            ASSERT_EQ(a.color[v][k], b.color[v][k]) << "vertex " << v << " channel " << k;
        lit += a.color[v].x + a.color[v].y + a.color[v].z > 0;
    }
    EXPECT_GT(lit, a.position.size() / 2) << "most vertices should be lit";
    fs::remove_all(dir);
}

}  // namespace
}  // namespace mebake
