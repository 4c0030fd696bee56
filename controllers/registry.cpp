// The only list of dialects. A new dialect is a folder controllers/<name>/ whose dialect.cpp
// defines `const Dialect& <name>Dialect()` (its name() being <name>), plus one line here.
#include <stdexcept>
#include <string>

#include "controllers/dialect.hpp"

// In the order the command line lists them: the neutral csv first.
#define ROTACAL_DIALECTS(X) \
  X(csv)                    \
  X(linuxcnc)               \
  X(fanuc)                  \
  X(haas)                   \
  X(siemens)                \
  X(heidenhain)             \
  X(okuma)

namespace rotacal {

#define ROTACAL_DECLARE_DIALECT(n) const Dialect& n##Dialect();
ROTACAL_DIALECTS(ROTACAL_DECLARE_DIALECT)
#undef ROTACAL_DECLARE_DIALECT

const std::vector<const Dialect*>& dialects() {
#define ROTACAL_LIST_DIALECT(n) &n##Dialect(),
  static const std::vector<const Dialect*> all{ROTACAL_DIALECTS(ROTACAL_LIST_DIALECT)};
#undef ROTACAL_LIST_DIALECT
  return all;
}

std::vector<std::string> dialectNames() {
  std::vector<std::string> names;
  for (const Dialect* d : dialects()) names.emplace_back(d->name());
  return names;
}

const Dialect* findDialect(std::string_view name) {
  for (const Dialect* d : dialects())
    if (d->name() == name) return d;
  return nullptr;
}

const Dialect& dialectByName(std::string_view name) {
  if (const Dialect* d = findDialect(name)) return *d;
  std::string known;
  for (const auto& n : dialectNames()) known += (known.empty() ? "" : ", ") + n;
  throw std::invalid_argument("unknown dialect '" + std::string(name) + "' (available: " + known + ")");
}

}  // namespace rotacal
