#pragma once
// Errors at the boundary: bad input names its file and line. Pure functions inside core throw
// std::invalid_argument for misuse; parsers and loaders wrap it into InputError.
#include <stdexcept>
#include <string>

namespace rotacal {

class InputError : public std::runtime_error {
 public:
  InputError(std::string file, int line, const std::string& what)
      : std::runtime_error(file + ":" + std::to_string(line) + ": " + what),
        file_(std::move(file)),
        line_(line) {}
  const std::string& file() const { return file_; }
  int line() const { return line_; }

 private:
  std::string file_;
  int line_;
};

}  // namespace rotacal
