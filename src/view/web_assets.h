// The viewer's page (web/: HTML, JS modules, GLSL) and the parts of three.js it imports,
// embedded into the binary at build time (cmake/EmbedFiles.cmake), served by `mebake
// view` and written by `mebake export --web`. No network at run time.
#pragma once

#include <span>
#include <string_view>

namespace mebake::view {

struct WebAsset {
    std::string_view path;  // URL path without the leading '/', e.g. "index.html"
    std::string_view mime;
    std::string_view data;
};

std::span<const WebAsset> WebAssets();

}  // namespace mebake::view
