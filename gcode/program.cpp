#include "gcode/program.hpp"

namespace rotacal::nc {

Shape shapeOf(const Program& program) {
  Shape s;
  s.number = program.number;
  for (const auto& op : program.ops) {
    if (op.kind == Op::Kind::Probe) ++s.probes;
    if (op.kind == Op::Kind::Read) ++s.reads;
    if (op.kind == Op::Kind::Mode && op.inverse_time) s.inverse_time = true;
  }
  return s;
}

}  // namespace rotacal::nc
