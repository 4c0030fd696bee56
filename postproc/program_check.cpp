#include "postproc/program_check.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <set>
#include <stdexcept>

#include <fmt/format.h>

#include "core/error_model.hpp"

namespace rotacal {
namespace {

constexpr double kMmPerInch = 25.4;
constexpr double kStrokeTolMm = 1e-3;     // printed rounding of 4-5 decimals, with margin
constexpr double kRotaryStrokeTolDeg = 1e-6;
constexpr double kDegToRad = 3.14159265358979323846 / 180.0;

// What the probe can hit, in the workpiece (table) frame: it turns with the rotary table.
// How deep below its top the table is modelled as solid for a part program: enough that a path
// crossing the top is inside it by far more than the sweep's resolution.
constexpr double kTableSlabMm = 10.0;

struct Obstacle {
  enum class Shape { Box, Sphere, Disc } shape = Shape::Box;
  std::string name;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  Eigen::Vector3d half = Eigen::Vector3d::Zero();  // Box
  double radius = 0.0;                             // Sphere, Disc (a disc in the plane z = centre.z)
  double depth = 0.0;                              // Disc: a solid slab below the plane this deep (0: a disc)

  // Signed distance (negative inside); the disc has no inside. Each is a convex function of the
  // point (distance to a convex set), so its minimum along a segment is found by golden section.
  double sdf(const Eigen::Vector3d& p) const {
    switch (shape) {
      case Shape::Box: {
        const Eigen::Vector3d q = (p - centre).cwiseAbs() - half;
        return q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0);
      }
      case Shape::Sphere: return (p - centre).norm() - radius;
      case Shape::Disc: {
        if (depth > 0.0) {  // a capped cylinder from the plane down by `depth`
          const double qr = std::hypot(p.x() - centre.x(), p.y() - centre.y()) - radius;
          const double qz = std::abs(p.z() - (centre.z() - depth / 2)) - depth / 2;
          return std::hypot(std::max(qr, 0.0), std::max(qz, 0.0)) + std::min(std::max(qr, qz), 0.0);
        }
        const double dr = std::max(std::hypot(p.x() - centre.x(), p.y() - centre.y()) - radius, 0.0);
        return std::hypot(dr, p.z() - centre.z());
      }
    }
    return 0.0;
  }
  // Distance of the farthest point from the origin (on the rotary axes): a bound on how high it
  // can rise at any table angle.
  double reach() const {
    switch (shape) {
      case Shape::Box: return (centre.cwiseAbs() + half).norm();
      case Shape::Sphere: return centre.norm() + radius;
      case Shape::Disc:
        return std::hypot(centre.head<2>().norm() + radius, std::max(std::abs(centre.z()), std::abs(centre.z() - depth)));
    }
    return 0.0;
  }
  // Highest machine z at a pose (T = T_m_w).
  double top(const Eigen::Isometry3d& T) const {
    switch (shape) {
      case Shape::Box: {
        double z = -std::numeric_limits<double>::infinity();
        for (int i = 0; i < 8; ++i) {
          const Eigen::Vector3d c(i & 1 ? half.x() : -half.x(), i & 2 ? half.y() : -half.y(), i & 4 ? half.z() : -half.z());
          z = std::max(z, (T * (centre + c)).z());
        }
        return z;
      }
      case Shape::Sphere: return (T * centre).z() + radius;
      case Shape::Disc: {
        const double nz = (T.linear() * Eigen::Vector3d::UnitZ()).z();
        const double rim = radius * std::sqrt(std::max(0.0, 1.0 - nz * nz));
        return std::max((T * centre).z(), (T * (centre - Eigen::Vector3d(0, 0, depth))).z()) + rim;
      }
    }
    return 0.0;
  }
};

double segmentSphereDistance(const Eigen::Vector3d& a, const Eigen::Vector3d& u, double len, const Eigen::Vector3d& c) {
  const double t = std::clamp((c - a).dot(u), 0.0, len);
  return (a + t * u - c).norm();
}

// Minimum of the convex f on [0, len] by golden section (interval shrinks to 0.618^40 len).
template <class F>
double minOnSegment(F&& f, double len) {
  const double g = 0.5 * (std::sqrt(5.0) - 1.0);
  double lo = 0.0, hi = len;
  double x1 = hi - g * (hi - lo), x2 = lo + g * (hi - lo);
  double f1 = f(x1), f2 = f(x2);
  for (int i = 0; i < 40; ++i) {
    if (f1 < f2) {
      hi = x2;
      x2 = x1;
      f2 = f1;
      x1 = hi - g * (hi - lo);
      f1 = f(x1);
    } else {
      lo = x1;
      x1 = x2;
      f1 = f2;
      x2 = lo + g * (hi - lo);
      f2 = f(x2);
    }
  }
  return std::min({f1, f2, f(0.0), f(len)});
}

struct Gap {
  double mm = std::numeric_limits<double>::infinity();
  const Obstacle* what = nullptr;
};

class Simulator {
 public:
  // A part program's tool is a point: its radius and length are the tool's, which the program's
  // tool table holds and rotacal does not.
  Simulator(const MachineModel& m, std::vector<Obstacle> obstacles, std::optional<GeometricErrors> errors, bool point)
      : m_(m), obstacles_(std::move(obstacles)), errors_(std::move(errors)), r_(point ? 0.0 : m.probe.ball_radius_mm()),
        len_(point ? 0.0 : m.probe.stylus_length_mm) {}

