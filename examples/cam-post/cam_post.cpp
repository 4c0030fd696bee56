// A minimal CAM post-processor on the installed rotacal library (docs/compensation.md, "Library
// for CAM posts"): reads the location errors identified by `rotacal analyze` (REPORT.json) and a
// CSV of nominal poses, and prints each pose compensated: the command that puts the controlled
// point, with the nominal tool direction, on the same workpiece point on the machine with those
// errors. It does per pose what `rotacal compensate` does at each block's end point, and prints
// what that command would print: the angles rounded to the program's 4 decimals, the position
// computed for the rounded angles (a long move split to follow the nominal path: compensateMove).
//
//   cam_post REPORT.json POSES.csv [DIALECT]
//
// POSES.csv: x,y,z (mm, machine coordinates of the controlled point relative to the rotary-axis
// intersection), then the two rotary angles of the report's machine in the order of its
// MACHINE.json (a,c for an A/C table), in deg as DIALECT's control counts them (MACHINE.json's
// dialect_sign: LinuxCNC's trunnion kinematics turn A and C the other way); without DIALECT, in
// the papers' convention. Lines starting with '#' and a header line starting with a letter are
// skipped.
#include <array>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <exception>
#include <fstream>
#include <iostream>
#include <sstream>
#include <stdexcept>
#include <string>

#include "core/compensation.hpp"
#include "core/errors.hpp"
#include "core/json_io.hpp"
#include "core/machine.hpp"
#include "postproc/report_errors.hpp"

namespace {

double& axis(rotacal::Pose& q, char name) { return name == 'A' ? q.A : name == 'B' ? q.B : q.C; }
double axis(const rotacal::Pose& q, char name) { return name == 'A' ? q.A : name == 'B' ? q.B : q.C; }

// The value as the program prints it (4 decimals) and the control reads it back.
double printed(double v, int decimals = 4) {
  char text[64];
  std::snprintf(text, sizeof text, "%.*f", decimals, v);
  const double r = std::stod(text);
  return r == 0.0 ? 0.0 : r;  // no "-0.0000"
}

int run(const std::string& report_file, const std::string& poses_file, const std::string& dialect) {
  // The report carries the machine it was measured on (kinematics, strokes, axis counting) and
  // the identified errors; errorsFromReport checks that all of them are there and plausible
  // (errorsFromReports combines several: touch154's location errors, spheres3's error motions).
  const rotacal::JsonDoc report = rotacal::readJsonFile(report_file);
  if (!report.value.is_object() || !report.value.contains("machine_model"))
    report.fail(report.value, "", "no 'machine_model' (written by rotacal analyze)");
  const rotacal::MachineModel machine = rotacal::machineFromJson(report, report.value["machine_model"]);
  const rotacal::GeometricErrors errors = rotacal::errorsFromReport(report, machine.kinematics, /*force=*/false);
  if (machine.rotary.size() != 2) throw std::runtime_error(report_file + ": the machine has not two rotary axes");
  const std::array<char, 2> rot{machine.rotary[0].name, machine.rotary[1].name};
  std::array<int, 2> sign{1, 1};
  if (!dialect.empty())
    for (int i = 0; i < 2; ++i) sign[i] = machine.controllerSign(rot[i], dialect);

  std::printf("# %s: %s machine '%s', location errors:", report_file.c_str(),
              std::string(rotacal::kinematicsName(machine.kinematics)).c_str(), machine.name.c_str());
  for (int i = 0; i < rotacal::kNumLocationErrors; ++i) {
    const auto& p = rotacal::locationParameters(machine.kinematics)[i];
    std::printf(" %s %.2f %s", std::string(p.name).c_str(), errors.location.reportValue(i),
                std::string(rotacal::reportUnit(p.kind)).c_str());
  }
  for (const auto& c : errors.components) std::printf("; component errors of %c at %zu angles", c.axis, c.angle_deg.size());
  std::printf("\nx,y,z,%c,%c,shift_um,tool_direction_residual_urad\n", rot[0] + ('a' - 'A'), rot[1] + ('a' - 'A'));

  std::ifstream in(poses_file);
  if (!in) throw std::runtime_error(poses_file + ": cannot read");
  std::string line;
  for (int line_no = 1; std::getline(in, line); ++line_no) {
    if (line.empty() || line[0] == '#' || std::isalpha(static_cast<unsigned char>(line[0]))) continue;
    std::array<double, 5> v{};
    std::istringstream fields(line);
    std::string field;
    int n = 0;
    try {
      for (; n < 5 && std::getline(fields, field, ','); ++n) {
        size_t used = 0;
        v[n] = std::stod(field, &used);
        if (used != field.size() || !std::isfinite(v[n])) throw std::invalid_argument(field);
      }
    } catch (const std::exception&) {
      n = -1;
    }
    if (n != 5 || std::getline(fields, field, ','))
      throw rotacal::InputError(poses_file, line_no, "expected 5 numbers x,y,z,angle,angle: '" + line + "'");

    // The nominal pose in the papers' convention, and the compensated one.
    const Eigen::Vector3d x(v[0], v[1], v[2]);
    rotacal::Pose q;
    for (int i = 0; i < 2; ++i) axis(q, rot[i]) = sign[i] * v[3 + i];
    const rotacal::CompensatedCommand cc = rotacal::compensatePose(errors, q);
    // Round the angles as they will be printed, then compute the position for exactly those.
    rotacal::Pose q_cmd = q;
    std::array<double, 2> angle{};
    for (int i = 0; i < 2; ++i) {
      angle[i] = printed(sign[i] * axis(cc.pose, rot[i]));
      axis(q_cmd, rot[i]) = sign[i] * angle[i];
      const rotacal::RotaryAxis& a = machine.rotaryAxis(rot[i]);
      if (!a.continuous && !a.stroke_deg.contains(axis(q_cmd, rot[i])))
        throw rotacal::InputError(poses_file, line_no, std::string("the compensated ") + rot[i] +
                                                           " is outside its stroke in MACHINE.json");
    }
    const Eigen::Vector3d x_cmd = rotacal::compensatedPosition(errors, q, x, q_cmd);
    std::printf("%.4f,%.4f,%.4f,%.4f,%.4f,%.3f,%.3f\n", x_cmd[0], x_cmd[1], x_cmd[2], angle[0], angle[1],
                (x_cmd - x).norm() * 1000.0,
                rotacal::toolDirectionError(errors, q_cmd, q) * 1e6);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3 || argc > 4) {
    std::cerr << "usage: cam_post REPORT.json POSES.csv [DIALECT]\n";
    return 2;
  }
  try {
    return run(argv[1], argv[2], argc == 4 ? argv[3] : "");
  } catch (const std::exception& e) {
    std::cerr << "cam_post: error: " << e.what() << "\n";
    return 1;
  }
}
