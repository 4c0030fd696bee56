// MACHINE.json loader (core/machine.hpp: machineFromJson), as `plan`, `design`, `check` and
// `compensate --machine` read it.
#include "core/machine.hpp"
#include "tests/fuzz/fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace rotacal;
  const std::string file = "machine.json";
  fuzz::expectInputErrorOnly(file, [&] {
    const JsonDoc doc = parseJsonText(fuzz::asText(data, size), file);
    (void)machineFromJson(doc, doc.value);
  });
  return 0;
}