  // The workpiece frame in the machine frame: nominal, or on the machine with its location errors
  // (a compensated program is written for that machine).
  Eigen::Isometry3d T(const Pose& pose) const {
    return errors_ ? T_m_w(*errors_, pose) : T_m_w_nominal(m_.kinematics, pose);
  }

  bool empty() const { return obstacles_.empty(); }
  size_t size() const { return obstacles_.size(); }

  // Gap between the probe (ball and stylus: a capsule of the ball's radius from the ball centre
  // up the tool axis, machine +Z on a table machine) and the nearest obstacle.
  // `axes_m`: the X Y Z reading, which a head carries the ball away from.
  Gap gap(const Eigen::Vector3d& axes_m, const Pose& pose) const {
    Gap best;
    if (obstacles_.empty()) return best;
    const Eigen::Isometry3d Tinv = T(pose).inverse();
    const Eigen::Vector3d a = Tinv * (axes_m + ballFromAxes_m(m_, pose));
    const Eigen::Vector3d u = Tinv.linear() * stylusAxis_m(m_, pose);
    for (const auto& o : obstacles_) {
      double d;
      if (o.shape == Obstacle::Shape::Sphere) d = segmentSphereDistance(a, u, len_, o.centre) - o.radius;
      else d = minOnSegment([&](double t) { return o.sdf(a + t * u); }, len_);
      d -= r_;
      if (d < best.mm) best = {d, &o};
    }
    return best;
  }

  // Lower bound of the gap when X or Y (or the table angle) is unknown: the probe stands above
  // its ball centre, so it clears whatever lies lower than ball z - r by the difference.
  // From pose a to pose b (interpolated together), or at any angle when they are not known. The
  // top of an obstacle moves by at most reach x the rotary step (rad): sampled at steps of
  // kSweepResolutionMm in that bound, plus that resolution.
  // On a head machine `axes_z` is the pivot's: the probe's lowest point hangs below it by the
  // head's offset at the angle (any angle while it is not known; a stylus tilted past the
  // horizontal reaches lower than its ball), sampled with the obstacles.
  double gapBelow(double axes_z, const std::optional<Pose>& a, const std::optional<Pose>& b) const {
    double top = -std::numeric_limits<double>::infinity();
    double reach = 0.0;
    for (const auto& o : obstacles_) reach = std::max(reach, o.reach());
    const double L = ballDropBelowAxes(m_);
    if (!a || !b) return axes_z - L - len_ * (L > 0 ? 1.0 : 0.0) - r_ - reach;
    const double turn = (std::abs(b->A - a->A) + std::abs(b->B - a->B) + std::abs(b->C - a->C)) * 3.14159265358979323846 / 180.0;
    const int n = std::min(200000, static_cast<int>(std::ceil((reach + L + len_ * (L > 0 ? 1.0 : 0.0)) * turn / kSweepResolutionMm)));
    double drop = 0.0;
    for (int i = 0; i <= n; ++i) {
      const double s = n == 0 ? 0.0 : static_cast<double>(i) / n;
      const Pose p{(1 - s) * a->A + s * b->A, (1 - s) * a->B + s * b->B, (1 - s) * a->C + s * b->C};
      for (const auto& o : obstacles_) top = std::max(top, o.top(T(p)));
      drop = std::max(drop, -(ballFromAxes_m(m_, p).z() + std::min(0.0, len_ * stylusAxis_m(m_, p).z())));
    }
    return axes_z - drop - r_ - top - (n > 0 ? kSweepResolutionMm : 0.0);
  }

