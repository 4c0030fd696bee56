#include "history/store.hpp"

#include "core/error_model.hpp"

#include <sqlite3.h>

#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <limits>
#include <memory>
#include <optional>
#include <stdexcept>

#include <fmt/format.h>

#include "core/errors.hpp"

namespace rotacal::history {

namespace {

constexpr int kSchemaVersion = 1;
constexpr int kBusyTimeoutMs = 30000;  // concurrent adds wait for each other this long at most
// Values and uncertainties kept in the history, in report units (um, mdeg): a report beyond
// this is not a calibration, and a row beyond it is damage.
constexpr double kMaxStoredValue = 1e6;

const char* kSchema = R"sql(
CREATE TABLE IF NOT EXISTS meta(key TEXT PRIMARY KEY, value TEXT NOT NULL);
CREATE TABLE IF NOT EXISTS calibration(
  id INTEGER PRIMARY KEY AUTOINCREMENT,
  machine_id TEXT NOT NULL,
  time_s REAL NOT NULL,
  time_utc TEXT NOT NULL,
  added_utc TEXT NOT NULL,
  cycle TEXT NOT NULL,
  method TEXT NOT NULL,
  machine_name TEXT NOT NULL,
  source TEXT NOT NULL,
  residual_rms_um REAL NOT NULL,
  points_used INTEGER NOT NULL,
  plan_json TEXT NOT NULL);
CREATE INDEX IF NOT EXISTS calibration_by_machine ON calibration(machine_id, time_s, id);
CREATE TABLE IF NOT EXISTS parameter(
  calibration_id INTEGER NOT NULL REFERENCES calibration(id) ON DELETE CASCADE,
  name TEXT NOT NULL,
  iso TEXT NOT NULL,
  unit TEXT NOT NULL,
  value REAL NOT NULL,
  u REAL NOT NULL,
  PRIMARY KEY(calibration_id, name));
)sql";

struct Stmt {
  sqlite3_stmt* s = nullptr;
  ~Stmt() { sqlite3_finalize(s); }
};

// `sql` prepared into `st`; false when SQLite refuses it (the caller says what it was for).
bool prepared(sqlite3* db, Stmt& st, const char* sql) { return sqlite3_prepare_v2(db, sql, -1, &st.s, nullptr) == SQLITE_OK; }

// How many tables of the schema `where` selects; nullopt when the schema cannot be read.
std::optional<int> tableCount(sqlite3* db, const std::string& where) {
  Stmt st;
  const std::string sql = "SELECT count(*) FROM sqlite_master WHERE type='table' AND " + where;
  if (!prepared(db, st, sql.c_str())) return std::nullopt;
  sqlite3_step(st.s);
  return sqlite3_column_int(st.s, 0);
}

}  // namespace

std::string defaultDatabasePath() {
  namespace fs = std::filesystem;
  if (const char* x = std::getenv("XDG_DATA_HOME"); x != nullptr && *x == '/')
    return (fs::path(x) / "rotacal" / "history.sqlite").string();
  const char* home = std::getenv("HOME");
  if (home == nullptr || *home == '\0') throw std::runtime_error("neither XDG_DATA_HOME nor HOME is set: give --db FILE");
  return (fs::path(home) / ".local" / "share" / "rotacal" / "history.sqlite").string();
}

