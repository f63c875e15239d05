#pragma once
// Text input files (case files, steering logs) read as input: only a regular file, only up to a
// size that such a file can sensibly have. A device (/dev/zero), a FIFO nobody writes to or a
// socket would otherwise make a read that never ends or fills the memory (issue 14: nothing hangs).
#include <cstddef>
#include <stdexcept>
#include <string>

namespace spate {

struct InputFileError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// The whole text of `path`, a regular file of at most `largest` bytes; `what` names the kind of
// file in messages ("the case file"). InputFileError "<path>: cannot read <what> (<reason>)".
std::string read_input_text(const std::string& path, const std::string& what, std::size_t largest);

}  // namespace spate