  double stylus() const { return len_; }

 private:
  const MachineModel& m_;
  std::vector<Obstacle> obstacles_;
  std::optional<GeometricErrors> errors_;
  double r_, len_;
};

std::vector<Obstacle> obstaclesOf(const ProgramCheckSetup& s) {
  std::vector<Obstacle> out;
  const MachineModel& m = *s.machine;
  // A head machine's XYZ are its pivot's, not the ball centre's: without its "head" (004's
  // head_ab carries a tester's sphere, not a probe) there is no ball to model (strokes,
  // guards, feeds and numbers are still checked). With it, Simulator::gap carries the ball by
  // the head's offset.
  if (m.kinematics == Kinematics::HeadAB && !m.head) return out;
  // A part program on a head machine: its X Y Z read the pivot and the tool hangs from it by its
  // own length, which the tool table holds: nothing to place against the table.
  if (s.part_program && m.head) return out;
  if (m.artefact && s.artefact_on_table && !s.part_program) {
    const SquareColumn& c = *m.artefact;
    Obstacle b;
    b.name = "the artefact";
    b.centre = c.top_centre_w - Eigen::Vector3d(0, 0, c.size_mm.z() / 2);
    b.half = c.size_mm / 2;
    out.push_back(b);
  }
  // The table's top: declared, or the column's bottom face (it stands on the table).
  std::optional<double> top = m.table_top_z_mm;
  if (!top && m.artefact) top = m.artefact->top_centre_w.z() - m.artefact->size_mm.z();
  if (top) {
    Obstacle t;
    t.shape = Obstacle::Shape::Disc;
    t.name = "the table";
    t.centre = Eigen::Vector3d(0, 0, *top);
    t.radius = m.table_diameter_mm / 2;
    // A part program's tool must not cross the top: the table as a slab (a probe keeps its gap
    // above the top, where the two are one).
    if (s.part_program) t.depth = kTableSlabMm;
    out.push_back(t);
  }
  if (s.plan && !s.part_program) {
    std::set<int> seen;
    for (const auto& p : s.plan->points)
      if (p.sphere && seen.insert(p.sphere->id).second) {
        Obstacle o;
        o.shape = Obstacle::Shape::Sphere;
        o.name = fmt::format("sphere {}", p.sphere->id);
        o.centre = p.sphere->center_w_mm;
        o.radius = p.sphere->radius_mm;
        out.push_back(o);
      }
  }
  return out;
}

double& axisOf(Pose& p, char a) { return a == 'A' ? p.A : a == 'B' ? p.B : p.C; }

struct Config {
  std::array<std::optional<double>, 3> xyz;  // mm, machine frame (ball centre)
  std::map<char, std::optional<double>> rot;  // paper-convention deg
  bool known() const {
    for (const auto& v : xyz)
      if (!v) return false;
    for (const auto& [a, v] : rot)
      if (!v) return false;
    return true;
  }
  bool rotKnown() const {
    for (const auto& [a, v] : rot)
      if (!v) return false;
    return true;
  }
  Eigen::Vector3d p() const { return Eigen::Vector3d(*xyz[0], *xyz[1], *xyz[2]); }
  Pose pose() const {
    Pose q;
    for (const auto& [a, v] : rot) axisOf(q, a) = v ? *v : 0.0;
    return q;
  }
};

struct SweepResult {
  double min_lb = std::numeric_limits<double>::infinity();  // certified lower bound of the gap
  double min_gap = std::numeric_limits<double>::infinity();  // smallest sampled gap
  const Obstacle* nearest = nullptr;
  double g0 = 0.0, g1 = 0.0;
  double contact_s = -1.0;  // probing: where the probe first touches (-1: never)
};

}  // namespace

