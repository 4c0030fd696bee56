#pragma once
// The calibration history of rotacal: one SQLite file, many machines. Every
// `rotacal history add` stores one calibration (its parameters with their uncertainty, time,
// plan, residual). Several processes may add at once: the file runs in WAL mode with a busy
// timeout, and each add is one IMMEDIATE transaction (all or nothing). A file that is not a
// rotacal history (or is damaged) is refused with a clear error naming it. Schema:
// docs/reports.md.
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/iso_time.hpp"
#include "core/json_io.hpp"

struct sqlite3;

namespace rotacal::history {

struct StoredParameter {
  std::string name, iso, unit;  // unit: um or mdeg (report units)
  double value = 0.0, u = 0.0;  // u: standard uncertainty, k = 1
};

struct Calibration {
  long long id = 0;
  std::string machine_id;
  double time_s = 0.0;       // when the calibration was made, Unix seconds (UTC)
  std::string time_utc;      // the same, ISO 8601
  std::string cycle, method, machine_name, source;
  double residual_rms_um = 0.0;
  int points_used = 0;
  std::string plan_json;     // PLAN.json when given, else the report's cycle and machine model
  std::vector<StoredParameter> parameters;
};

/// $XDG_DATA_HOME/rotacal/history.sqlite, or ~/.local/share/rotacal/history.sqlite.
std::string defaultDatabasePath();

/// The calibrations' times (core/iso_time.hpp).
using ::rotacal::isoTime;
using ::rotacal::parseIsoTime;

/// A calibration from the content of a REPORT.json (rotacal-report/1); throws InputError naming
/// the file and line of what is missing.
Calibration calibrationFromReport(const JsonDoc& report, const std::string& machine_id, double time_s);

class Database {
 public:
  /// Opens (creating the file and its directory when `create`) and checks the schema. Throws
  /// InputError(path, 0, ...) when the file is not a rotacal history or is damaged.
  explicit Database(const std::string& path, bool create = true);
  ~Database();
  Database(const Database&) = delete;
  Database& operator=(const Database&) = delete;

  /// Stores one calibration in one transaction; returns its id.
  long long add(const Calibration& c);
  /// The calibrations of a machine in time order (then id order). Every row is checked (types,
  /// finite values, u >= 0): a damaged row fails with InputError naming the file and the row.
  std::vector<Calibration> list(const std::string& machine_id) const;
  std::vector<std::string> machines() const;

 private:
  void exec(const char* sql) const;
  [[noreturn]] void fail(const std::string& what) const;
  // Owned from the moment sqlite3_open_v2 hands it over, so that a constructor that throws
  // (a damaged file) still closes it.
  struct Close {
    void operator()(sqlite3* db) const;
  };
  std::unique_ptr<sqlite3, Close> db_;
  std::string path_;
};

}  // namespace rotacal::history
