// Progress as a user sees it on a terminal: `mebake bake` of a generated 1M-triangle scan
// runs in a tmux pane (typed with send-keys); the pane is captured while it runs, and lines
// with a percentage and an ETA must appear for ingest, the direct pass and the batches.
// Skipped, with a message, where tmux is not installed (scripts/install-deps.sh installs it).
#include "run.h"

#include <gtest/gtest.h>

#include <cctype>
#include <chrono>
#include <filesystem>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <unistd.h>

namespace fs = std::filesystem;
using namespace mebake::e2e;

namespace {

std::string Quote(const std::string& s) {
    return "'" + s + "'";
}

}  // namespace

TEST(ProgressTmux, LinesWithPercentAndEtaDuringIngestDirectAndBatches) {
    if (Shell("tmux -V > /dev/null 2>&1") != 0)
        GTEST_SKIP() << "tmux is not installed (scripts/install-deps.sh installs it)";
    // Per process: two checkouts' test runs on one machine must not share the directory
    // (one removed the other's tiles mid-bake).
    const fs::path tmp =
        fs::temp_directory_path() / ("mebake_progress_tmux_" + std::to_string(::getpid()));
    fs::remove_all(tmp);
    fs::create_directories(tmp);
    const std::string scan = (tmp / "scan.ply").string();
    ASSERT_EQ(
        Shell(Quote(MEBAKE_MKSCAN) + " --triangles 1000000 > " + Quote(scan) + " 2>/dev/null"), 0);

    const std::string session = "mebake_progress_" + std::to_string(::getpid());
    ASSERT_EQ(Shell("tmux new-session -d -s " + session + " -x 200 -y 50"), 0);
    struct Kill {
        std::string s;
        ~Kill() { Shell("tmux kill-session -t " + s + " 2>/dev/null"); }
    } kill{session};
    // Few bounces keep the test short. With the defaults alone the sphere's direct pass takes
    // 0.16 s on a quiet machine, too short to be drawn (a stage is first drawn after 0.25 s):
    // the ground plane (the sphere's shadow on it) and a tighter tolerance make it seconds.
    const std::string cmd = Quote(MEBAKE_BINARY) + " bake " + Quote(scan) + " -o " +
                            Quote((tmp / "out").string()) +
                            " --max-bounces 2 --ground --tolerance 0.005; echo MEBAKE_EXIT=$?";
    ASSERT_EQ(Shell("tmux send-keys -t " + session + " " + Quote(cmd) + " Enter"), 0);

    // A live line: "  <stage> [detail] 12.3% (...) elapsed 4.1s, ETA 20s".
    const std::regex live(
        R"(^\s+(spill|bricks|orient|charts|proxy|direct|solve|export|render)\b.*\d+\.\d%.*ETA \d)");
    std::set<std::string> seen;
    std::string screen;
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::minutes(20);
    bool exited = false;
    while (!exited && std::chrono::steady_clock::now() < deadline) {
        std::this_thread::sleep_for(std::chrono::milliseconds(200));
        const RunResult cap = Capture("tmux capture-pane -p -t " + session);
        ASSERT_EQ(cap.code, 0);
        screen = cap.out;
        std::istringstream in(screen);
        std::string line;
        while (std::getline(in, line)) {
            std::smatch m;
            if (std::regex_search(line, m, live))
                seen.insert(m[1]);
            // The status, not the typed command: a long checkout path wraps the command
            // line so that its "MEBAKE_EXIT=$?" can begin a screen line too.
            exited |= line.rfind("MEBAKE_EXIT=", 0) == 0 && line.size() > 12 &&
                      std::isdigit(static_cast<unsigned char>(line[12]));
        }
    }
    ASSERT_TRUE(exited) << "the bake did not finish in 20 minutes; last screen:\n" << screen;
    EXPECT_NE(screen.find("MEBAKE_EXIT=0"), std::string::npos) << screen;
    std::string stages;
    for (const auto& s : seen)
        stages += s + " ";
    EXPECT_TRUE(seen.count("charts") || seen.count("bricks") || seen.count("spill"))
        << "no ingest progress line; seen: " << stages;
    EXPECT_TRUE(seen.count("direct")) << "no direct-pass progress line; seen: " << stages;
    EXPECT_TRUE(seen.count("solve")) << "no batch progress line; seen: " << stages;
    fs::remove_all(tmp);
}
