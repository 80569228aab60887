// Test helper: runs tests/e2e/validate_gltf.js (the Khronos glTF validator) on a file when
// node and the npm package gltf-validator are installed; nullopt when they are not (the
// caller skips). The package is looked up in $MEBAKE_GLTF_VALIDATOR (a node_modules
// directory), <build>/gltfv/node_modules and tests/e2e/node_modules; install it with
//   mkdir -p build/gltfv && (cd build/gltfv && npm install gltf-validator)
#pragma once

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <string>
#include <sys/wait.h>
#include <utility>
#include <vector>

namespace mebake::testing {

struct GltfValidation {
    int exit_code = 0;   // 0 valid, 1 errors
    std::string report;  // the script's JSON summary
};

inline std::optional<GltfValidation> ValidateGltf(const std::string& file) {
    namespace fs = std::filesystem;
    if (std::system("command -v node > /dev/null 2>&1") != 0)
        return std::nullopt;
    std::vector<std::string> dirs;
    if (const char* env = std::getenv("MEBAKE_GLTF_VALIDATOR"))
        dirs.push_back(env);
    const fs::path build = fs::path(MEBAKE_BINARY).parent_path().parent_path().parent_path();
    dirs.push_back((build / "gltfv" / "node_modules").string());
    dirs.push_back(std::string(MEBAKE_SOURCE_DIR) + "/tests/e2e/node_modules");
    std::string modules;
    for (const auto& d : dirs)
        if (fs::exists(fs::path(d) / "gltf-validator")) {
            modules = d;
            break;
        }
    if (modules.empty())
        return std::nullopt;
    const std::string cmd = "NODE_PATH='" + modules + "' node '" + MEBAKE_SOURCE_DIR +
                            "/tests/e2e/validate_gltf.js' '" + file + "' 2>&1";
    FILE* p = ::popen(cmd.c_str(), "r");
    if (!p)
        return std::nullopt;
    GltfValidation v;
    char buf[4096];
    for (size_t n; (n = std::fread(buf, 1, sizeof(buf), p)) > 0;)
        v.report.append(buf, n);
    const int status = ::pclose(p);
    v.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    if (v.exit_code == 77)
        return std::nullopt;
    return v;
}

}  // namespace mebake::testing
