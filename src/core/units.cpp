#include "core/units.h"

#include <fmt/format.h>
#include <sys/resource.h>
#include <unistd.h>

#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>

namespace mebake {

std::optional<uint64_t> ParseByteSize(std::string_view text) {
    while (!text.empty() && std::isspace(static_cast<unsigned char>(text.back())))
        text.remove_suffix(1);
    if (text.empty()) return std::nullopt;
    double value = 0;
    auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
    if (ec != std::errc() || value < 0 || !std::isfinite(value)) return std::nullopt;
    std::string unit(end, text.data() + text.size());
    for (auto& c : unit) c = char(std::toupper(static_cast<unsigned char>(c)));
    double mult = 1;
    if (unit.empty() || unit == "B") mult = 1;
    else if (unit == "K" || unit == "KB" || unit == "KIB") mult = 1024.0;
    else if (unit == "M" || unit == "MB" || unit == "MIB") mult = 1024.0 * 1024;
    else if (unit == "G" || unit == "GB" || unit == "GIB") mult = 1024.0 * 1024 * 1024;
    else if (unit == "T" || unit == "TB" || unit == "TIB") mult = 1024.0 * 1024 * 1024 * 1024;
    else return std::nullopt;
    double bytes = value * mult;
    if (bytes > 1.8e19) return std::nullopt;
    return uint64_t(std::llround(bytes));
}

std::string FormatBytes(uint64_t bytes) {
    const char* units[] = {"B", "KiB", "MiB", "GiB", "TiB"};
    double v = double(bytes);
    int u = 0;
    while (v >= 1024 && u < 4) {
        v /= 1024;
        ++u;
    }
    return u == 0 ? fmt::format("{} B", bytes) : fmt::format("{:.3g} {}", v, units[u]);
}

std::string FormatSeconds(double s) {
    if (s < 1) return fmt::format("{:.0f}ms", s * 1000);
    if (s < 60) return fmt::format("{:.1f}s", s);
    auto total = uint64_t(s + 0.5);
    if (total < 3600) return fmt::format("{}m{:02}s", total / 60, total % 60);
    return fmt::format("{}h{:02}m", total / 3600, (total / 60) % 60);
}

std::string FormatCount(double n) {
    if (n < 1e3) return fmt::format("{:.0f}", n);
    if (n < 1e6) return fmt::format("{:.3g}K", n / 1e3);
    if (n < 1e9) return fmt::format("{:.3g}M", n / 1e6);
    return fmt::format("{:.3g}G", n / 1e9);
}

uint64_t PeakRssBytes() {
    struct rusage ru {};
    getrusage(RUSAGE_SELF, &ru);
    return uint64_t(ru.ru_maxrss) * 1024;  // Linux reports KiB
}

uint64_t CurrentRssBytes() {
    FILE* f = std::fopen("/proc/self/statm", "r");
    if (!f) return 0;
    unsigned long long pages_total = 0, pages_resident = 0;
    int n = std::fscanf(f, "%llu %llu", &pages_total, &pages_resident);
    std::fclose(f);
    if (n != 2) return 0;
    return uint64_t(pages_resident) * uint64_t(sysconf(_SC_PAGESIZE));
}

}  // namespace mebake
