// `mebake view` and `mebake export --web`: option checks, then one call into view/.
#include "app/view_commands.h"
#include "core/error.h"
#include "core/parallel.h"
#include "view/view_job.h"

namespace mebake::app {

int RunView(const ViewCommand& c) {
    ThreadLimit limit(c.threads);
    if (c.chunk_triangles < 1)
        UsageError("--chunk {}: expected at least 1 triangle", c.chunk_triangles);
    view::ViewOptions o;
    o.dir = c.dir;
    o.port = c.port;
    o.data.meshopt = !c.no_meshopt;
    o.data.chunk_triangles = c.chunk_triangles;
    o.rewrite = c.rewrite || c.no_meshopt || c.chunk_triangles != 65536;
    view::RunView(o);
    return 0;
}

int RunExportWeb(const std::string& dir, const std::string& out, bool force, bool no_meshopt,
                 int threads) {
    ThreadLimit limit(threads);
    view::WebDataOptions o;
    o.meshopt = !no_meshopt;
    view::ExportWeb(dir, out, force, o);
    return 0;
}

}  // namespace mebake::app
