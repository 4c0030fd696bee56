#include "cycles/touch154/closed_form.hpp"

#include <Eigen/Dense>
#include <cmath>
#include <map>
#include <stdexcept>

#include <fmt/format.h>

#include "core/units.hpp"

namespace rotacal {

namespace {

enum { kDx = 0, kDy, kDz, kDyCA, kA, kB, kC, kBCA };

struct Sample {
  const ProbePoint* point = nullptr;
  Eigen::Vector3d p = Eigen::Vector3d::Zero();   // measured ball centre, machine
  Eigen::Vector3d dp = Eigen::Vector3d::Zero();  // Eq. (21)
  Eigen::Vector3d P = Eigen::Vector3d::Zero();   // nominal contact, machine
  Eigen::Vector3d n_m = Eigen::Vector3d::Zero();
};

class Samples {
 public:
  Samples(const ProbePlan& plan, const MeasurementRun& run) {
    std::map<int, const TriggerPoint*> by_id;
    for (const auto& t : run.points) by_id[t.point_id] = &t;
    for (const auto& p : plan.points) {
      const auto it = by_id.find(p.id);
      if (it == by_id.end()) continue;
      Sample s;
      s.point = &p;
      s.p = it->second->position_m_mm;
      const Eigen::Isometry3d T = T_m_w_nominal(plan.machine.kinematics, p.pose);
      s.P = T * p.contact_w_mm;
      s.n_m = T.linear() * p.normal_w;
      at_[{p.pose_name, p.target}] = s;
    }
    for (auto& [key, s] : at_) {
      const Sample* ref = find("I", key.second);
      if (!ref) continue;
      const Eigen::Matrix3d R0 = T_m_w_nominal(plan.machine.kinematics, s.point->pose).linear();
      s.dp = s.p - R0 * ref->p;
    }
  }
  const Sample* find(const std::string& pose, int target) const {
    const auto it = at_.find({pose, target});
    if (it == at_.end() || !find_ref(target)) return nullptr;
    return &it->second;
  }
  std::vector<int> targets(const std::string& pose) const {
    std::vector<int> t;
    for (const auto& [key, s] : at_)
      if (key.first == pose && find_ref(key.second)) t.push_back(key.second);
    return t;
  }

