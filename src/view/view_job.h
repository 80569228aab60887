// `mebake view` and `mebake export --web` as library calls.
//
// view: a small HTTP server on 127.0.0.1 (cpp-httplib, docs/dependencies.md) serving the
// embedded page (web_assets.h) at / and the bake's viewer data (web_data.h) at /data/.
// The data lives in <bake>/web/ and is written on first use, and again whenever the
// solution is newer than it. SIGINT/SIGTERM stop the server (exit 0).
// export --web: the page and the data as static files in one directory.
#pragma once

#include "view/web_data.h"

#include <functional>
#include <string>

namespace mebake::view {

struct ViewOptions {
    std::string dir;  // bake directory, or an output directory holding scene.mebake
    int port = 8080;  // 0: any free port
    WebDataOptions data;
    bool rewrite = false;  // write the viewer data even when current
};

// Serves until SIGINT or SIGTERM. Prints "serving <dir> at http://127.0.0.1:PORT/" on
// stdout once listening. Throws Error(Usage) for a directory that is not a bake, an
// unsolved bake, or a port that cannot be bound.
void RunView(const ViewOptions& options);

// Writes index.html, the modules, three.js and data/ into `out` (created). Throws
// Error(Usage) when `out` exists and is not empty, unless force.
void ExportWeb(const std::string& dir, const std::string& out, bool force,
               const WebDataOptions& data = {});

}  // namespace mebake::view
