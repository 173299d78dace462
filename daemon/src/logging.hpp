#pragma once
// The "daemon" spdlog logger. Journal-friendly: under systemd (JOURNAL_STREAM set) every line
// starts with its syslog priority ("<6>...", which journald turns into the entry's priority) and
// has no timestamp or colour; when stderr is not a terminal, plain "level: message" lines; on a
// terminal, time and coloured level.
#include "handtrack/daemon/config.hpp"

#include <spdlog/spdlog.h>

#include <memory>

namespace handtrack::daemon {

// Creates the logger on first use (stderr), so the library works without setup_logging().
spdlog::logger& log();
void setup_logging(LogLevel level);
void set_log_level(LogLevel level);

}  // namespace handtrack::daemon
