#pragma once
// The registries (controllers/registry.cpp, cycles/registry.cpp) hand out references to stateless
// dialects and cycles: each is built once, on first use, and lives until exit.

namespace rotacal {

template <class T>
const T& singleton() {
  static const T instance;
  return instance;
}

}  // namespace rotacal
