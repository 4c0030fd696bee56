#pragma once
// The FN 16 format files the Heidenhain program prints its results through.
#include <string>
#include <utility>
#include <vector>

namespace rotacal {

/// The FN 16 format files the heidenhain program prints through (file name, text): they must be
/// saved in TNC:\ROTACAL\ on the control; the program lists them in its header comments.
std::vector<std::pair<std::string, std::string>> heidenhainFormatFiles(const std::string& cycle, int points);

}  // namespace rotacal