Calibration calibrationFromReport(const JsonDoc& doc, const std::string& machine_id, double time_s) {
  return guardJson(doc, [&] {
    const Json& j = doc.value;
    if (!j.is_object() || !j.contains("format") || j["format"] != "rotacal-report/1")
      doc.fail(j, "format", "not a rotacal report (format rotacal-report/1 expected)");
    Calibration c;
    c.machine_id = machine_id;
    c.time_s = time_s;
    c.time_utc = isoTime(time_s);
    c.cycle = requireString(doc, j, "cycle");
    c.method = stringOr(doc, j, "method", "");
    c.machine_name = stringOr(doc, j, "machine", "");
    c.residual_rms_um = requireNumber(doc, j, "residual_rms_um", Limits::nonNegative(kMaxStoredValue, "um"));
    c.points_used = intOr(doc, j, "points_used", 0, 0, std::numeric_limits<int>::max());
    c.source = doc.file;
    Json plan = {{"cycle", c.cycle}};
    if (j.contains("machine_model")) plan["machine"] = j["machine_model"];
    c.plan_json = plan.dump();
    // A head machine's report carries its ISO 230-7 parameters as kinematic_parameters (no
    // location_errors in the papers' sense): the fitted ones, with their budget, are its history.
    const bool head = !j.contains("location_errors") && j.contains("kinematic_parameters");
    const char* key = head ? "kinematic_parameters" : "location_errors";
    if (!j.contains(key) || !j[key].is_object() || j[key].empty())
      doc.fail(j, "location_errors", "no location_errors in the report");
    for (const auto& [name, e] : j[key].items()) {
      // Held, the sphere's set-up (new at every calibration) or not budgeted: no trend.
      if (head && (!e.is_object() || e.value("held", false) || e.value("set_up", false) || !e.contains("u_c"))) continue;
      StoredParameter p;
      p.name = name;
      p.value = requireNumber(doc, e, "value", Limits::symmetric(kMaxStoredValue));
      // A trend compares calibrations of one machine, so it weighs each by what differs between
      // them: u_between (u_A and the contributors drawn anew at every set-up). The machine's own
      // systematic errors, in u (= u_c) and u_b, are the same every time and cancel. A report
      // without u_between: its u_a, the data's part; older still, its u, which was then the data's.
      p.u = e.contains("u_between") ? requireNumber(doc, e, "u_between", Limits::nonNegative(kMaxStoredValue))
            : e.contains("u_a")     ? requireNumber(doc, e, "u_a", Limits::nonNegative(kMaxStoredValue))
                                    : requireNumber(doc, e, "u", Limits::nonNegative(kMaxStoredValue));
      p.unit = requireString(doc, e, "unit");
      if (head && p.unit != "um" && p.unit != "mdeg")
        doc.fail(e, "unit", fmt::format("unit of '{}' must be um or mdeg (got '{}')", name, p.unit));
      // The trend compares values of one parameter across reports: each in the unit analyze
      // writes for its kind (um for lengths, mdeg for angles).
      for (const Kinematics k : {Kinematics::TableAC, Kinematics::TableBC, Kinematics::TableAB}) {  // head_ab has no location errors
        const int i = parameterIndex(k, name);
        if (i < 0) continue;
        const char* want = locationParameters(k)[i].kind == ParamKind::Length ? "um" : "mdeg";
        if (p.unit != want) doc.fail(e, "unit", fmt::format("unit of '{}' must be {} (got '{}')", name, want, p.unit));
        break;
      }
      p.iso = head ? name : stringOr(doc, e, "iso", "");
      c.parameters.push_back(p);
    }
    return c;
  });
}

