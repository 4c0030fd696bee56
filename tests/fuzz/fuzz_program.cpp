// NC programs: the word-address tokenizer (gcode/reader.hpp), each dialect's motion reader
// (controllers/motion_reader.hpp: `rotacal check`) and the rewrite of `compensate`
// (postproc/compensate_program.hpp). The first byte picks the dialect among those with programs,
// in the registry's order (scripts/fuzz.sh prefixes its seeds the same way). The tokenizer and the motion reader never
// throw (odd blocks are issues / Unreadable motions); compensate throws only InputError.
#include "controllers/dialect.hpp"
#include "controllers/motion_reader.hpp"
#include "core/machine.hpp"
#include "gcode/reader.hpp"
#include "postproc/compensate_program.hpp"
#include "tests/fuzz/fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace rotacal;
  static const std::vector<const Dialect*> kDialects = [] {
    std::vector<const Dialect*> out;
    for (const Dialect* d : dialects())
      if (d->hasPrograms()) out.push_back(d);
    return out;
  }();
  static const MachineModel machine = loadMachine(fuzz::sourcePath("examples/machines/ac_trunnion.json"));
  static const LocationErrors errors = [] {
    LocationErrors e;
    e.set("dx_AY", 0.0146);
    e.set("dz_AY", -0.0081);
    e.set("a_AY", -9e-6);
    e.set("b_CA", 4e-6);
    return e;
  }();
  if (size < 1) return 0;
  const Dialect& d = *kDialects[data[0] % kDialects.size()];
  const std::string dialect(d.name());
  const std::string text = fuzz::asText(data + 1, size - 1);
  try {
    (void)nc::readProgram(text);
    (void)ctl::readMotions(dialect, text);
  } catch (const std::exception& e) {
    fuzz::finding("the program readers threw", e.what());
  }
  if (!isWordAddress(d.language())) return 0;
  NcSyntax syntax;
  syntax.dialect = dialect;
  if (d.language() == ProgramLanguage::Sinumerik) syntax.comment = NcSyntax::Comment::Semicolon;
  ProgramCompensationOptions opt;
  opt.header.push_back("fuzz");
  const std::string file = "program.nc";
  fuzz::expectInputErrorOnly(file, [&] { (void)compensateProgram(text, file, machine, errors, syntax, opt); });
  return 0;
}
