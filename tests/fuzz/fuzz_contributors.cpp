// CONTRIB.json loader (core/contributors.hpp: contributorsFromJson), as `uncertainty` and
// `design` read it.
#include "core/contributors.hpp"
#include "tests/fuzz/fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace rotacal;
  const std::string file = "contributors.json";
  fuzz::expectInputErrorOnly(file, [&] {
    const JsonDoc doc = parseJsonText(fuzz::asText(data, size), file);
    (void)contributorsFromJson(doc);
  });
  return 0;
}