Database::Database(const std::string& path, bool create) : path_(path) {
  namespace fs = std::filesystem;
  if (!create && !fs::exists(path)) throw InputError(path, 0, "no history database here (add a calibration first)");
  if (create && fs::path(path).has_parent_path()) {
    std::error_code ec;
    fs::create_directories(fs::path(path).parent_path(), ec);
  }
  const int flags = SQLITE_OPEN_READWRITE | (create ? SQLITE_OPEN_CREATE : 0) | SQLITE_OPEN_FULLMUTEX;
  sqlite3* handle = nullptr;
  const int rc = sqlite3_open_v2(path.c_str(), &handle, flags, nullptr);
  db_.reset(handle);  // sqlite hands out a handle to close even when the open fails
  if (rc != SQLITE_OK) fail("cannot open");
  sqlite3_busy_timeout(db_.get(), kBusyTimeoutMs);
  // Reading the schema is the first touch of the file's content: a file that is not a
  // database (or whose header is damaged) fails here with SQLITE_NOTADB.
  exec("PRAGMA foreign_keys=ON");
  {
    Stmt st;
    if (!prepared(db_.get(), st, "PRAGMA journal_mode=WAL")) fail("cannot read");
    if (sqlite3_step(st.s) != SQLITE_ROW) fail("cannot set WAL mode");
  }
  exec("PRAGMA synchronous=NORMAL");
  // Creating the schema: one writer at a time, and idempotent.
  exec("BEGIN IMMEDIATE");
  try {
    const auto others = tableCount(db_.get(), "name NOT IN ('meta','calibration','parameter','sqlite_sequence')");
    if (!others) fail("cannot read the schema");
    if (*others != 0) fail("not a rotacal history database (it holds other tables)");
    // A new file gets the schema; an existing one must have all of it (recreating a dropped
    // table would hide the damage and change a file that `show` only reads).
    const auto counted = tableCount(db_.get(), "name IN ('meta','calibration','parameter')");
    if (!counted) fail("cannot read the schema");
    const int present = *counted;
    if (present != 0 && present != 3)
      fail("damaged history: tables meta, calibration and parameter are not all there; keep the file for inspection "
           "and use --db NEW_FILE");
    if (present == 0 && !create) fail("not a rotacal history database (it holds no calibration table)");
    if (present == 0) {
      exec(kSchema);
      exec("INSERT OR IGNORE INTO meta(key, value) VALUES('format', 'rotacal-history/1')");
      exec(("INSERT OR IGNORE INTO meta(key, value) VALUES('schema_version', '" + std::to_string(kSchemaVersion) + "')").c_str());
    }
    {
      Stmt st;
      if (!prepared(db_.get(), st, "SELECT value FROM meta WHERE key='schema_version'") ||
          sqlite3_step(st.s) != SQLITE_ROW)
        fail("cannot read the schema version");
      const std::string v = reinterpret_cast<const char*>(sqlite3_column_text(st.s, 0));
      if (v != std::to_string(kSchemaVersion)) fail("schema version " + v + " is not the " + std::to_string(kSchemaVersion) + " this rotacal reads");
    }
    exec("COMMIT");
  } catch (...) {
    sqlite3_exec(db_.get(), "ROLLBACK", nullptr, nullptr, nullptr);
    throw;
  }
  // A damaged page behind a valid header shows up only when read: check the whole file.
  Stmt st;
  if (!prepared(db_.get(), st, "PRAGMA quick_check")) fail("cannot check");
  if (sqlite3_step(st.s) != SQLITE_ROW) fail("integrity check failed");
  const std::string ok = reinterpret_cast<const char*>(sqlite3_column_text(st.s, 0));
  if (ok != "ok") fail("damaged (integrity check: " + ok + ")");
}

Database::~Database() = default;

void Database::Close::operator()(sqlite3* db) const { sqlite3_close(db); }

void Database::fail(const std::string& what) const {
  std::string msg = what;
  if (db_ != nullptr) {
    const int code = sqlite3_errcode(db_.get());
    if (code == SQLITE_NOTADB || code == SQLITE_CORRUPT)
      msg = "not a rotacal history database, or damaged (" + std::string(sqlite3_errmsg(db_.get())) +
            "); keep it for inspection and use --db NEW_FILE";
    else if (code != SQLITE_OK && code != SQLITE_ROW && code != SQLITE_DONE)
      msg += ": " + std::string(sqlite3_errmsg(db_.get()));
  }
  throw InputError(path_, 0, msg);
}

void Database::exec(const char* sql) const {
  char* err = nullptr;
  if (sqlite3_exec(db_.get(), sql, nullptr, nullptr, &err) != SQLITE_OK) {
    const std::string e = err ? err : "unknown";
    sqlite3_free(err);
    fail(e);
  }
}

