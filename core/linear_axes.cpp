#include "core/linear_axes.hpp"

#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

namespace rotacal {

void AxisNodes::locate(double q, int* k, double* t) const {
  const int n = static_cast<int>(mm[0].size());
  const double f = q * (inv_spacing > 0.0 ? inv_spacing : 1.0 / spacing_mm) - first;
  int i = static_cast<int>(f);  // floor without a libm call (the hot loop of the Monte Carlo)
  if (f < i) --i;
  if (i < 0) {
    *k = 0;
    *t = 0.0;
  } else if (i >= n - 1) {
    *k = n - 2;
    *t = 1.0;
  } else {
    *k = i;
    *t = f - i;
  }
}

Eigen::Vector3d AxisNodes::at(double q) const {
  if (spacing_mm <= 0.0 || mm[0].size() < 2) return Eigen::Vector3d::Zero();
  int k;
  double t;
  locate(q, &k, &t);
  Eigen::Vector3d v;
  for (int c = 0; c < 3; ++c) v[c] = (1.0 - t) * mm[c][static_cast<size_t>(k)] + t * mm[c][static_cast<size_t>(k + 1)];
  return v;
}

double nodeCorrelation(double x, double y, double lo, double hi) {
  if (std::abs(x - y) >= 2.0 * hi) return 0.0;  // no node's hat covers both
  const int steps = lo == hi ? 1 : 256;
  double sum = 0.0;
  for (int q = 0; q < steps; ++q) {
    const double p = lo + (hi - lo) * (q + 0.5) / steps;
    const double fx = x / p, fy = y / p;
    const double kx = std::floor(fx), ky = std::floor(fy);
    if (std::abs(kx - ky) > 1.0) continue;
    const double tx = fx - kx, ty = fy - ky;
    double v = 0.0;
    for (double k : {kx, kx + 1.0}) {
      const double wx = k == kx ? 1.0 - tx : tx;
      double wy = 0.0;
      if (k == ky) wy = 1.0 - ty;
      else if (k == ky + 1.0) wy = ty;
      v += wx * wy;
    }
    sum += v;
  }
  return sum / steps;
}


Eigen::Vector3d LinearAxisErrors::error(const Eigen::Vector3d& c) const {
  Eigen::Vector3d e = scale.cwiseProduct(c);
  e.x() += S_xy * c.y() + S_xz * c.z();
  e.y() += S_yz * c.z();
  for (int a = 0; a < 3; ++a) e += nodes[static_cast<size_t>(a)].at(c[a]);
  return e;
}

std::function<Eigen::Vector3d(const Eigen::Vector3d&)> LinearAxisErrors::asFunction() const {
  return [copy = *this](const Eigen::Vector3d& c) { return copy.error(c); };
}

bool LinearAxisModel::validate(std::string* why) const {
  auto fail = [&](const std::string& w) {
    if (why) *why = w;
    return false;
  };
  if (!(u_scale.minCoeff() >= 0) || !(u_rand.minCoeff() >= 0) || !(u_S_xy >= 0) || !(u_S_xz >= 0) || !(u_S_yz >= 0))
    return fail("standard uncertainties of the linear axes must be >= 0");
  if (!(spacing_min_mm > 0) || !(spacing_max_mm >= spacing_min_mm))
    return fail(fmt::format("node spacing must satisfy 0 < min <= max (got [{}, {}] mm)", spacing_min_mm, spacing_max_mm));
  return true;
}

void drawAxisNodes(const LinearAxisModel& model, int axis, double lo, double hi, Rng& rng, AxisNodes* out) {
  if (!(hi >= lo)) throw std::invalid_argument("drawAxisNodes: empty coordinate range");
  if (model.u_rand.col(axis).maxCoeff() <= 0.0) {
    out->spacing_mm = 0.0;
    out->inv_spacing = 0.0;
    for (auto& v : out->mm) v.clear();
    return;
  }
  const double p = model.spacing_min_mm + (model.spacing_max_mm - model.spacing_min_mm) * rng.uniform();
  out->spacing_mm = p;
  out->inv_spacing = 1.0 / p;
  out->first = static_cast<int>(std::floor(lo / p)) - 1;
  const int last = static_cast<int>(std::ceil(hi / p)) + 1;
  const size_t n = static_cast<size_t>(last - out->first + 1);
  for (int c = 0; c < 3; ++c) {
    auto& v = out->mm[static_cast<size_t>(c)];
    v.resize(n);
    const double u = model.u_rand(c, axis);
    for (size_t k = 0; k < n; ++k) v[k] = u * rng.normal();
  }
}

void drawLinearAxisErrors(const LinearAxisModel& model, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
                          Rng& rng_fixed, const std::array<Rng*, 3>& rng_axis, LinearAxisErrors* e) {
  for (int a = 0; a < 3; ++a) e->scale[a] = model.u_scale[a] * rng_fixed.normal();
  e->S_xy = model.u_S_xy * rng_fixed.normal();
  e->S_xz = model.u_S_xz * rng_fixed.normal();
  e->S_yz = model.u_S_yz * rng_fixed.normal();
  for (int a = 0; a < 3; ++a) drawAxisNodes(model, a, lo[a], hi[a], *rng_axis[static_cast<size_t>(a)], &e->nodes[static_cast<size_t>(a)]);
}

}  // namespace rotacal
