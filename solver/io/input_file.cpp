#include "input_file.hpp"

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>

#include <fmt/format.h>

namespace spate {

std::string read_input_text(const std::string& path, const std::string& what, std::size_t largest) {
  auto fail = [&](const std::string& reason) { return InputFileError(fmt::format("{}: cannot read {} ({})", path, what, reason)); };
  std::error_code ec;
  const std::filesystem::file_status st = std::filesystem::status(path, ec);
  if (ec) throw fail(ec.message());
  if (st.type() == std::filesystem::file_type::directory) throw fail("it is a folder");
  if (st.type() != std::filesystem::file_type::regular) throw fail("not a regular file: a device, FIFO or socket");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw fail(std::strerror(errno));
  // At most largest + 1 bytes, whatever its size said (a file may grow while it is read).
  std::string text;
  char block[1 << 16];
  while (in && text.size() <= largest) {
    in.read(block, sizeof block);
    text.append(block, static_cast<std::size_t>(in.gcount()));
  }
  if (in.bad()) throw fail(std::strerror(errno));
  if (text.size() > largest) throw fail(fmt::format("larger than {} MiB, too large for {}", largest >> 20, what));
  return text;
}

}  // namespace spate