ProgramCheckResult checkProgram(const std::vector<nc::Motion>& motions, const ProgramCheckSetup& setup) {
  if (!setup.machine) throw std::invalid_argument("checkProgram: no machine");
  const MachineModel& m = *setup.machine;
  ProgramCheckResult res;
  const Simulator sim(m, obstaclesOf(setup),
                      setup.errors && hasPapersLocationErrors(m.kinematics) ? setup.errors : std::nullopt,
                      setup.part_program);
  res.obstacles = static_cast<int>(sim.size());
  const double planned = std::min(m.clearance_mm, m.approach_mm);
  res.required_gap_mm = setup.part_program ? 0.0 : planned - std::min(kCompensationAllowanceMm, 0.5 * planned);
  const double need = res.required_gap_mm;
  const Eigen::Vector3d& origin = setup.program_origin_m_mm;
  auto violation = [&](int line, std::string what) { res.violations.push_back({line, std::move(what)}); };

  // Where the program starts: X, Y and Z are wherever the operator left them (the first move
  // must take Z alone to a safe height); the rotary axes are taken at their zero (the machine's
  // home): a program is proven safe when started there (docs/safety.md).
  Config cur;
  for (const auto& r : m.rotary) cur.rot[r.name] = 0.0;
  bool feed_set = false, inverse_time = false;
  struct PendingProbe {
    int line = 0;
    Eigen::Vector3d end_units = Eigen::Vector3d::Zero();
    bool alarms = false;
  };
  std::optional<PendingProbe> pending;
  std::optional<int> near_end_line;  // a non-probing move that ended nearer than `need`
  double near_end_gap = 0.0;
  std::vector<int> numbers;

  // Sweeps from `a` to `b` (both fully known) with the certified step. `floor`: the gap the move
  // must keep; probing moves (floor 0) stop at the first contact.
  auto sweep = [&](const Config& a, const Config& b, double floor, bool probing) {
    SweepResult out;
    const Eigen::Vector3d p0 = a.p(), p1 = b.p();
    double rot_rad = 0.0;
    for (const auto& [ax, v] : a.rot) rot_rad += std::abs(*b.rot.at(ax) - *v) * kDegToRad;
    // Distance from the rotary axes; with location errors the axes are off the origin by their
    // offsets (at most the plausibility limit, 0.5 mm, unless forced): 10 mm covers them.
    const double rho = std::max((p0 + origin).norm(), (p1 + origin).norm()) + ballDropBelowAxes(m) + sim.stylus() +
                       (setup.errors ? 10.0 : 0.0);
    const double D = (p1 - p0).norm() + rot_rad * rho;  // mm per unit s, for any point of the probe
    auto at = [&](double s) {
      Config c = a;
      for (int i = 0; i < 3; ++i) c.xyz[static_cast<size_t>(i)] = (1 - s) * p0[i] + s * p1[i];
      for (auto& [ax, v] : c.rot) v = (1 - s) * *a.rot.at(ax) + s * *b.rot.at(ax);
      ++res.swept_samples;
      return sim.gap(c.p() + origin, c.pose());
    };
    double s = 0.0;
    for (;;) {
      const Gap g = at(s);
      if (s == 0.0) out.g0 = g.mm;
      if (g.mm < out.min_gap) {
        out.min_gap = g.mm;
        out.nearest = g.what;
      }
      if (probing && g.mm <= kSweepResolutionMm) {
        out.contact_s = s;
        out.g1 = g.mm;
        return out;
      }
      if (s >= 1.0 || D <= 0.0) {
        out.g1 = g.mm;
        out.min_lb = std::min(out.min_lb, g.mm);
        return out;
      }
      const double step_mm = std::max(probing ? g.mm : 0.5 * (g.mm - floor), kSweepResolutionMm);
      const double ds = std::min(step_mm / D, 1.0 - s);
      out.min_lb = std::min(out.min_lb, g.mm - ds * D);
      s += ds;
      if (1.0 - s < 1e-12) s = 1.0;
    }
  };

  auto strokeCheck = [&](int line, const Config& c) {
    const char names[3] = {'X', 'Y', 'Z'};
    const AxisRange* ranges[3] = {&m.x, &m.y, &m.z};
    for (int i = 0; i < 3; ++i) {
      const auto& v = c.xyz[static_cast<size_t>(i)];
      if (v && !ranges[i]->contains(*v + origin[i], kStrokeTolMm))
        violation(line, fmt::format("{} = {:.4f} mm{} is outside the {} stroke [{:g}, {:g}] mm", names[i], *v,
                                    origin[i] == 0.0 ? std::string() : fmt::format(" (machine {:.4f} mm)", *v + origin[i]),
                                    names[i], ranges[i]->min, ranges[i]->max));
    }
    for (const auto& r : m.rotary) {
      const auto& v = c.rot.at(r.name);
      if (v && !r.continuous && !r.stroke_deg.contains(*v, kRotaryStrokeTolDeg))
        violation(line, fmt::format("{} = {:.4f} deg (papers' convention) is outside the {} stroke [{:g}, {:g}] deg", r.name,
                                    *v, r.name, r.stroke_deg.min, r.stroke_deg.max));
    }
  };

  // The configuration after a move's words.
  auto apply = [&](const nc::Motion& mo, Config c) {
    const double unit = mo.inch ? kMmPerInch : 1.0;
    // Z to its reference, the top of the stroke, counted in the machine: in the program's
    // coordinates that is the stroke's top less the program's zero.
    if (mo.z_from_reference) c.xyz[2] = m.z.max + *mo.z_from_reference * unit - origin.z();
    for (const auto& [letter, value] : mo.words) {
      if (letter == 'X' || letter == 'Y' || letter == 'Z') {
        auto& v = c.xyz[static_cast<size_t>(letter - 'X')];
        if (mo.incremental) {
          if (v) v = *v + value * unit;
        } else {
          v = value * unit;
        }
      } else if (!m.hasRotary(letter)) {
        violation(mo.line, fmt::format("{} is not a rotary axis of this machine", letter));
      } else {
        const double paper = value / m.controllerSign(letter, setup.dialect);
        auto& v = c.rot[letter];
        if (mo.incremental) {
          if (v) v = *v + paper;
        } else {
          v = paper == 0.0 ? 0.0 : paper;
        }
      }
    }
    return c;
  };

  auto closePending = [&](int next_line) {
    if (pending && !pending->alarms)
      violation(pending->line, fmt::format("probing move without its no-trigger check before the next move (line {}): a "
                                           "probe that never triggers would end silently at its end point",
                                           next_line));
    pending.reset();
  };

  // A move between (possibly partly unknown) configurations, not probing.
  auto positioning = [&](const nc::Motion& mo, const Config& a, const Config& b) {
    if (sim.empty()) return;
    if (a.known() && b.known()) {
      // First the end gaps, to know the floor: never nearer than the required gap, or than where
      // the move starts or ends when that is nearer (leaving a touch, setting up the next one).
      const double g0 = sim.gap(a.p() + origin, a.pose()).mm;
      const Gap end_gap = sim.gap(b.p() + origin, b.pose());
      const double g1 = end_gap.mm;
      // Only a probing move stops at a surface; any other move that ends inside one has hit it.
      if (g1 < -kSweepResolutionMm)
        violation(mo.line, fmt::format("this move ends {:.3f} mm inside {}: only a guarded probing move may reach a "
                                       "surface",
                                       -g1, end_gap.what ? end_gap.what->name : "an obstacle"));
      const double floor = std::min({need, g0, g1});
      const SweepResult r = sweep(a, b, floor, false);
      if (r.min_lb < floor - kSweepResolutionMm - 1e-9)
        violation(mo.line, fmt::format("this move comes within {:.3f} mm of {} (it must keep {:.3f} mm: a move toward a "
                                       "surface must be a guarded probing move)",
                                       std::max(r.min_gap, r.min_lb), r.nearest ? r.nearest->name : "an obstacle",
                                       floor));
      if (g0 >= need && g1 >= need) res.min_clearance_mm = std::min(res.min_clearance_mm, r.min_gap);
      if (g1 < need) {
        near_end_line = mo.line;
        near_end_gap = g1;
      }
      return;
    }
    // Part of the position is not known yet (the program's first moves): what the probe clears
    // at any X, Y and, while the angle is unknown or turning, at any table angle.
    if (setup.part_program && !a.xyz[2]) return;  // the operator's set-up: a part program starts where they stand
    if (!a.xyz[2] && !b.xyz[2]) {
      violation(mo.line, "a move before the program has set Z: the first move must take Z alone to a safe height");
      return;
    }
    if (!a.xyz[2]) {
      // The machine stands where the operator left it: the move must be Z alone.
      for (const auto& [letter, v] : mo.words)
        if (letter != 'Z')
          violation(mo.line, "the first move must take Z alone to a safe height: where the machine stands is unknown");
    }
    const double zmin = a.xyz[2] ? std::min(*a.xyz[2], *b.xyz[2]) : *b.xyz[2];
    const bool turning = a.pose().A != b.pose().A || a.pose().B != b.pose().B || a.pose().C != b.pose().C;
    const bool known = a.rotKnown() && b.rotKnown();
    const double lb = sim.gapBelow(zmin + origin.z(), known ? std::optional<Pose>(a.pose()) : std::nullopt,
                                   known ? std::optional<Pose>(b.pose()) : std::nullopt);
    ++res.swept_samples;
    if (lb < need)
      violation(mo.line, fmt::format("X, Y{} not known yet here: the {} at Z {:.3f} mm clears what it may pass over "
                                     "by only {:.3f} mm (it must keep {:.3f} mm at any position)",
                                     turning ? " or the table angle" : "", setup.part_program ? "tool" : "probe",
                                     zmin, lb, need));
    else
      res.min_clearance_mm = std::min(res.min_clearance_mm, lb);
  };

  for (const auto& mo : motions) {
    using K = nc::Motion::Kind;
    if (mo.kind == K::Unreadable) {
      violation(mo.line, mo.problem);
      continue;
    }
    if (mo.kind == K::ProgramNumber) {
      numbers.push_back(mo.line);
      if (numbers.size() > 1) violation(mo.line, "a second program number in one program");
      else if (setup.program_number && mo.number != *setup.program_number)
        violation(mo.line, fmt::format("program number {} is not this cycle's ({}): each cycle has its own number, so "
                                       "that two programs never overwrite each other in the control",
                                       mo.number, *setup.program_number));
      else if (!setup.program_number && !setup.rotacal_numbers.empty() &&
               std::find(setup.rotacal_numbers.begin(), setup.rotacal_numbers.end(), mo.number) ==
                   setup.rotacal_numbers.end())
        violation(mo.line, fmt::format("program number {} is none of rotacal's cycle numbers", mo.number));
      continue;
    }
    if (mo.kind == K::Check) {
      if (!pending) {
        violation(mo.line, "a no-trigger check with no probing move before it");
        continue;
      }
      for (int a = 0; a < 3; ++a) {
        const auto& e = mo.check_end[static_cast<size_t>(a)];
        if (e && std::abs(*e - pending->end_units[a]) > kCheckEndTolerance)
          violation(mo.line, fmt::format("the no-trigger check compares {} with {:.4f} but the probing move at line {} "
                                         "ends at {:.4f}: a probe that never triggers would pass (a stale check)",
                                         "XYZ"[a], *e, pending->line, pending->end_units[a]));
      }
      pending.reset();
      continue;
    }
    // Modes and feeds.
    if (mo.inverse_time != inverse_time) {
      inverse_time = mo.inverse_time;
      feed_set = false;  // a G93 F is no per-minute feed, and G94 wants its own F
    }
    if (mo.feed) {
      if (!(*mo.feed > 0)) violation(mo.line, fmt::format("F{:g}: a feed must be > 0", *mo.feed));
      else if (!inverse_time) feed_set = true;
    }
    if (mo.kind == K::Setting) continue;
    closePending(mo.line);
    if (mo.kind == K::End) {
      if (near_end_line)
        violation(*near_end_line, fmt::format("this move ends {:.3f} mm from a surface (less than {:.3f} mm) and no "
                                              "probing move follows it",
                                              near_end_gap, need));
      break;
    }
    ++res.motion_blocks;
    if (near_end_line && mo.kind != K::Probe)
      violation(*near_end_line, fmt::format("this move ends {:.3f} mm from a surface (less than {:.3f} mm) and the next "
                                            "move (line {}) is no probing move",
                                            near_end_gap, need, mo.line));
    near_end_line.reset();
    if (mo.kind == K::Feed) {
      if (inverse_time && !mo.feed)
        violation(mo.line, "inverse-time (G93) move without F: every G93 block needs its own F");
      else if (!inverse_time && !feed_set)
        violation(mo.line, "feed move before any feed is set");
    }
    if (mo.kind == K::Rapid || mo.kind == K::Feed) {
      const Config next = apply(mo, cur);
      strokeCheck(mo.line, next);
      positioning(mo, cur, next);
      cur = next;
      continue;
    }
    // Probing move.
    ++res.probing_moves;
    if (inverse_time) violation(mo.line, "probing move under inverse time (G93)");
    else if (!mo.feed_from_control && !feed_set) violation(mo.line, "probing move before any feed is set");
    Config start = cur;
    Config end;
    const double unit = mo.inch ? kMmPerInch : 1.0;
    if (mo.travel_axis) {
      // Heidenhain cycle 0: to the pre-position, then along one axis for the maximum travel of the
      // touch-probe table, which the program's header sets to approach + overtravel.
      start = apply(mo, cur);
      strokeCheck(mo.line, start);
      positioning(mo, cur, start);
      near_end_line.reset();
      end = start;
      auto& v = end.xyz[static_cast<size_t>(*mo.travel_axis)];
      if (v) v = *v + mo.travel_sign * (m.approach_mm + m.overtravel_mm);
    } else {
      end = apply(mo, cur);
    }
    strokeCheck(mo.line, end);
    PendingProbe pp;
    pp.line = mo.line;
    pp.alarms = mo.alarms;
    for (int i = 0; i < 3; ++i) {
      const auto& v = end.xyz[static_cast<size_t>(i)];
      pp.end_units[i] = v ? *v / unit : std::numeric_limits<double>::quiet_NaN();
    }
    pending = pp;
    if (!start.known() || !end.known()) {
      violation(mo.line, "probing move from a position the program has not set");
      cur = end;
      continue;
    }
    if (sim.empty()) {
      cur = end;
      continue;
    }
    const SweepResult r = sweep(start, end, 0.0, true);
    if (r.g0 <= 0.0)
      violation(mo.line, fmt::format("probing move starts in contact with {}", r.nearest ? r.nearest->name : "an obstacle"));
    // A probe that never triggers (a broken cable, a dead battery) runs to the end point: the
    // stylus deflects by the overtravel and no more. The contact found above says nothing of
    // that case; the end must lie no deeper than the overtravel (and what compensate may shift).
    const double deepest = m.overtravel_mm + kCompensationAllowanceMm + kSweepResolutionMm;
    if (const Gap ge = sim.gap(end.p() + origin, end.pose()); ge.mm < -deepest)
      violation(mo.line, fmt::format("probing move ends {:.3f} mm inside {}: a probe that does not trigger is driven "
                                     "past its overtravel ({:.3f} mm)",
                                     -ge.mm, ge.what ? ge.what->name : "an obstacle", m.overtravel_mm));
    if (r.contact_s < 0) {
      if (setup.plan)
        violation(mo.line, fmt::format("probing move reaches no surface (it ends {:.3f} mm from the nearest): it cannot "
                                       "trigger where the plan expects",
                                       r.g1));
      cur = end;  // untriggered: the probe stops at the end point
    } else {
      // The probe stops at its first contact: the moves after it start there.
      Config c = start;
      const Eigen::Vector3d p = start.p() + r.contact_s * (end.p() - start.p());
      for (int i = 0; i < 3; ++i) c.xyz[static_cast<size_t>(i)] = p[i];
      cur = c;
    }
  }
  closePending(motions.empty() ? 0 : motions.back().line);
  if (setup.numbered && numbers.empty())
    violation(1, setup.program_number ? fmt::format("the program has no program number (this cycle's is {})",
                                                    *setup.program_number)
                                      : std::string("the program has no program number"));
  std::stable_sort(res.violations.begin(), res.violations.end(),
                   [](const ProgramViolation& a, const ProgramViolation& b) { return a.line < b.line; });
  return res;
}

}  // namespace rotacal
