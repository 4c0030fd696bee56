// TRUTH.json loader (core/simulation.hpp: truthFromJson) for the table kinematics the probing
// cycles simulate (the tool-tip cycle reads its own); the first byte picks the kinematics.
#include "core/simulation.hpp"
#include "tests/fuzz/fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace rotacal;
  if (size < 1) return 0;
  const Kinematics k[] = {Kinematics::TableAC, Kinematics::TableBC};
  const std::string file = "truth.json";
  fuzz::expectInputErrorOnly(file, [&] {
    const JsonDoc doc = parseJsonText(fuzz::asText(data + 1, size - 1), file);
    (void)truthFromJson(doc, k[data[0] % 2]);
  });
  return 0;
}
