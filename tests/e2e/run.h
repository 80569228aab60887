// Running commands from end-to-end tests: one shell line, its exit code and (optionally)
// its standard output. Shared by every test in tests/e2e that drives the real binaries.
#pragma once

#include <array>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <string>
#include <sys/wait.h>

namespace mebake::e2e {

struct RunResult {
    int code;         // exit code; -1 when the command did not exit normally
    std::string out;  // standard output (add 2>&1 to the line to merge stderr)
};

inline int ExitCode(int status) {
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

// Runs a shell command line; stdout and stderr go where the test's go.
inline int Shell(const std::string& line) {
    return ExitCode(std::system(line.c_str()));
}

// Runs a shell command line and captures its standard output.
inline RunResult Capture(const std::string& line) {
    RunResult r{-1, {}};
    FILE* p = popen(line.c_str(), "r");
    if (!p)
        return r;
    std::array<char, 4096> buf;
    size_t n;
    while ((n = fread(buf.data(), 1, buf.size(), p)) > 0)
        r.out.append(buf.data(), n);
    r.code = ExitCode(pclose(p));
    return r;
}

// `mebake ARGS` (the binary under test); ARGS is shell text, quote paths in it.
inline int Mebake(const std::string& args) {
    return Shell(std::string("'") + MEBAKE_BINARY + "' " + args);
}

// A whole file's bytes (empty if it cannot be read).
inline std::string ReadFile(const std::string& path) {
    std::ifstream f(path, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(f)), {});
}

// Ingests the sample rock (data/samples/rock.ply) with a 256-texel light map into bake.
inline int IngestSampleRock(const std::string& bake) {
    return Mebake("-q ingest '" + std::string(MEBAKE_SOURCE_DIR) + "/data/samples/rock.ply' -o '" +
                  bake + "' --lightmap-resolution 256");
}

}  // namespace mebake::e2e
