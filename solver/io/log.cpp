#include "log.hpp"

#include <spdlog/sinks/base_sink.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <ctime>
#include <memory>
#include <mutex>

namespace spate {

namespace {

// Routes by level (info and below: stdout; warnings and errors: stderr) and formats itself: the
// format depends on whether that stream is a terminal, which spdlog's patterns cannot express.
class ConsoleSink final : public spdlog::sinks::base_sink<std::mutex> {
 public:
  explicit ConsoleSink(std::string program) : program_(std::move(program)) {}

 protected:
  void sink_it_(const spdlog::details::log_msg& msg) override {
    const bool to_err = msg.level >= spdlog::level::warn;
    std::FILE* out = to_err ? stderr : stdout;
    const bool tty = to_err ? err_tty_ : out_tty_;
    // On a terminal the line first clears what the progress line left there (carriage return,
    // erase to the end of the line); elsewhere it starts with the time.
    std::string line = tty ? "\r\x1b[K" : timestamp(msg.time) + " ";
    line += program_ + ": ";
    switch (msg.level) {
      case spdlog::level::trace: line += "trace: "; break;
      case spdlog::level::debug: line += "debug: "; break;
      case spdlog::level::warn: line += "warning: "; break;
      case spdlog::level::err:
      case spdlog::level::critical: line += "error: "; break;
      default: break;
    }
    std::string text = strip_escape_codes(std::string_view(msg.payload.data(), msg.payload.size()));
    while (!text.empty() && (text.back() == '\n' || text.back() == '\r')) text.pop_back();
    line += text;
    line += '\n';
    // Keep the two streams in order for a reader that merges them (2>&1).
    std::fflush(to_err ? stdout : stderr);
    std::fwrite(line.data(), 1, line.size(), out);
    std::fflush(out);
  }
  void flush_() override {
    std::fflush(stdout);
    std::fflush(stderr);
  }

 private:
  static std::string timestamp(spdlog::log_clock::time_point t) {
    const std::time_t seconds = spdlog::log_clock::to_time_t(t);
    const auto ms = std::chrono::duration_cast<std::chrono::milliseconds>(t.time_since_epoch()).count() % 1000;
    std::tm utc{};
    gmtime_r(&seconds, &utc);
    char text[40];
    const std::size_t n = std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%S", &utc);
    std::snprintf(text + n, sizeof text - n, ".%03dZ", static_cast<int>(ms));
    return text;
  }
  std::string program_;
  bool out_tty_ = isatty(STDOUT_FILENO) == 1;
  bool err_tty_ = isatty(STDERR_FILENO) == 1;
};

}  // namespace

void configure_logging(spdlog::level::level_enum level, const std::string& program) {
  auto logger = std::make_shared<spdlog::logger>("spate", std::make_shared<ConsoleSink>(program));
  logger->set_level(level);
  logger->flush_on(spdlog::level::trace);
  spdlog::set_default_logger(logger);
}

std::optional<spdlog::level::level_enum> parse_log_level(std::string_view name) {
  if (name == "trace") return spdlog::level::trace;
  if (name == "debug") return spdlog::level::debug;
  if (name == "info") return spdlog::level::info;
  if (name == "warning" || name == "warn") return spdlog::level::warn;
  if (name == "error") return spdlog::level::err;
  if (name == "off") return spdlog::level::off;
  return std::nullopt;
}

std::string strip_escape_codes(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (text[i] != '\x1b') {
      out += text[i];
      continue;
    }
    if (i + 1 >= text.size()) break;
    const char kind = text[++i];
    if (kind == '[') {  // CSI: parameters, then one final byte in @..~
      while (i + 1 < text.size() && !(text[i + 1] >= '@' && text[i + 1] <= '~')) ++i;
      ++i;
    } else if (kind == ']') {  // OSC: up to BEL or ESC backslash
      while (i + 1 < text.size() && text[i + 1] != '\a' && text[i + 1] != '\x1b') ++i;
      ++i;
      if (i < text.size() && text[i] == '\x1b') ++i;
    }
    // anything else: a two-character sequence, already skipped
  }
  return out;
}

}  // namespace spate