long long Database::add(const Calibration& c) {
  exec("BEGIN IMMEDIATE");
  try {
    Stmt st;
    if (!prepared(db_.get(), st,
                  "INSERT INTO calibration(machine_id, time_s, time_utc, added_utc, cycle, method, machine_name, "
                  "source, residual_rms_um, points_used, plan_json) VALUES(?,?,?,?,?,?,?,?,?,?,?)"))
      fail("cannot prepare the insert");
    const std::string added = isoTime(static_cast<double>(std::time(nullptr)));
    sqlite3_bind_text(st.s, 1, c.machine_id.c_str(), -1, SQLITE_TRANSIENT);
    sqlite3_bind_double(st.s, 2, c.time_s);
    sqlite3_bind_text(st.s, 3, c.time_utc.c_str(), -1, SQLITE_TRANSIENT);
    sqlite3_bind_text(st.s, 4, added.c_str(), -1, SQLITE_TRANSIENT);
    sqlite3_bind_text(st.s, 5, c.cycle.c_str(), -1, SQLITE_TRANSIENT);
    sqlite3_bind_text(st.s, 6, c.method.c_str(), -1, SQLITE_TRANSIENT);
    sqlite3_bind_text(st.s, 7, c.machine_name.c_str(), -1, SQLITE_TRANSIENT);
    sqlite3_bind_text(st.s, 8, c.source.c_str(), -1, SQLITE_TRANSIENT);
    sqlite3_bind_double(st.s, 9, c.residual_rms_um);
    sqlite3_bind_int(st.s, 10, c.points_used);
    sqlite3_bind_text(st.s, 11, c.plan_json.c_str(), -1, SQLITE_TRANSIENT);
    if (sqlite3_step(st.s) != SQLITE_DONE) fail("cannot store the calibration");
    const long long id = sqlite3_last_insert_rowid(db_.get());
    Stmt ps;
    if (!prepared(db_.get(), ps, "INSERT INTO parameter(calibration_id, name, iso, unit, value, u) VALUES(?,?,?,?,?,?)"))
      fail("cannot prepare the insert");
    for (const auto& p : c.parameters) {
      sqlite3_reset(ps.s);
      sqlite3_bind_int64(ps.s, 1, id);
      sqlite3_bind_text(ps.s, 2, p.name.c_str(), -1, SQLITE_TRANSIENT);
      sqlite3_bind_text(ps.s, 3, p.iso.c_str(), -1, SQLITE_TRANSIENT);
      sqlite3_bind_text(ps.s, 4, p.unit.c_str(), -1, SQLITE_TRANSIENT);
      sqlite3_bind_double(ps.s, 5, p.value);
      sqlite3_bind_double(ps.s, 6, p.u);
      if (sqlite3_step(ps.s) != SQLITE_DONE) fail("cannot store parameter " + p.name);
    }
    exec("COMMIT");
    return id;
  } catch (...) {
    sqlite3_exec(db_.get(), "ROLLBACK", nullptr, nullptr, nullptr);
    throw;
  }
}

namespace {

// A row read back is checked as strictly as a report is on the way in: SQLite keeps whatever a
// column is given (text in a REAL column reads as 0.0), so a damaged or hand-edited file would
// otherwise show zeros and NaN with a verdict of "stable".
class RowReader {
 public:
  RowReader(sqlite3_stmt* st, const std::string& path, std::string row) : st_(st), path_(path), row_(std::move(row)) {}
  double number(int col, const char* name, double lo, double hi) const {
    const int type = sqlite3_column_type(st_, col);
    if (type != SQLITE_FLOAT && type != SQLITE_INTEGER) fail(name, "holds " + shown(col) + ", not a number");
    const double v = sqlite3_column_double(st_, col);
    if (!std::isfinite(v) || v < lo || v > hi)
      fail(name, fmt::format("holds {:g}, outside [{:g}, {:g}]", v, lo, hi));
    return v;
  }
  std::string text(int col, const char* name) const {
    if (sqlite3_column_type(st_, col) != SQLITE_TEXT) fail(name, "holds " + shown(col) + ", not text");
    return reinterpret_cast<const char*>(sqlite3_column_text(st_, col));
  }

