#include <stdexcept>
#include <string>

#include "controllers/dialects.hpp"

namespace rotacal {

const Dialect& dialectByName(std::string_view name) {
  if (name == "csv") return csvDialect();
  if (name == "linuxcnc") return linuxcncDialect();
  if (name == "fanuc") return fanucDialect();
  std::string known;
  for (const auto& n : dialectNames()) known += (known.empty() ? "" : ", ") + n;
  throw std::invalid_argument("unknown dialect '" + std::string(name) + "' (available: " + known + ")");
}

std::vector<std::string> dialectNames() { return {"csv", "linuxcnc", "fanuc"}; }

}  // namespace rotacal
