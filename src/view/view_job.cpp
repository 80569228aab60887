#include "view/view_job.h"

#include "core/error.h"
#include "core/log.h"
#include "io/byte_stream.h"
#include "view/web_assets.h"

#include <arpa/inet.h>
#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <httplib.h>
#include <netinet/in.h>
#include <pthread.h>
#include <sys/socket.h>
#include <thread>
#include <unistd.h>

namespace mebake::view {

namespace fs = std::filesystem;

namespace {

// Writes the viewer data into <bake>/web unless it is already current.
std::string PrepareData(const ViewOptions& o, const std::string& bake) {
    const std::string data = (fs::path(bake) / "web").string();
    if (!o.rewrite && WebDataCurrent(bake, data)) {
        spdlog::info("viewer data: {} (current)", data);
        return data;
    }
    const WebDataStats st = WriteWebData(bake, data, o.data);
    spdlog::info("viewer data: {} ({} triangles in {} chunks, {} bytes; {} atlas page{})", data,
                 st.triangles, st.chunks, st.mesh_bytes, st.pages, st.pages == 1 ? "" : "s");
    return data;
}

// Binding first with plain sockets gives the reason (errno) when the port is taken; the
// server then binds the same address (both with SO_REUSEADDR).
void CheckPortFree(int port) {
    if (port < 0 || port > 65535)
        UsageError("--port {}: expected 0 to 65535", port);
    if (port == 0)
        return;
    const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
    if (fd < 0)
        IoError({"socket"}, "{}", std::strerror(errno));
    int yes = 1;
    ::setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(uint16_t(port));
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    const int r = ::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a);
    const int err = errno;
    ::close(fd);
    if (r != 0)
        IoError({fmt::format("127.0.0.1:{}", port)}, "cannot listen there: {}{}",
                std::strerror(err),
                err == EADDRINUSE ? " (another server runs there; pick another --port, or "
                                    "--port 0 for any free one)"
                                  : "");
}

void AddRoutes(httplib::Server& svr, const std::string& data) {
    if (!svr.set_mount_point("/data", data))
        IoError({data}, "cannot serve this directory");
    svr.set_file_extension_and_mimetype_mapping("glb", "model/gltf-binary");
    svr.set_file_extension_and_mimetype_mapping("half", "application/octet-stream");
    svr.Get(R"(/(.*))", [](const httplib::Request& req, httplib::Response& res) {
        std::string path = req.matches[1];
        if (path == "favicon.ico") {
            res.status = 204;
            return;
        }
        if (path.empty())
            path = "index.html";
        for (const WebAsset& a : WebAssets())
            if (a.path == path) {
                res.set_content(a.data.data(), a.data.size(), std::string(a.mime).c_str());
                return;
            }
        res.status = 404;
        res.set_content("not found\n", "text/plain");
    });
}

}  // namespace

void RunView(const ViewOptions& o) {
    // SIGINT/SIGTERM are blocked in every thread (worker pools started later inherit the
    // mask) and taken by one waiting thread: before the server listens it ends the process
    // (files are renamed into place whole, so none is left half-written), after it stops
    // the server. No work in a signal handler.
    sigset_t stop_signals, old;
    sigemptyset(&stop_signals);
    sigaddset(&stop_signals, SIGINT);
    sigaddset(&stop_signals, SIGTERM);
    pthread_sigmask(SIG_BLOCK, &stop_signals, &old);
    httplib::Server svr;
    std::atomic<bool> serving{false}, done{false};
    std::thread waiter([&] {
        int sig = 0;
        sigwait(&stop_signals, &sig);
        if (done)
            return;
        if (!serving) {
            std::fprintf(stderr, "mebake: interrupted\n");
            std::_Exit(130);
        }
        svr.stop();
    });
    // Wakes the waiter so it can be joined, whatever happens below.
    struct Join {
        std::thread& t;
        std::atomic<bool>& done;
        sigset_t old;
        ~Join() {
            done = true;
            pthread_kill(t.native_handle(), SIGTERM);
            t.join();
            pthread_sigmask(SIG_SETMASK, &old, nullptr);
        }
    } join{waiter, done, old};

    const std::string bake = ResolveBakeDirectory(o.dir);
    CheckPortFree(o.port);
    const std::string data = PrepareData(o, bake);
    AddRoutes(svr, data);
    int port = o.port;
    if (port == 0)
        port = svr.bind_to_any_port("127.0.0.1");
    else if (!svr.bind_to_port("127.0.0.1", port))
        port = -1;
    if (port <= 0)
        IoError({fmt::format("127.0.0.1:{}", o.port)}, "cannot listen there");
    serving = true;
    std::printf("serving %s at http://127.0.0.1:%d/ (Ctrl-C stops)\n", bake.c_str(), port);
    std::fflush(stdout);
    svr.listen_after_bind();
    spdlog::info("stopped");
}

void ExportWeb(const std::string& dir, const std::string& out, bool force,
               const WebDataOptions& data_opt) {
    const std::string bake = ResolveBakeDirectory(dir);
    if (fs::exists(out) && !fs::is_empty(out) && !force)
        UsageError("{} exists and is not empty; use --force to write into it", out);
    const WebDataStats st = WriteWebData(bake, (fs::path(out) / "data").string(), data_opt);
    for (const WebAsset& a : WebAssets()) {
        const fs::path p = fs::path(out) / std::string(a.path);
        fs::create_directories(p.parent_path());
        auto s = io::OutputStream::Open(p.string());
        s->Write(a.data);
        s->Commit();
    }
    spdlog::info("web page: {}/index.html ({} triangles in {} chunks; serve the directory with "
                 "any web server, e.g. `python3 -m http.server -d {}`)",
                 out, st.triangles, st.chunks, out);
}

}  // namespace mebake::view
