#include "core/progress.h"

#include "core/error.h"
#include "core/log.h"
#include "core/units.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fmt/format.h>

namespace mebake {

namespace {

std::atomic<int> g_mode{int(ProgressMode::Off)};
// A terminal line being redrawn is open (no newline yet); log lines clear it first.
std::mutex g_stderr_mutex;
bool g_line_open = false;

// Seconds between drawings: a terminal line is cheap to redraw, a log file is not.
double Interval(ProgressMode mode) {
    switch (mode) {
    case ProgressMode::Tty:
        return 0.25;
    case ProgressMode::Json:
        return 0.5;
    default:
        return 5.0;
    }
}

std::string Amount(double n, const std::string& unit) {
    if (unit == "B")
        return FormatBytes(uint64_t(std::max(n, 0.0)));
    return unit.empty() ? FormatCount(n) : FormatCount(n) + " " + unit;
}

std::string JsonNumber(double v) {
    return std::isfinite(v) ? fmt::format("{:.6g}", v) : std::string("null");
}

// Stage names and units are ours (ASCII words), but quote them properly anyway.
std::string JsonString(const std::string& s) {
    std::string out = "\"";
    for (char c : s) {
        if (c == '"' || c == '\\')
            out += '\\';
        if (static_cast<unsigned char>(c) < 0x20)
            out += fmt::format("\\u{:04x}", int(c));
        else
            out += c;
    }
    return out + "\"";
}

}  // namespace

ProgressMode ParseProgressMode(const std::string& text, bool quiet) {
    ProgressMode mode;
    if (text == "auto" || text.empty())
        mode = StderrIsTerminal() ? ProgressMode::Tty : ProgressMode::Plain;
    else if (text == "plain")
        mode = ProgressMode::Plain;
    else if (text == "json")
        mode = ProgressMode::Json;
    else if (text == "off")
        mode = ProgressMode::Off;
    else
        UsageError("--progress {}: expected auto, plain, json or off", text);
    return quiet ? ProgressMode::Off : mode;
}

void ClearProgressLine() {
    std::lock_guard lock(g_stderr_mutex);
    if (g_line_open) {
        std::fputs("\r\x1b[K", stderr);
        g_line_open = false;
    }
}

void SetProgressMode(ProgressMode mode) {
    g_mode = int(mode);
}
ProgressMode GetProgressMode() {
    return ProgressMode(g_mode.load());
}

struct ProgressStage::Snapshot {
    double elapsed = 0;
    uint64_t done = 0, total = 0;
    double fraction = -1;       // < 0: unknown
    std::optional<double> eta;  // seconds left
    double rate = 0;            // units per second
};

ProgressStage::ProgressStage(std::string name, uint64_t total, std::string unit)
    : name_(std::move(name)), unit_(std::move(unit)), start_(std::chrono::steady_clock::now()) {
    total_ = total;
    // Stages shorter than this are not shown at all on a terminal or in a log.
    const ProgressMode mode = GetProgressMode();
    next_draw_ns_ = mode == ProgressMode::Tty ? int64_t(5e8) : int64_t(Interval(mode) * 1e9);
    if (mode == ProgressMode::Json) {
        std::lock_guard lock(mutex_);
        Draw(false);
    }
}

ProgressStage::~ProgressStage() {
    Finish();
}

double ProgressStage::Elapsed() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

void ProgressStage::Add(uint64_t n) {
    done_.fetch_add(n, std::memory_order_relaxed);
    MaybeDraw();
}

void ProgressStage::Set(uint64_t done) {
    uint64_t cur = done_.load(std::memory_order_relaxed);
    while (cur < done && !done_.compare_exchange_weak(cur, done, std::memory_order_relaxed)) {
    }
    MaybeDraw();
}

void ProgressStage::SetTotal(uint64_t total) {
    total_ = total;
}

void ProgressStage::SetEstimate(double fraction, std::optional<double> eta_seconds) {
    {
        std::lock_guard lock(mutex_);
        est_fraction_ = std::clamp(fraction, 0.0, 1.0);
        est_eta_ = eta_seconds;
    }
    MaybeDraw();
}

void ProgressStage::SetDetail(std::string detail) {
    std::lock_guard lock(mutex_);
    detail_ = std::move(detail);
}

void ProgressStage::MaybeDraw() {
    const ProgressMode mode = GetProgressMode();
    if (mode == ProgressMode::Off)
        return;
    const int64_t now_ns = std::chrono::duration_cast<std::chrono::nanoseconds>(
                               std::chrono::steady_clock::now() - start_)
                               .count();
    int64_t due = next_draw_ns_.load(std::memory_order_relaxed);
    if (now_ns < due)
        return;
    // One thread wins the slot; the others go back to work without waiting.
    const int64_t next = now_ns + int64_t(Interval(mode) * 1e9);
    if (!next_draw_ns_.compare_exchange_strong(due, next, std::memory_order_relaxed))
        return;
    std::unique_lock lock(mutex_, std::try_to_lock);
    if (lock.owns_lock() && !finished_)
        Draw(false);
}

ProgressStage::Snapshot ProgressStage::Take() const {
    Snapshot s;
    s.elapsed = Elapsed();
    s.done = done_.load(std::memory_order_relaxed);
    s.total = total_.load(std::memory_order_relaxed);
    s.rate = s.elapsed > 0 ? double(s.done) / s.elapsed : 0;
    if (est_fraction_ >= 0) {
        s.fraction = est_fraction_;
        s.eta = est_eta_;
    } else if (s.total > 0) {
        s.fraction = std::min(1.0, double(s.done) / double(s.total));
    }
    // Time left at the rate so far, once there is something to extrapolate from.
    if (!s.eta && s.fraction > 0)
        s.eta = s.elapsed * (1 - s.fraction) / s.fraction;
    return s;
}

void ProgressStage::Draw(bool final) {
    const ProgressMode mode = GetProgressMode();
    const Snapshot s = Take();
    std::string line;
    if (mode == ProgressMode::Json) {
        line = fmt::format(
            "{{\"stage\":{},\"detail\":{},\"done\":{},\"total\":{},\"unit\":{},\"fraction\":{},"
            "\"rate\":{},"
            "\"elapsed\":{},\"eta\":{},\"final\":{}}}\n",
            JsonString(name_), JsonString(detail_), s.done, s.total, JsonString(unit_),
            s.fraction >= 0 ? JsonNumber(final ? 1.0 : s.fraction) : "null", JsonNumber(s.rate),
            JsonNumber(s.elapsed), s.eta && !final ? JsonNumber(*s.eta) : (final ? "0" : "null"),
            final ? "true" : "false");
    } else {
        std::string what = s.total > 0 ? fmt::format("{}/{}", Amount(double(s.done), ""),
                                                     Amount(double(s.total), unit_))
                                       : Amount(double(s.done), unit_);
        if (unit_ == "B" && s.total > 0)
            what = fmt::format("{}/{}", FormatBytes(s.done), FormatBytes(s.total));
        std::string pct = s.fraction >= 0
                              ? fmt::format("{:5.1f}%", 100 * (final ? 1.0 : s.fraction))
                              : std::string("    ?%");
        std::string tail = final ? fmt::format("done in {}", FormatSeconds(s.elapsed))
                                 : fmt::format("elapsed {}, ETA {}", FormatSeconds(s.elapsed),
                                               s.eta ? FormatSeconds(*s.eta) : "?");
        std::string rate =
            unit_ == "B" ? FormatBytes(uint64_t(s.rate)) + "/s" : FormatCount(s.rate) + "/s";
        const std::string name = detail_.empty() ? name_ : name_ + " " + detail_;
        if (mode == ProgressMode::Tty)
            line = fmt::format("\r\x1b[K  {} {} ({}, {}) {}{}", name, pct, what, rate, tail,
                               final ? "\n" : "");
        else
            line = fmt::format("progress: {} {} ({}, {}) {}\n", name, pct, what, rate, tail);
    }
    {
        std::lock_guard lock(g_stderr_mutex);
        std::fwrite(line.data(), 1, line.size(), stderr);
        std::fflush(stderr);
        g_line_open = mode == ProgressMode::Tty && !final;
    }
    drawn_ = true;
}

void ProgressStage::Finish() {
    std::lock_guard lock(mutex_);
    if (finished_)
        return;
    finished_ = true;
    const ProgressMode mode = GetProgressMode();
    // A stage too short to have been shown is not shown at its end either (except to
    // scripts, which get every stage's start and end).
    if (mode == ProgressMode::Json || (mode != ProgressMode::Off && drawn_))
        Draw(true);
}

}  // namespace mebake
