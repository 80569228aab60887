#include "stream/ingest_job.h"

#include "core/checksum.h"
#include "core/error.h"
#include "io/mesh_format.h"
#include "stream/up_axis.h"

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <csignal>
#include <fcntl.h>
#include <fmt/format.h>
#include <memory>
#include <sys/stat.h>
#include <thread>
#include <unistd.h>

namespace mebake::stream {

namespace {

bool IsRegularFile(const std::string& path) {
    struct stat st {};
    return path != "-" && ::stat(path.c_str(), &st) == 0 && S_ISREG(st.st_mode);
}

// Throws Error(Usage) unless `path` (a file, or all of stdin) has the recorded identity.
void CheckSameInput(const std::string& path, const stream::InputRecord& rec,
                    const std::string& dir) {
    uint64_t size = 0;
    uint32_t crc = 0;
    stream::HashFile(path, &size, &crc);
    if (size != rec.file_size || crc != rec.crc32)
        UsageError("{} changed since it was ingested into {} (size {} -> {}, CRC-32 {:08x} -> "
                   "{:08x}); pass --force to start over with the new input",
                   path == "-" ? "stdin" : path, dir, rec.file_size, size, rec.crc32, crc);
}

// Stdin passed through a pipe to the ingest on fd 0 by a thread that hashes it on the
// way, so the manifest can record the identity of what was read. Finish() drains what
// the reader left (the identity covers all of stdin) and restores fd 0.
class StdinTee {
public:
    StdinTee() {
        int fds[2];
        orig_ = ::dup(0);
        if (orig_ < 0 || ::pipe(fds) != 0)
            IoError({"<stdin>"}, "cannot set up a pipe: {}", ErrnoString(errno));
        old_pipe_ = std::signal(SIGPIPE, SIG_IGN);  // the reader may stop early
        ::dup2(fds[0], 0);
        ::close(fds[0]);
        state_ = std::make_shared<State>();
        thread_ = std::thread([state = state_, in = orig_, out = fds[1]] {
            std::vector<uint8_t> buf(size_t(1) << 20);
            bool forward = true;
            for (;;) {
                ssize_t n = ::read(in, buf.data(), buf.size());
                if (n < 0 && errno == EINTR)
                    continue;
                if (n <= 0) {
                    state->failed = n < 0;
                    break;
                }
                state->crc = Crc32(buf.data(), size_t(n), state->crc);
                state->size += uint64_t(n);
                for (ssize_t done = 0; forward && done < n;) {
                    ssize_t w = ::write(out, buf.data() + done, size_t(n - done));
                    if (w < 0 && errno == EINTR)
                        continue;
                    if (w < 0)
                        forward = false;  // the reader is gone: keep hashing
                    else
                        done += w;
                }
                if (!forward && state->abandon)
                    break;
            }
            ::close(out);
        });
    }
    ~StdinTee() {
        if (thread_.joinable()) {
            // Error path: stop feeding the reader; the thread stops at its next read.
            state_->abandon = true;
            CloseReader();
            thread_.detach();
        }
    }
    // False when reading stdin failed (the identity is then not recorded).
    bool Finish(uint64_t* size, uint32_t* crc) {
        CloseReader();
        thread_.join();
        ::dup2(orig_, 0);
        ::close(orig_);
        std::signal(SIGPIPE, old_pipe_);
        *size = state_->size;
        *crc = state_->crc;
        return !state_->failed;
    }

private:
    struct State {
        uint64_t size = 0;
        uint32_t crc = 0;
        bool failed = false;
        std::atomic<bool> abandon{false};
    };
    static void CloseReader() {
        int null = ::open("/dev/null", O_RDONLY | O_CLOEXEC);
        if (null >= 0) {
            ::dup2(null, 0);  // closes the pipe's read end: the pump's writes fail now
            ::close(null);
        }
    }
    int orig_ = -1;
    void (*old_pipe_)(int) = SIG_DFL;
    std::shared_ptr<State> state_;
    std::thread thread_;
};

}  // namespace

std::string CheckIngestReusable(const IngestOptions& c) {
    const std::string& dir = c.out_dir;
    if (!stream::IsBakeDirectory(dir))
        return "ingest did not finish";
    stream::Manifest m = stream::ReadManifest(dir);
    if (m.state != "ingested")
        return "ingest did not finish (state '" + m.state + "')";
    if (m.options.empty())
        return "the bake directory does not record its options";
    // --ground adds itself as the last input (its option is compared below).
    const size_t scans = m.inputs.size() - (m.ground ? 1 : 0);
    if (scans != c.inputs.size())
        UsageError("{} was ingested from {} inputs, not {}; pass --force to start over", dir,
                   scans, c.inputs.size());
    // Everything but stdin first: reading stdin consumes it, so it is checked last, when
    // the only outcomes left are "reuse" and "refuse".
    for (size_t k = 0; k < c.inputs.size(); ++k) {
        const auto& rec = m.inputs[k];
        const std::string& path = c.inputs[k];
        if (rec.path != path)
            UsageError("input {} was {} when {} was ingested; pass --force to start over", k + 1,
                       rec.path, dir);
        if (!rec.hashed)
            return path + " cannot be verified (its identity was not recorded)";
        if (path == "-")
            continue;
        if (!IsRegularFile(path))
            return path + " is not a regular file any more";
        CheckSameInput(path, rec, dir);
    }
    const auto want = IngestOptionsRecord(c);
    for (const auto& [key, value] : want) {
        const std::string& name = key;  // clang 14 cannot capture a structured binding
        auto it = std::find_if(m.options.begin(), m.options.end(),
                               [&](const auto& kv) { return kv.first == name; });
        // Directories from before the orientation pass and up detection: ingest again.
        if (it == m.options.end() && (key == "orient" || key == "up"))
            return "it was ingested before the " + key + " option existed";
        // Directories from before --ground / --merge-horizon-cells have neither.
        const std::string had = it != m.options.end() ? it->second
                                 : key == "ground"      ? "0"
                                 : key == "merge_horizon_cells" ? "0"
                                                                : "(none)";
        if (had != value)
            UsageError("{} was ingested with {} {}, this run asks for {}; pass --force to start "
                       "over",
                       dir, key, had, value);
    }
    for (size_t k = 0; k < c.inputs.size(); ++k)
        if (c.inputs[k] == "-")
            CheckSameInput("-", m.inputs[k], dir);
    return "";
}
std::vector<std::pair<std::string, std::string>> IngestOptionsRecord(const IngestOptions& opt) {
    return {{"format", opt.format ? std::string(io::FormatName(*opt.format)) : std::string()},
            {"lightmap_resolution", std::to_string(opt.lightmap_resolution)},
            {"max_distortion", fmt::format("{:.17g}", opt.max_distortion)},
            {"memory", std::to_string(opt.memory)},
            {"texel_size", fmt::format("{:.17g}", opt.texel_size)},
            {"orient", opt.orient ? "1" : "0"},
            {"merge_horizon_cells", opt.merge_horizon_cells ? "1" : "0"},
            {"up", opt.up ? AxisName(*opt.up) : "auto"}};
}

Manifest RunIngestJob(const IngestOptions& opt) {
    // Identities of the file inputs, taken before they are read, for resume checks.
    std::vector<InputRecord> ids(opt.inputs.size());
    std::unique_ptr<StdinTee> tee;
    for (size_t k = 0; k < opt.inputs.size(); ++k) {
        if (opt.inputs[k] == "-") {
            tee = std::make_unique<StdinTee>();
        } else if (IsRegularFile(opt.inputs[k])) {
            HashFile(opt.inputs[k], &ids[k].file_size, &ids[k].crc32);
            ids[k].hashed = true;
        }
    }
    Manifest m = Ingest(opt);
    for (size_t k = 0; k < opt.inputs.size(); ++k)
        if (opt.inputs[k] == "-")
            ids[k].hashed = tee->Finish(&ids[k].file_size, &ids[k].crc32);
    // A second manifest write adds what resume needs; killed before it, the directory
    // is taken as not ingested and ingest starts over.
    for (size_t k = 0; k < m.inputs.size() && k < ids.size(); ++k) {
        m.inputs[k].hashed = ids[k].hashed;
        m.inputs[k].file_size = ids[k].file_size;
        m.inputs[k].crc32 = ids[k].crc32;
    }
    m.options = IngestOptionsRecord(opt);
    WriteManifest(opt.out_dir, m);
    return m;
}

}  // namespace mebake::stream
