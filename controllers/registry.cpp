#include <stdexcept>
#include <string>

#include "controllers/dialects.hpp"

namespace rotacal {

const Dialect& dialectByName(std::string_view name) {
  if (name == "csv") return csvDialect();
  if (name == "linuxcnc") return linuxcncDialect();
  if (name == "fanuc") return fanucDialect();
  if (name == "haas") return haasDialect();
  if (name == "siemens") return siemensDialect();
  if (name == "heidenhain") return heidenhainDialect();
  if (name == "okuma") return okumaDialect();
  std::string known;
  for (const auto& n : dialectNames()) known += (known.empty() ? "" : ", ") + n;
  throw std::invalid_argument("unknown dialect '" + std::string(name) + "' (available: " + known + ")");
}

std::vector<std::string> dialectNames() { return {"csv", "linuxcnc", "fanuc", "haas", "siemens", "heidenhain", "okuma"}; }

}  // namespace rotacal
