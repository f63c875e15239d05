#pragma once
// spate's log: spdlog's default logger, set up by the program with --log-level. Messages read like
// the rest of the command line's output ("spate: ...", "spate: warning: ...", "spate: error: ...");
// info and below go to stdout, warnings and errors to stderr. Where the stream is not a terminal
// (a log file, a pipe) each line starts with an ISO 8601 UTC timestamp, and escape sequences (the
// colours some libraries put in their text) are removed everywhere, so log files hold plain text.
// Call sites use spdlog directly: spdlog::info("..."), spdlog::warn("{} ...", x).
#include <optional>
#include <string>
#include <string_view>

#include <spdlog/spdlog.h>

namespace spate {

// Installs the console logger. `program` is the name lines start with ("spate", or
// "spate (rank 1 of 2)" under MPI). Safe to call again (e.g. once the rank is known).
void configure_logging(spdlog::level::level_enum level, const std::string& program = "spate");
// trace, debug, info, warning (or warn), error, off; nothing for anything else.
std::optional<spdlog::level::level_enum> parse_log_level(std::string_view name);
// `text` without ANSI/VT100 escape sequences (CSI "ESC [ ... letter", OSC "ESC ] ... BEL/ST", and
// two-character "ESC x").
std::string strip_escape_codes(std::string_view text);

}  // namespace spate
