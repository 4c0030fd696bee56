#pragma once
// A physical cause the baseline model leaves out, as an extension of the exact model with named
// parameters (the causes' catalog). An extension acts on one observation in one or more of three
// exact ways: it changes the location errors in force (e.g. thermal drift: errors that move
// with time), it adds a positioning error of the linear axes (squareness, probe length), or it
// shifts the trigger along the approach (pretravel). The identification differentiates the exact
// model with respect to the extension's parameters.
#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "core/error_model.hpp"
#include "core/probe_plan.hpp"

namespace rotacal {

/// Where and when an observation was taken.
struct ObservationContext {
  const ProbePoint* point = nullptr;
  int run = 0;
  double t_h = 0.0;  // hours on the common clock, relative to the data's mean time
};

struct ExtensionParameter {
  std::string name;          // e.g. "dz_AY/h", "pretravel_+X"
  std::string unit;          // report unit, e.g. "um/h"
  double to_report = 1.0;    // report value = internal value * to_report
  double fd_step = 1e-6;     // internal units, for the model's finite-difference Jacobian
};

class ModelExtension {
 public:
  virtual ~ModelExtension() = default;
  virtual std::string cause() const = 0;      // catalog id: thermal_drift, probe_pretravel, ...
  virtual std::string variant() const = 0;    // e.g. "linear", "per_repeat"
  virtual std::string describe() const = 0;   // one sentence: how it enters the model
  virtual std::vector<ExtensionParameter> parameters() const = 0;

  /// Location errors in force at this observation (default: unchanged).
  virtual LocationErrors errorsAt(const Eigen::VectorXd& p, const ObservationContext& o, const LocationErrors& e) const {
    (void)p;
    (void)o;
    return e;
  }
  /// Positioning error of the linear axes at a read position (mm), default none.
  virtual bool hasPositionError() const { return false; }
  virtual Eigen::Vector3d positionError(const Eigen::VectorXd& p, const Eigen::Vector3d& c_m) const {
    (void)p;
    (void)c_m;
    return Eigen::Vector3d::Zero();
  }
  /// Extra trigger travel along the approach (mm), default none.
  virtual double triggerOffset(const Eigen::VectorXd& p, const ObservationContext& o) const {
    (void)p;
    (void)o;
    return 0.0;
  }
};

using ExtensionPtr = std::shared_ptr<const ModelExtension>;

}  // namespace rotacal
