#include "core/log.h"

#include "core/progress.h"

#include <spdlog/sinks/stdout_color_sinks.h>
#include <unistd.h>

namespace mebake {

namespace {

// The coloured stderr sink, after clearing a progress line that is being redrawn.
class ProgressAwareSink : public spdlog::sinks::sink {
public:
    ProgressAwareSink() : inner_(std::make_shared<spdlog::sinks::stderr_color_sink_mt>()) {}
    void log(const spdlog::details::log_msg& msg) override {
        ClearProgressLine();
        inner_->log(msg);
    }
    void flush() override { inner_->flush(); }
    void set_pattern(const std::string& pattern) override { inner_->set_pattern(pattern); }
    void set_formatter(std::unique_ptr<spdlog::formatter> f) override {
        inner_->set_formatter(std::move(f));
    }

private:
    std::shared_ptr<spdlog::sinks::sink> inner_;
};

}  // namespace

void InitLogging(int verbosity) {
    auto logger = std::make_shared<spdlog::logger>("mebake", std::make_shared<ProgressAwareSink>());
    spdlog::register_logger(logger);
    logger->set_pattern("%^%l%$: %v");
    spdlog::level::level_enum level = spdlog::level::info;
    if (verbosity < 0)
        level = spdlog::level::err;
    if (verbosity == 1)
        level = spdlog::level::debug;
    if (verbosity >= 2)
        level = spdlog::level::trace;
    logger->set_level(level);
    spdlog::set_default_logger(logger);
}

bool StderrIsTerminal() {
    return ::isatty(STDERR_FILENO) == 1;
}

}  // namespace mebake