 private:
  std::string shown(int col) const {
    switch (sqlite3_column_type(st_, col)) {
      case SQLITE_NULL: return "NULL";
      case SQLITE_BLOB: return "a blob";
      case SQLITE_TEXT: return "'" + std::string(reinterpret_cast<const char*>(sqlite3_column_text(st_, col))) + "'";
      default: return fmt::format("{:g}", sqlite3_column_double(st_, col));
    }
  }
  [[noreturn]] void fail(const char* name, const std::string& what) const {
    throw InputError(path_, 0, fmt::format("damaged history: {}, column {} {}; keep the file for inspection and use --db "
                                           "NEW_FILE",
                                           row_, name, what));
  }
  sqlite3_stmt* st_;
  const std::string& path_;
  std::string row_;
};

}  // namespace

std::vector<Calibration> Database::list(const std::string& machine_id) const {
  std::vector<Calibration> out;
  Stmt st;
  if (!prepared(db_.get(), st,
                "SELECT id, time_s, time_utc, cycle, method, machine_name, source, residual_rms_um, points_used, "
                "plan_json FROM calibration WHERE machine_id = ? ORDER BY time_s, id"))
    fail("cannot read the calibrations");
  sqlite3_bind_text(st.s, 1, machine_id.c_str(), -1, SQLITE_TRANSIENT);
  int rc;
  while ((rc = sqlite3_step(st.s)) == SQLITE_ROW) {
    Calibration c;
    c.id = sqlite3_column_int64(st.s, 0);
    const RowReader row(st.s, path_, fmt::format("calibration {}", c.id));
    c.machine_id = machine_id;
    // Unix seconds of the years parseIsoTime accepts (1970-9999).
    c.time_s = row.number(1, "time_s", 0.0, 253402300799.0);
    c.time_utc = row.text(2, "time_utc");
    c.cycle = row.text(3, "cycle");
    c.method = row.text(4, "method");
    c.machine_name = row.text(5, "machine_name");
    c.source = row.text(6, "source");
    c.residual_rms_um = row.number(7, "residual_rms_um", 0.0, kMaxStoredValue);
    c.points_used = static_cast<int>(row.number(8, "points_used", 0.0, std::numeric_limits<int>::max()));
    c.plan_json = row.text(9, "plan_json");
    out.push_back(std::move(c));
  }
  if (rc != SQLITE_DONE) fail("cannot read the calibrations");
  Stmt ps;
  if (!prepared(db_.get(), ps, "SELECT name, iso, unit, value, u FROM parameter WHERE calibration_id = ? ORDER BY rowid"))
    fail("cannot read the parameters");
  for (auto& c : out) {
    sqlite3_reset(ps.s);
    sqlite3_bind_int64(ps.s, 1, c.id);
    while ((rc = sqlite3_step(ps.s)) == SQLITE_ROW) {
      StoredParameter p;
      const unsigned char* raw = sqlite3_column_text(ps.s, 0);  // for the message, whatever it holds
      const std::string label = raw ? reinterpret_cast<const char*>(raw) : "";
      const RowReader row(ps.s, path_, fmt::format("calibration {}, parameter '{}'", c.id, label));
      p.name = row.text(0, "name");
      p.iso = row.text(1, "iso");
      p.unit = row.text(2, "unit");
      p.value = row.number(3, "value", -kMaxStoredValue, kMaxStoredValue);
      p.u = row.number(4, "u", 0.0, kMaxStoredValue);
      c.parameters.push_back(p);
    }
    if (rc != SQLITE_DONE) fail("cannot read the parameters");
  }
  return out;
}

std::vector<std::string> Database::machines() const {
  std::vector<std::string> out;
  Stmt st;
  if (!prepared(db_.get(), st, "SELECT DISTINCT machine_id FROM calibration ORDER BY machine_id"))
    fail("cannot read the machines");
  while (sqlite3_step(st.s) == SQLITE_ROW) out.emplace_back(reinterpret_cast<const char*>(sqlite3_column_text(st.s, 0)));
  return out;
}

}  // namespace rotacal::history