 private:
  bool find_ref(int target) const { return at_.count({"I", target}) > 0; }
  std::map<std::pair<std::string, int>, Sample> at_;
};

bool facing(const Sample& s, int axis, int sign) { return sign * s.n_m[axis] > 0.99; }
bool facingAxis(const Sample& s, int axis) { return std::abs(s.n_m[axis]) > 0.99; }

void finish(PatternEquation& eq, const std::string& what) {
  if (eq.points == 0) throw std::invalid_argument("closed form: no points for pattern " + eq.name + " (" + what + ")");
  eq.value_mm /= eq.points;
  eq.row /= eq.points;
}

double slope(const std::vector<double>& x, const std::vector<double>& y) {
  double mx = 0, my = 0;
  for (size_t i = 0; i < x.size(); ++i) { mx += x[i]; my += y[i]; }
  mx /= static_cast<double>(x.size());
  my /= static_cast<double>(y.size());
  double sxy = 0, sxx = 0;
  for (size_t i = 0; i < x.size(); ++i) { sxy += (x[i] - mx) * (y[i] - my); sxx += (x[i] - mx) * (x[i] - mx); }
  return sxy / sxx;
}

}  // namespace

std::vector<PatternEquation> touch154Patterns(const ProbePlan& plan, const MeasurementRun& run) {
  if (plan.machine.kinematics != Kinematics::TableAC)
    throw std::invalid_argument("closed form: needs an A/C machine");
  for (const char* name : {"I", "II", "III", "IV", "V", "VI", "VII"}) plan.poseByName(name);
  const Samples S(plan, run);
  const Pose pose_check = plan.poseByName("V").pose;
  if (std::abs(pose_check.A + 90) > 1e-9) throw std::invalid_argument("closed form: pose V must be A = -90 deg");
  std::vector<PatternEquation> eqs;

  // Patterns 1 and 2-c: the top face at two poses C 180 deg apart, `to` after `from`;
  // z2 - z1 = 2 y~ a_AY - 2 x~ (b_AY + b_CA), one of the two terms vanishing on each pair.
  auto topFace = [&](PatternEquation e, const char* from, const char* to, const std::string& where) {
    for (int k : S.targets(to)) {
      const Sample* i = S.find(from, k);
      const Sample* ii = S.find(to, k);
      if (!i || !facing(*i, 2, 1)) continue;
      e.value_mm += ii->dp.z() - i->dp.z();
      e.row[kA] += ii->P.y() - i->P.y();
      e.row[kB] += -(ii->P.x() - i->P.x());
      e.row[kBCA] += -(ii->P.x() - i->P.x());
      ++e.points;
    }
    finish(e, where);
    eqs.push_back(e);
  };
  // Pattern 1 (Eq. 6): top face, C 0 -> 180; z2 - z1 = 2 y~ a_AY (- 2 x~ (b_AY + b_CA)).
  topFace({"1", "z2 - z1 = 2 y~ a_AY", 0, ErrorVector::Zero(), 0}, "I", "III", "top face at I and III");
  {  // Pattern 2-a (Eq. 7): faces facing +-X at IV and II; x1 + x2 = 2 dx_AY + 2 z~ (b_AY + b_CA).
    PatternEquation e{"2-a", "x1 + x2 = 2 dx_AY + 2 z~ (b_AY + b_CA)", 0, ErrorVector::Zero(), 0};
    for (int k : S.targets("II")) {
      const Sample* i = S.find("IV", k);
      const Sample* ii = S.find("II", k);
      if (!i || !facingAxis(*i, 0) || !facingAxis(*ii, 0)) continue;
      e.value_mm += i->dp.x() + ii->dp.x();
      e.row[kDx] += 2;
      e.row[kB] += i->P.z() + ii->P.z();
      e.row[kBCA] += i->P.z() + ii->P.z();
      e.row[kC] += -(i->P.y() + ii->P.y());
      ++e.points;
    }
    finish(e, "faces facing X at II and IV");
    eqs.push_back(e);
  }
  {  // Pattern 2-b (Eq. 8): faces facing +-Y at I and III; y2 + y1 = 2 (dy_AY + dy_CA) - 2 z~ a_AY.
    PatternEquation e{"2-b", "y2 + y1 = 2 (dy_AY + dy_CA) - 2 z~ a_AY", 0, ErrorVector::Zero(), 0};
    for (int k : S.targets("III")) {
      const Sample* i = S.find("I", k);
      const Sample* ii = S.find("III", k);
      if (!facingAxis(*i, 1) || !facingAxis(*ii, 1)) continue;
      e.value_mm += ii->dp.y() + i->dp.y();
      e.row[kDy] += 2;
      e.row[kDyCA] += 2;
      e.row[kA] += -(i->P.z() + ii->P.z());
      e.row[kC] += i->P.x() + ii->P.x();
      ++e.points;
    }
    finish(e, "faces facing Y at I and III");
    eqs.push_back(e);
  }
  // Pattern 2-c (Eq. 9): top face, C 270 -> 90; z2 - z1 = 2 x~ (b_AY + b_CA) (- 2 y~ a_AY).
  topFace({"2-c", "z2 - z1 = 2 x~ (b_AY + b_CA)", 0, ErrorVector::Zero(), 0}, "IV", "II", "top face at IV and II");
  const std::vector<std::pair<std::string, std::string>> tilt_pairs = {{"II", "V"}, {"III", "VI"}, {"IV", "VII"}};
  {  // Pattern 3-a (Eq. 10): faces facing +-X at A = 0 and A = -90.
    PatternEquation e{"3-a", "x2 - x1 = (z~2 - z~1) b_AY + (y~1 - y~2) c_AY", 0, ErrorVector::Zero(), 0};
    for (const auto& [pi, pii] : tilt_pairs)
      for (int k : S.targets(pii)) {
        const Sample* i = S.find(pi, k);
        const Sample* ii = S.find(pii, k);
        if (!i || !facingAxis(*i, 0) || !facingAxis(*ii, 0)) continue;
        e.value_mm += ii->dp.x() - i->dp.x();
        e.row[kB] += ii->P.z() - i->P.z();
        e.row[kC] += i->P.y() - ii->P.y();
        ++e.points;
      }
    finish(e, "faces facing X at A = 0 and A = -90");
    eqs.push_back(e);
  }
  {  // Pattern 3-b (Eq. 11): a face facing +Y at A = 0 faces +Z at A = -90.
    PatternEquation e{"3-b", "z2 - y1 = dz_AY - dy_AY (- (b_AY + c_AY) x~)", 0, ErrorVector::Zero(), 0};
    for (const auto& [pi, pii] : tilt_pairs)
      for (int k : S.targets(pii)) {
        const Sample* i = S.find(pi, k);
        const Sample* ii = S.find(pii, k);
        if (!i || !facing(*i, 1, 1) || !facing(*ii, 2, 1)) continue;
        e.value_mm += ii->dp.z() - i->dp.y();
        e.row[kDz] += 1;
        e.row[kDy] += -1;
        e.row[kA] += ii->P.y() + i->P.z();
        e.row[kB] += -i->P.x();
        e.row[kC] += -i->P.x();
        ++e.points;
      }
    finish(e, "faces facing +Y at A = 0 and +Z at A = -90");
    eqs.push_back(e);
  }
  {  // Pattern 3-c (Eq. 12): the top face faces -Y at A = -90.
    PatternEquation e{"3-c", "y2 + z1 = dz_AY + dy_AY (+ (c_AY - b_AY) x~)", 0, ErrorVector::Zero(), 0};
    for (const auto& [pi, pii] : tilt_pairs)
      for (int k : S.targets(pii)) {
        const Sample* i = S.find(pi, k);
        const Sample* ii = S.find(pii, k);
        if (!i || !facing(*i, 2, 1) || !facing(*ii, 1, -1)) continue;
        e.value_mm += ii->dp.y() + i->dp.z();
        e.row[kDy] += 1;
        e.row[kDz] += 1;
        e.row[kA] += i->P.y() - ii->P.z();
        e.row[kB] += -i->P.x();
        e.row[kC] += i->P.x();
        ++e.points;
      }
    finish(e, "top face at A = 0 and A = -90");
    eqs.push_back(e);
  }
  {  // Pattern 4 (Eq. 13): angle_z of the top face (facing -Y) at V and VII.
    PatternEquation e{"4", "angle_z(y2) + angle_z(y1) = 2 (c_AY + b_CA)", 0, ErrorVector::Zero(), 0};
    for (const char* pose : {"V", "VII"}) {
      std::vector<double> x, dy, fc, fbca, fa, fb;
      for (int k : S.targets(pose)) {
        const Sample* s = S.find(pose, k);
        if (!facing(*s, 1, -1) || s->point->face != Face::Top) continue;
        const Eigen::Vector3d& pw = s->point->contact_w_mm;
        x.push_back(s->P.x());
        dy.push_back(s->dp.y());
        fc.push_back(s->P.x());
        fbca.push_back(s->P.x() - pw.x());
        fa.push_back(pw.y() - s->P.z());
        fb.push_back(-pw.x());
      }
      if (x.size() < 2) throw std::invalid_argument(std::string("closed form: pattern 4 needs >= 2 top points at pose ") + pose);
      e.value_mm += slope(x, dy);
      e.row[kC] += slope(x, fc);
      e.row[kBCA] += slope(x, fbca);
      e.row[kA] += slope(x, fa);
      e.row[kB] += slope(x, fb);
      e.points += static_cast<int>(x.size());
    }
    eqs.push_back(e);
  }
  return eqs;
}

LocationErrors solvePatterns(const std::vector<PatternEquation>& patterns) {
  Eigen::MatrixXd A(patterns.size(), kNumLocationErrors);
  Eigen::VectorXd m(patterns.size());
  for (size_t i = 0; i < patterns.size(); ++i) {
    A.row(static_cast<long>(i)) = patterns[i].row.transpose();
    m[static_cast<long>(i)] = patterns[i].value_mm;
  }
  LocationErrors e;
  e.kinematics = Kinematics::TableAC;
  e.values = A.colPivHouseholderQr().solve(m);
  return e;
}

IdentificationResult identifyClosedForm(const ProbePlan& plan, const std::vector<MeasurementRun>& runs, double prior_sigma_um) {
  IdentificationResult out;
  out.method = Method::ClosedForm;
  out.estimate.kinematics = plan.machine.kinematics;
  try {
    ErrorVector sum = ErrorVector::Zero();
    ErrorVector var = ErrorVector::Zero();
    for (const auto& run : runs) {
      const auto eqs = touch154Patterns(plan, run);
      const LocationErrors e = solvePatterns(eqs);
      sum += e.values;
      // The closed form is linear in the measured coordinates: propagate the probe's
      // repeatability through it by unit perturbations of each trigger along its approach.
      const double h = 1e-3;
      MeasurementRun pert = run;
      for (size_t i = 0; i < run.points.size(); ++i) {
        const ProbePoint* p = plan.findPoint(run.points[i].point_id);
        if (!p) continue;
        pert.points[i].position_m_mm += h * p->approach_m;
        const ErrorVector d = (solvePatterns(touch154Patterns(plan, pert)).values - e.values) / h;
        var += d.cwiseAbs2();
        pert.points[i].position_m_mm = run.points[i].position_m_mm;
      }
      out.summary.observations += static_cast<int>(run.points.size());
    }
    const double nr = static_cast<double>(runs.size());
    out.estimate.values = sum / nr;
    const double sigma = umToMm(prior_sigma_um);
    out.u = (var / (nr * nr)).cwiseSqrt() * sigma;
    out.covariance = out.u.cwiseAbs2().asDiagonal();
    out.summary.termination = Termination::Converged;
    out.summary.parameters = kNumLocationErrors;
    out.summary.rank = kNumLocationErrors;
    out.summary.sigma_um = prior_sigma_um;
    out.summary.message = "closed form (000 Eqs. (14)-(19), corrected); u from the probe repeatability";
  } catch (const std::invalid_argument& e) {
    out.summary.termination = Termination::InvalidInput;
    out.summary.message = e.what();
  }
  return out;
}

IdentificationResult identifyTouch154(const ProbePlan& plan, const std::vector<MeasurementRun>& runs,
                                      const IdentificationOptions& options) {
  if (options.method != Method::ClosedForm) return identify(plan, runs, options);
  IdentificationResult bad;
  bad.method = Method::ClosedForm;
  bad.estimate.kinematics = plan.machine.kinematics;
  std::string why;
  if (!options.validate(&why)) bad.summary.message = "invalid options: " + why;
  else if (runs.empty()) bad.summary.message = "no results to identify from";
  else if (!plan.machine.artefact) bad.summary.message = "the plan has no artefact";
  else return identifyClosedForm(plan, runs, options.prior_sigma_um);
  return bad;
}

}  // namespace rotacal
