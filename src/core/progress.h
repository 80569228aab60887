// Progress of long stages on stderr: percentage, rate, elapsed time and time left.
//
// One reporter for every stage (ingest passes, the solve, export, render, reference).
// Three forms, chosen once per process (SetProgressMode):
//   tty   one line per stage redrawn in place ("\r"), finished with a newline;
//   plain a log line every few seconds (stderr is a file or a pipe);
//   json  one JSON object per update and line, for scripts and GUIs.
// Workers count with atomics; at most one thread draws, and only when the last drawing is
// old enough, so counting costs a clock read. Nothing here feeds back into a result.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <mutex>
#include <optional>
#include <string>

namespace mebake {

enum class ProgressMode { Off, Tty, Plain, Json };

// "auto" (tty when stderr is a terminal, else plain), "plain", "json", "off"; anything
// else is a usage error. Quiet forces off.
ProgressMode ParseProgressMode(const std::string& text, bool quiet);
void SetProgressMode(ProgressMode mode);
ProgressMode GetProgressMode();
// Clears a progress line open on the terminal, so that a log line can take its place (the
// stage redraws it at its next update). The logger calls it.
void ClearProgressLine();

class ProgressStage {
public:
    // total 0: unknown (shown as a count and a rate, without percentage or ETA).
    ProgressStage(std::string name, uint64_t total, std::string unit);
    ~ProgressStage();  // Finish()
    ProgressStage(const ProgressStage&) = delete;
    ProgressStage& operator=(const ProgressStage&) = delete;

    // Thread-safe.
    void Add(uint64_t n = 1);
    void Set(uint64_t done);  // never lowers the count
    void SetTotal(uint64_t total);
    // A stage whose work is not a count of equal units (the solve) gives its own estimate of
    // the share done and the seconds left; it replaces done/total in the percentage and ETA.
    void SetEstimate(double fraction, std::optional<double> eta_seconds);
    // Words shown after the stage name ("batch 3 of ~7"); empty by default.
    void SetDetail(std::string detail);
    // Draws the last line (a newline on a terminal). Later calls do nothing.
    void Finish();

    double Elapsed() const;

private:
    struct Snapshot;
    Snapshot Take() const;
    void MaybeDraw();
    void Draw(bool final);

    const std::string name_, unit_;
    const std::chrono::steady_clock::time_point start_;
    std::atomic<uint64_t> done_{0}, total_{0};
    std::atomic<int64_t> next_draw_ns_{0};  // since start_
    std::mutex mutex_;                      // drawing and the estimate
    double est_fraction_ = -1;
    std::optional<double> est_eta_;
    std::string detail_;
    bool finished_ = false, drawn_ = false;
};

}  // namespace mebake
