// REPORT.json as `compensate` reads it (the machine it carries, postproc errorsFromReport, with
// and without --force) and as `history add` reads it (history::calibrationFromReport).
#include "core/machine.hpp"
#include "history/store.hpp"
#include "postproc/report_errors.hpp"
#include "tests/fuzz/fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace rotacal;
  const std::string file = "report.json";
  fuzz::expectInputErrorOnly(file, [&] {
    const JsonDoc doc = parseJsonText(fuzz::asText(data, size), file);
    (void)history::calibrationFromReport(doc, "m1", 1.7e9);
  });
  fuzz::expectInputErrorOnly(file, [&] {
    const JsonDoc doc = parseJsonText(fuzz::asText(data, size), file);
    Kinematics k = Kinematics::TableAC;
    if (doc.value.is_object() && doc.value.contains("machine_model"))
      k = machineFromJson(doc, doc.value["machine_model"]).kinematics;
    (void)errorsFromReport(doc, k, false);
    (void)errorsFromReport(doc, k, true);
  });
  return 0;
}
