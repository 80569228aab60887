// `mebake view` (and `export --web`) as plain functions over option structs.
#pragma once

#include <cstdint>
#include <string>

namespace mebake::app {

struct ViewCommand {
    std::string dir;  // bake directory or output directory of `mebake bake`
    int port = 8080;
    bool no_meshopt = false;
    uint64_t chunk_triangles = 65536;
    bool rewrite = false;
    int threads = 0;
};
int RunView(const ViewCommand& c);

// `mebake export DIR --web OUT`: the page and its data as static files.
int RunExportWeb(const std::string& dir, const std::string& out, bool force, bool no_meshopt,
                 int threads);

}  // namespace mebake::app
