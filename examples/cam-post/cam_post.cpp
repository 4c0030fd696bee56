// A minimal CAM post-processor on the installed rotacal library (docs/library.md): reads the
// location errors identified by `rotacal analyze` (REPORT.json) and a CSV of nominal poses, and
// prints each pose compensated: the command that puts the controlled point, with the nominal tool
// direction, on the same workpiece point on the machine with those errors. It does per pose what
// `rotacal compensate` does at each block's end point, and prints what that command would print:
// the angles rounded to the program's 4 decimals, the position computed for the rounded angles (a
// long move is split to follow the nominal path: rotacal::compensate does that for a program).
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
#include <iterator>
#include <sstream>
#include <stdexcept>
#include <string>

#include <rotacal/rotacal.hpp>

namespace {

std::string slurp(const std::string& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw std::runtime_error(file + ": cannot read");
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

int run(const std::string& report_file, const std::string& poses_file, const std::string& dialect) {
  // The report carries the machine it was measured on (kinematics, strokes, axis counting) and
  // the identified errors; the Compensator checks that all of them are there and plausible
  // (several reports combine: touch154's location errors, spheres3's error motions).
  const rotacal::Compensator comp({{report_file, slurp(report_file)}}, dialect);
  const std::array<char, 2> rot = comp.rotaryAxes();

  std::printf("# %s: %s machine '%s', location errors:", report_file.c_str(), comp.kinematics().c_str(),
              comp.machineName().c_str());
  for (const rotacal::ErrorValue& e : comp.locationErrors())
    std::printf(" %s %.2f %s", e.name.c_str(), e.value, e.unit.c_str());
  for (const auto& c : comp.componentErrors()) std::printf("; component errors of %c at %zu angles", c.axis, c.angles);
  std::printf("\nx,y,z,%c,%c,shift_um,tool_direction_residual_urad\n", rot[0] + ('a' - 'A'), rot[1] + ('a' - 'A'));

  std::ifstream in(poses_file);
  if (!in) throw std::runtime_error(poses_file + ": cannot read");
  std::string line;
  for (int line_no = 1; std::getline(in, line); ++line_no) {
    if (line.empty() || line[0] == '#' || std::isalpha(static_cast<unsigned char>(line[0]))) continue;
    const std::string where = poses_file + ":" + std::to_string(line_no) + ": ";
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
      throw std::runtime_error(where + "expected 5 numbers x,y,z,angle,angle: '" + line + "'");

    // The command for the nominal pose: its angles as the program prints them (4 decimals), the
    // position exact for those.
    rotacal::CompensatedPose c;
    try {
      c = comp.compensate({v[0], v[1], v[2], {v[3], v[4]}});
    } catch (const rotacal::Error& e) {
      throw std::runtime_error(where + e.what());
    }
    std::printf("%.4f,%.4f,%.4f,%.4f,%.4f,%.3f,%.3f\n", c.pose.x, c.pose.y, c.pose.z, c.pose.angles[0],
                c.pose.angles[1], c.shift_um, c.tool_direction_residual_urad);
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
