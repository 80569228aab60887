// Logging goes to stderr only, so stdout stays clean for piped mesh data.
#pragma once

#include <spdlog/spdlog.h>

namespace mebake {

// verbosity: -1 quiet (errors only), 0 normal (info), 1 verbose (debug), 2 trace.
void InitLogging(int verbosity);

// True when stderr is an interactive terminal (live progress lines are worth drawing).
bool StderrIsTerminal();

}  // namespace mebake
