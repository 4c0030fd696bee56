#include "report/html_report.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <stdexcept>

#include <fmt/format.h>

#include "report/figure.hpp"
#include "report/svg.hpp"

namespace rotacal::report {

namespace {

const char* kStyle = R"(<style>
body{font-family:sans-serif;margin:24px;color:#222;max-width:1280px}
h1{font-size:22px}h2{font-size:17px;border-bottom:1px solid #ccc;padding-bottom:3px;margin-top:28px}
h3{font-size:14px;margin-bottom:4px}
table{border-collapse:collapse;margin:6px 0}td,th{border:1px solid #ccc;padding:3px 8px;font-size:13px}
th{background:#f2f2f2;text-align:left}td.num{text-align:right;font-variant-numeric:tabular-nums}
.note{color:#555;font-size:13px;max-width:900px}.verdict{font-weight:bold;padding:6px 10px;display:inline-block}
.found{background:#fde2e1}.none{background:#e2f5e1}.flag-step{background:#fde2e1}.flag-drift{background:#fff3cd}
.panels{display:flex;flex-wrap:wrap;gap:6px}.figure{margin:10px 0}.magsel{margin:6px 0;font-size:13px}
</style>)";

// Installed before anything else so that the browser test sees any error of the page's script.
const char* kErrorTrap = R"(<script>
window.addEventListener('error', function (e) {
  document.documentElement.setAttribute('data-script-error', String(e.message));
});
</script>)";

const char* kScript = R"(<script>
(function () {
  var inputs = document.querySelectorAll('.magsel input');
  for (var i = 0; i < inputs.length; ++i) {
    inputs[i].addEventListener('change', function (ev) {
      var r = ev.target, group = r.getAttribute('data-group');
      var views = document.querySelectorAll('.magview');
      for (var j = 0; j < views.length; ++j)
        if (views[j].getAttribute('data-group') === group)
          views[j].hidden = views[j].getAttribute('data-mag') !== r.value;
    });
  }
  document.body.setAttribute('data-report-ready', String(document.querySelectorAll('svg').length));
})();
</script>)";

std::string num(double v, int decimals) { return fmt::format("{:.{}f}", v, decimals); }

std::string str(const Json& j, const char* key, const std::string& fallback = "") {
  const auto it = j.find(key);
  if (it == j.end() || it->is_null()) return fallback;
  if (it->is_string()) return it->get<std::string>();
  if (it->is_number_integer()) return std::to_string(it->get<long long>());
  if (it->is_number()) return num(it->get<double>(), 3);
  return it->dump();
}

double dbl(const Json& j, const char* key, double fallback = std::nan("")) {
  const auto it = j.find(key);
  return it != j.end() && it->is_number() ? it->get<double>() : fallback;
}

std::string row(const std::vector<std::string>& cells, bool header = false) {
  std::string s = "<tr>";
  for (const auto& c : cells) s += header ? "<th>" + c + "</th>" : "<td>" + c + "</td>";
  return s + "</tr>\n";
}
std::string numCell(double v, int decimals) {
  return std::isfinite(v) ? "<span class=\"n\">" + num(v, decimals) + "</span>" : "&ndash;";
}

/// Keys of a parameter object in the papers' order (000 Table 1, 002 Table 2), others after in
/// their own order (JSON objects come back sorted by name).
std::vector<std::string> paperOrder(const Json& obj) {
  static const std::vector<std::string> order = {"dx_AY", "dy_AY", "dz_AY", "dy_CA", "a_AY", "b_AY", "c_AY", "b_CA",
                                                 "dx_BY", "dy_CB", "dz_BY", "a_BY", "b_BY", "c_BY"};
  std::vector<std::string> out;
  for (const auto& n : order)
    if (obj.contains(n)) out.push_back(n);
  for (const auto& [k, v] : obj.items())
    if (std::find(order.begin(), order.end(), k) == order.end()) out.push_back(k);
  return out;
}

/// A table of location errors {"name": {"value","unit","u","iso"}} with optional extra columns.
/// A report's u is u_c (core/uncertainty_budget.hpp) and its column says so; a table whose entries
/// carry no u_c (a diagnosis' re-estimate) heads it plain u.
std::string locationTable(const Json& le, const std::vector<std::pair<std::string, const Json*>>& others = {}) {
  std::string s = "<table class=\"params\">";
  bool all_uc = !le.empty();
  for (const auto& [name, e] : le.items()) all_uc = all_uc && e.is_object() && e.contains("u_c");
  std::vector<std::string> head = {"parameter", "ISO 230-7", "value", all_uc ? "u_c (k = 1)" : "u (k = 1)", "unit"};
  for (const auto& o : others) head.push_back(escape(o.first));
  s += row(head, true);
  for (const auto& name : paperOrder(le)) {
    const Json& e = le[name];
    std::vector<std::string> cells = {escape(name), escape(str(e, "iso")), numCell(dbl(e, "value"), 3),
                                      numCell(dbl(e, "u"), 3), escape(str(e, "unit"))};
    for (const auto& o : others) {
      const Json* oj = o.second;
      cells.push_back(oj && oj->contains(name) ? numCell(dbl((*oj)[name], "value"), 3) : "&ndash;");
    }
    s += row(cells);
  }
  return s + "</table>\n";
}

// The uncertainty a report signs (core/uncertainty_budget.hpp: REPORT.json "uncertainty"): the
// sources in words, u_A u_B u_c U per parameter with its largest contributors, and the
// correlation matrix, each cell shaded by |r| so the strong pairs stand out.
std::string uncertaintySection(const Json& doc) {
  const auto it = doc.find("uncertainty");
  if (it == doc.end() || !it->is_object() || !it->contains("order") || !it->contains("parameters")) return {};
  const Json& u = *it;
  const Json& order = u["order"];
  const Json& le = doc.value("location_errors", Json::object());
  std::string s = "<h2 id=\"uncertainty\">Uncertainty</h2>\n";
  s += "<p>" + escape(fmt::format("u: standard uncertainty (k = 1); U = k u_c, {:.2f} % coverage: {}.",
                                  100.0 * dbl(u, "coverage_probability", 0.9545), str(u, "coverage_factor"))) +
       "</p>";
  s += "<ul><li>Type A: " + escape(str(u, "type_a")) + "</li><li>Type B: " + escape(str(u, "type_b")) + "</li></ul>";
  s += "<table class=\"params\" data-table=\"uncertainty\">";
  s += row({"parameter", "value", "u_A", "u_B", "u_c", "U", "k", "unit", "largest contributors (u alone)"}, true);
  for (const auto& nj : order) {
    if (!nj.is_string()) continue;
    const std::string name = nj.get<std::string>();
    if (!u["parameters"].contains(name)) continue;
    const Json& p = u["parameters"][name];
    std::string largest;
    if (u.contains("budget") && u["budget"].contains(name) && u["budget"][name].is_array())
      for (const auto& t : u["budget"][name])
        largest += (largest.empty() ? "" : ", ") + escape(str(t, "contributor")) + " " + numCell(dbl(t, "u"), 2);
    const double value = p.contains("value") ? dbl(p, "value") : le.contains(name) ? dbl(le[name], "value") : std::nan("");
    s += row({escape(name), numCell(value, 3), numCell(dbl(p, "u_a"), 3),
              numCell(dbl(p, "u_b"), 3), numCell(dbl(p, "u_c"), 3), numCell(dbl(p, "U"), 3), numCell(dbl(p, "k"), 2),
              escape(str(p, "unit")), largest});
  }
  s += "</table>\n";
  if (u.contains("correlation") && u["correlation"].is_array() && u["correlation"].size() == order.size()) {
    s += "<h3>Correlation of the estimates</h3><table class=\"params\" data-table=\"correlation\">";
    std::vector<std::string> head = {""};
    for (const auto& nj : order) head.push_back(escape(nj.is_string() ? nj.get<std::string>() : std::string()));
    s += row(head, true);
    for (size_t i = 0; i < order.size(); ++i) {
      s += "<tr><th>" + escape(order[i].is_string() ? order[i].get<std::string>() : std::string()) + "</th>";
      const Json& r = u["correlation"][i];
      for (size_t j = 0; j < order.size() && r.is_array() && j < r.size(); ++j) {
        const double v = r[j].is_number() ? r[j].get<double>() : 0.0;
        const int shade = static_cast<int>(std::lround(255.0 - 120.0 * std::min(1.0, std::abs(v))));
        s += fmt::format("<td style=\"background:rgb({0},{0},255)\">{1}</td>", shade, numCell(v, 2));
      }
      s += "</tr>";
    }
    s += "</table>\n";
  }
  return s;
}

std::string figureBlock(const Figure& f) {
  std::string s = "<div class=\"figure\" data-figure=\"" + escape(f.id) + "\">" + svgPlot(f);
  if (!f.note.empty()) s += "<p class=\"note\">" + escape(f.note) + "</p>";
  return s + "</div>\n";
}

std::string figuresSection(const Json& doc, const std::string& heading) {
  const auto it = doc.find("figures");
  if (it == doc.end() || !it->is_array() || it->empty()) return {};
  std::string s = "<h2>" + escape(heading) + "</h2>\n";
  for (const auto& fj : *it) s += figureBlock(figureFromJson(fj));
  return s;
}

double niceBar(double target) {
  const double mag = std::pow(10.0, std::floor(std::log10(target)));
  for (double m : {1.0, 2.0, 5.0})
    if (m * mag * 1.5 >= target) return m * mag;
  return 10 * mag;
}

// ---- touch cycles: the deviation views of 000 Figs. 7-9 ----

struct View {
  std::string id, title, note;
  bool relative;               // Eq. (21) relative displacement, or raw deviation
  bool tilted;                 // poses with A != 0 (or B != 0), else A = B = 0
  std::vector<std::pair<int, int>> planes;  // projections: coordinate indices
  std::vector<double> mags;
  double default_mag;
};

std::string deviationViews(const Json& doc) {
  const auto pit = doc.find("points");
  if (pit == doc.end() || !pit->is_array() || pit->empty()) return {};
  // A cycle whose plan follows a paper's figures names them (REPORT.json "figure_titles").
  const Json no_titles = Json::object();
  const Json& titles = doc.contains("figure_titles") && doc["figure_titles"].is_object() ? doc["figure_titles"] : no_titles;
  auto title = [&](const char* fig, const char* fallback) {
    return titles.contains(fig) && titles[fig].is_string() ? titles[fig].get<std::string>() : std::string(fallback);
  };
  const char* axes = "XYZ";
  std::vector<View> views = {
      {"fig7", title("fig7", "Probed positions, untilted poses"),
       "Black dots: nominal contact points on a perfect machine; red circles: measured, the deviation along the face "
       "normal magnified. Includes the test piece's setup and form errors.",
       false, false, {{0, 1}, {1, 2}}, {5, 25, 100, 500}, 25},
      {"fig8", title("fig8", "Relative displacements, untilted poses"),
       "Deviation minus the same target's deviation at the first pose: setup and form cancel, the rotary axes' errors remain.",
       true, false, {{0, 1}, {0, 2}, {1, 2}}, {100, 500, 2000, 8000}, 500},
      {"fig9", title("fig9", "Relative displacements, tilted poses"),
       "As above, at the tilted poses.", true, true, {{0, 1}, {0, 2}}, {100, 500, 2000, 8000}, 500}};

  // Poses of run 1 in plan order.
  std::vector<std::string> pose_order;
  std::map<std::string, std::vector<const Json*>> by_pose;
  std::map<std::string, bool> pose_tilted;
  std::map<std::string, std::string> pose_title;
  for (const auto& p : *pit) {
    if (p.value("run", 1) != 1 || !p.contains("contact_m_mm") || !p.contains("normal_m")) continue;
    const std::string name = str(p, "pose_name");
    if (!by_pose.count(name)) {
      pose_order.push_back(name);
      const Json& pose = p["pose"];
      const double A = dbl(pose, "A", 0), B = dbl(pose, "B", 0), C = dbl(pose, "C", 0);
      pose_tilted[name] = std::abs(A) > 1e-9 || std::abs(B) > 1e-9;
      pose_title[name] = fmt::format("({}) {}C = {:g} deg", name,
                                     std::abs(B) > 1e-9 ? fmt::format("B = {:g}, ", B) : fmt::format("A = {:g}, ", A), C);
    }
    by_pose[name].push_back(&p);
  }
  std::string s = "<h2>Deviation views</h2>\n<p class=\"note\">Run 1. Positions in the machine frame (origin at the "
                  "rotary-axes' intersection), mm; deviations in um, drawn magnified (choose the magnification).</p>\n";
  for (const auto& v : views) {
    std::vector<std::string> poses;
    for (const auto& n : pose_order)
      if (pose_tilted[n] == v.tilted) poses.push_back(n);
    if (poses.empty()) continue;
    bool any = false;
    for (const auto& n : poses)
      for (const Json* p : by_pose[n])
        if (!(*p)[v.relative ? "rel_dev_um" : "dev_um"].is_null()) any = true;
    if (!any) continue;
    s += "<h3 id=\"" + v.id + "\">" + escape(v.title) + "</h3><p class=\"note\">" + escape(v.note) + "</p>\n";
    s += "<div class=\"magsel\">Magnification:";
    for (double m : v.mags)
      s += fmt::format(" <label><input type=\"radio\" name=\"mag_{0}\" data-group=\"{0}\" value=\"{1:g}\"{2}> x{1:g}</label>", v.id,
                       m, m == v.default_mag ? " checked" : "");
    s += "</div>\n";
    for (double m : v.mags) {
      // Panels of one projection share their limits so that the poses compare.
      s += fmt::format("<div class=\"magview\" data-group=\"{}\" data-mag=\"{:g}\"{}>\n", v.id, m,
                       m == v.default_mag ? "" : " hidden");
      for (const auto& [a, b] : v.planes) {
        // Each panel centred on its own points, all at one scale so that the poses compare.
        std::vector<ProjectionPanel> panels;
        std::vector<Eigen::Vector4d> boxes;
        double span = 1.0;
        for (const auto& n : poses) {
          ProjectionPanel panel;
          panel.title = pose_title[n];
          panel.x_label = std::string(1, axes[a]);
          panel.y_label = std::string(1, axes[b]);
          Eigen::Vector4d box(1e300, -1e300, 1e300, -1e300);
          for (const Json* p : by_pose[n]) {
            const Json& d = (*p)[v.relative ? "rel_dev_um" : "dev_um"];
            if (!d.is_number()) continue;
            const Json& c = (*p)["contact_m_mm"];
            const Json& nn = (*p)["normal_m"];
            ProjectionPoint q;
            q.nominal_mm = {c[a].get<double>(), c[b].get<double>()};
            q.deviation_um = d.get<double>() * Eigen::Vector2d(nn[a].get<double>(), nn[b].get<double>());
            const Eigen::Vector2d mpos = q.nominal_mm + m * 1e-3 * q.deviation_um;
            for (const auto& pt : {q.nominal_mm, mpos}) {
              box[0] = std::min(box[0], pt.x());
              box[1] = std::max(box[1], pt.x());
              box[2] = std::min(box[2], pt.y());
              box[3] = std::max(box[3], pt.y());
            }
            panel.points.push_back(q);
          }
          if (panel.points.empty()) continue;
          span = std::max({span, box[1] - box[0], box[3] - box[2]});
          boxes.push_back(box);
          panels.push_back(std::move(panel));
        }
        span *= 1.16;
        s += "<div class=\"panels\">";
        for (size_t i = 0; i < panels.size(); ++i) {
          const double cx = 0.5 * (boxes[i][0] + boxes[i][1]), cy = 0.5 * (boxes[i][2] + boxes[i][3]);
          const Eigen::Vector4d lim(cx - span / 2, cx + span / 2, cy - span / 2, cy + span / 2);
          s += svgProjection(panels[i], m, lim, niceBar(0.15 * span * 1000.0 / m));
        }
        s += "</div>\n";
      }
      s += "</div>\n";
    }
  }
  return s;
}

std::vector<Figure> residualFigures(const Json& doc) {
  std::vector<Figure> out;
  const auto pit = doc.find("points");
  if (pit == doc.end() || !pit->is_array() || pit->empty()) return out;
  Figure by_angle{"residual_vs_angle", "Residuals against the C angle", "", {"C", "deg", {}}, {"residual", "um", {}}, {}, {}};
  Figure by_time{"residual_vs_time", "Residuals against time", "", {"t", "min", {}}, {"residual", "um", {}}, {}, {}};
  Figure by_face{"residual_vs_face", "Residuals per face", "", {"face", "-", {}}, {"residual", "um", {}}, {}, {}};
  std::map<std::string, size_t> angle_series, run_series, face_index;
  for (const auto& p : *pit) {
    const Json& r = p["residual_um"];
    if (!r.is_number()) continue;
    const double res = r.get<double>();
    const Json& pose = p["pose"];
    const double A = dbl(pose, "A", 0), B = dbl(pose, "B", 0);
    const std::string tilt = std::abs(B) > 1e-9 ? fmt::format("B = {:g} deg", B) : fmt::format("A = {:g} deg", A);
    if (!angle_series.count(tilt)) {
      angle_series[tilt] = by_angle.series.size();
      by_angle.series.push_back({tilt, "points", {}, {}, {}});
    }
    auto& sa = by_angle.series[angle_series[tilt]];
    sa.x.push_back(dbl(pose, "C", 0));
    sa.y.push_back(res);
    const std::string run = "run " + std::to_string(p.value("run", 1));
    if (p["t_s"].is_number()) {
      if (!run_series.count(run)) {
        run_series[run] = by_time.series.size();
        by_time.series.push_back({run, "points", {}, {}, {}});
      }
      auto& st = by_time.series[run_series[run]];
      st.x.push_back(p["t_s"].get<double>() / 60.0);
      st.y.push_back(res);
    }
    const std::string face = str(p, "face", "?");
    if (!face_index.count(face)) {
      face_index[face] = by_face.x.categories.size();
      by_face.x.categories.push_back(face);
    }
    if (by_face.series.empty()) by_face.series.push_back({"residual", "points", {}, {}, {}});
    // A small deterministic spread inside the face's column so that points do not overlap.
    const int id = p.value("point", 0);
    by_face.series[0].x.push_back(static_cast<double>(face_index[face]) + 0.06 * ((id % 7) - 3));
    by_face.series[0].y.push_back(res);
  }
  by_angle.note = "Measured minus fitted model along the probing direction; structure against C points at an error the model lacks.";
  by_time.note = "A trend against time is thermal drift (rotacal diagnose tests it).";
  for (auto* f : {&by_angle, &by_time, &by_face})
    if (!f->series.empty()) out.push_back(*f);
  return out;
}

/// Each parameter across the repeats (000 Table 4 columns), error bars u (k = 1).
std::vector<Figure> runFigures(const Json& doc) {
  std::vector<Figure> out;
  const auto rit = doc.find("runs");
  if (rit == doc.end() || !rit->is_array() || rit->size() < 2) return out;
  Figure lengths{"runs_lengths", "Location errors per repeat (lengths)", "", {"repeat", "-", {}}, {"value", "um", {}}, {}, {}};
  Figure angles{"runs_angles", "Location errors per repeat (angles)", "", {"repeat", "-", {}}, {"value", "mdeg", {}}, {}, {}};
  std::map<std::string, std::pair<Figure*, size_t>> index;
  for (size_t r = 0; r < rit->size(); ++r) {
    const Json& le = (*rit)[r]["location_errors"];
    for (const auto& name : paperOrder(le)) {
      const Json& e = le[name];
      Figure* f = str(e, "unit") == "um" ? &lengths : &angles;
      if (!index.count(name)) {
        index[name] = {f, f->series.size()};
        f->series.push_back({name, "line", {}, {}, {}});
      }
      auto& s = index[name].first->series[index[name].second];
      s.x.push_back(static_cast<double>(r + 1));
      s.y.push_back(dbl(e, "value", 0));
      s.u.push_back(dbl(e, "u", 0));
    }
  }
  for (auto* f : {&lengths, &angles})
    if (!f->series.empty()) out.push_back(*f);
  return out;
}

// The answer first: per parameter, adjust or leave (REPORT.json "verdict", core/verdict.hpp).
std::string verdictBlock(const Json& doc) {
  if (!doc.contains("verdict") || !doc["verdict"].is_object()) return {};
  const Json& v = doc["verdict"];
  std::string s = "<h2 id=\"verdict\">Verdict</h2>\n<p class=\"note\">" + escape(str(v, "summary")) + "</p>\n<table>" +
                  row({"parameter", "value", "U", "unit", "tolerance", "verdict"}, true);
  for (const auto& [name, p] : v["parameters"].items())
    s += row({escape(name), numCell(dbl(p, "value"), 3), numCell(dbl(p, "U"), 3), escape(str(p, "unit")),
              p.contains("tolerance") ? numCell(dbl(p, "tolerance"), 3) : std::string("-"), escape(str(p, "verdict"))});
  s += "</table>\n<p class=\"note\">" + escape(str(v, "rule")) + "</p>\n";
  return s;
}

std::string analyzeBody(const Json& doc) {
  std::string s = verdictBlock(doc);
  const Json mm = doc.value("machine_model", Json::object());
  const Json sum = doc.value("summary", Json::object());
  s += "<h2>Machine and plan</h2><table>";
  s += row({"machine", escape(str(doc, "machine", str(mm, "name")))});
  if (mm.contains("kinematics")) s += row({"kinematics", escape(str(mm, "kinematics"))});
  if (mm.contains("probe"))
    s += row({"probe", fmt::format("ball {} mm, repeatability {} um", escape(str(mm["probe"], "ball_diameter_mm")),
                                   escape(str(mm["probe"], "repeatability_um")))});
  s += row({"cycle", escape(str(doc, "cycle"))});
  s += row({"method", escape(str(doc, "method"))});
  if (doc.contains("results") && doc["results"].is_array()) {
    std::string files;
    for (const auto& f : doc["results"]) files += (files.empty() ? "" : ", ") + escape(f.get<std::string>());
    s += row({"results", files});
  }
  s += row({"points used", escape(str(doc, "points_used"))});
  s += row({"residual rms", numCell(dbl(doc, "residual_rms_um"), 3) + " um"});
  // The cycles' summaries carry different fields (e.g. a tool-tip fit has no rank): show what is there.
  if (sum.contains("sigma_um"))
    s += row({"noise estimate", numCell(dbl(sum, "sigma_um"), 3) + fmt::format(" um ({} dof)", escape(str(sum, "dof")))});
  if (sum.contains("rank"))
    s += row({"rank / condition", escape(str(sum, "rank")) + " / " + escape(str(sum, "condition"))});
  if (sum.contains("termination"))
    s += row({"termination", escape(str(sum, "termination")) +
                                 (sum.contains("message") ? ": " + escape(str(sum, "message")) : std::string())});
  // What the data were screened and tested against: a reader signs values from screened data, so
  // the page says what the screen left out, how large a gross error it sees, and where it sees none.
  if (doc.contains("outliers") && doc["outliers"].is_object()) {
    const Json& o = doc["outliers"];
    if (o.contains("summary")) s += row({"gross errors", escape(str(o, "summary"))});
    if (o.contains("reach") && o["reach"].is_object()) s += row({"what the screen can see", escape(str(o["reach"], "summary"))});
  }
  if (doc.contains("declared_noise") && doc["declared_noise"].is_object() && doc["declared_noise"].contains("summary"))
    s += row({"against the declared noise", escape(str(doc["declared_noise"], "summary"))});
  s += "</table>\n";

  // A cycle whose table holds other than location errors in ISO 230-7's sense (position-dependent
  // errors, a pivot length) names it (REPORT.json "errors_heading").
  // A cycle that identifies no machine errors (the probe's qualification) gets no empty heading.
  if (doc.contains("location_errors") || doc.contains("location_errors_note") || doc.contains("errors_heading"))
    s += "<h2>" + escape(doc.contains("errors_heading") ? str(doc, "errors_heading") : std::string("Identified location errors")) +
         "</h2>\n";
  std::vector<std::pair<std::string, const Json*>> others;
  if (doc.contains("other_methods"))
    for (const auto& [name, o] : doc["other_methods"].items())
      if (o.contains("location_errors")) others.push_back({name, &o["location_errors"]});
  if (doc.contains("location_errors")) s += locationTable(doc["location_errors"], others);
  // Where the cycle's location errors are other parameters (a head's ISO 230-7 set), its note says
  // where they stand.
  if (doc.contains("location_errors_note") && !doc.contains("location_errors"))
    s += "<p>" + escape(str(doc, "location_errors_note")) + "</p>\n";
  s += uncertaintySection(doc);
  if (doc.contains("runs") && doc["runs"].is_array() && doc["runs"].size() > 1) {
    s += "<h3>Per repeat (000 Table 4 layout)</h3>";
    std::vector<std::pair<std::string, const Json*>> cols;
    for (size_t r = 0; r < doc["runs"].size(); ++r) cols.push_back({"run " + std::to_string(r + 1), &doc["runs"][r]["location_errors"]});
    s += locationTable(doc["location_errors"], cols);
    for (const auto& f : runFigures(doc)) s += figureBlock(f);
  }
  s += deviationViews(doc);
  const auto res = residualFigures(doc);
  if (!res.empty()) {
    s += "<h2 id=\"residuals\">Residuals</h2>\n";
    for (const auto& f : res) s += figureBlock(f);
  }
  return s;
}

std::string diagnoseBody(const Json& doc) {
  std::string s;
  // The judge's three verdicts; its message says why, in words true for each.
  const std::string verdict = str(doc, "verdict");
  const bool found = verdict == "effect_found", inadequate = verdict == "model_inadequate";
  s += fmt::format("<p class=\"verdict {}\">{}</p>\n", found || inadequate ? "found" : "none",
                   found        ? "The model misses an effect: see the findings."
                   : inadequate ? "The model does not explain the data within the declared noise, and no catalogued cause does."
                                : "No significant effect beyond the location errors.");
  if (doc.contains("message")) s += "<p>" + escape(str(doc, "message")) + "</p>\n";
  const Json base = doc.value("baseline", Json::object());
  s += "<h2>Disagreement of the baseline model</h2><table>";
  s += row({"model", escape(str(base, "model"))});
  s += row({"residual rms", numCell(dbl(base, "residual_rms_um"), 3) + " um"});
  s += row({"held-out rms", numCell(dbl(base, "holdout_rms_um"), 3) + " um (" + escape(str(doc, "holdout")) + ")"});
  s += row({"noise used by the tests", numCell(dbl(doc, "sigma_um"), 3) + " um"});
  s += "</table>\n";
  // Where the judge finds the baseline's misfit (every cycle's DIAGNOSIS.json carries it): each
  // factor's share of the residual's chi-square, with the level of its test.
  // (under "judge", or the judge's fields at the top of the document)
  const Json& judged = doc.contains("judge") ? doc["judge"] : doc;
  const Json factors = judged.contains("baseline") && judged["baseline"].is_object() &&
                               judged["baseline"].contains("adequacy")
                           ? judged["baseline"]["adequacy"].value("factors", Json::array())
                           : Json::array();
  if (!factors.empty()) {
    Figure where{"diagnose_misfit_factors", "Where the baseline's misfit sits: share of its chi-square by factor", "",
                 {"factor", "-", {}}, {"share of chi2", "%", {}}, {}, {}};
    PlotSeries share{"share of the baseline's chi2", "points", {}, {}, {}};
    s += "<table>" + row({"factor", "chi2", "dof", "p", "share", "where"}, true);
    for (const auto& f : factors) {
      share.x.push_back(static_cast<double>(where.x.categories.size()));
      share.y.push_back(100.0 * dbl(f, "share", 0));
      where.x.categories.push_back(str(f, "factor"));
      s += row({escape(str(f, "factor")), numCell(dbl(f, "chi2"), 1), escape(str(f, "dof")),
                fmt::format("{:.3g}", dbl(f, "p_value", 1)), num(100.0 * dbl(f, "share", 0), 1) + " %",
                escape(str(f, "detail"))});
    }
    s += "</table>\n";
    where.series = {share};
    where.note = "A factor's share is the chi-square its own columns take from the baseline's residual (a nested test "
                 "on the residual), so factors overlap and shares need not add to 100 %.";
    s += figureBlock(where);
  }
  if (doc.contains("residual_analysis")) {
    s += "<h3>Residual structure by factor (chi-square against the noise)</h3><table>";
    s += row({"factor", "detail", "chi2", "dof", "p", "structured"}, true);
    for (const auto& f : doc["residual_analysis"])
      s += row({escape(str(f, "factor")), escape(str(f, "detail")), numCell(dbl(f, "chi2"), 1), escape(str(f, "dof")),
                fmt::format("{:.3g}", dbl(f, "p", 1)), f.value("structured", false) ? "<b>yes</b>" : "no"});
    s += "</table>\n";
  }
  if (doc.contains("findings") && !doc["findings"].empty()) {
    s += "<h2>Findings: the named cause and the gain</h2>\n";
    Figure gain{"diagnose_gain", "Residual rms before and after extending the model", "", {"model", "-", {}},
                {"rms", "um", {}}, {}, {}};
    gain.x.categories.push_back("baseline");
    PlotSeries fit{"fitted residual rms", "points", {0}, {dbl(base, "residual_rms_um", 0)}, {}};
    PlotSeries held{"held-out rms", "points", {0}, {dbl(base, "holdout_rms_um", 0)}, {}};
    for (const auto& f : doc["findings"]) {
      s += "<h3>" + escape(str(f, "cause")) + (f.contains("variant") ? " (" + escape(str(f, "variant")) + ")" : "") + "</h3>";
      s += "<p>" + escape(str(f, "summary")) + "</p>";
      s += fmt::format("<p>Gain on held-out data: <b>{} %</b> (held-out rms {} um against {} um; fitted {} um).</p>\n",
                       num(dbl(f, "gain_pct", 0), 1), num(dbl(f, "holdout_rms_um", 0), 3), num(dbl(base, "holdout_rms_um", 0), 3),
                       num(dbl(f, "residual_rms_um", 0), 3));
      if (f.contains("parameters") && !f["parameters"].empty()) {
        s += "<table>" + row({"parameter", "value", "u (k = 1)", "unit"}, true);
        for (const auto& [name, p] : f["parameters"].items())
          s += row({escape(name), numCell(dbl(p, "value"), 3), numCell(dbl(p, "u"), 3), escape(str(p, "unit"))});
        s += "</table>\n";
      }
      if (f.contains("location_errors")) {
        s += "<p class=\"note\">Location errors re-estimated with the extended model, beside the baseline's:</p>";
        s += locationTable(f["location_errors"], {{"baseline", base.contains("location_errors") ? &base["location_errors"] : nullptr}});
      }
      const double k = static_cast<double>(gain.x.categories.size());
      gain.x.categories.push_back("+ " + str(f, "cause"));
      fit.x.push_back(k);
      fit.y.push_back(dbl(f, "residual_rms_um", 0));
      held.x.push_back(k);
      held.y.push_back(dbl(f, "holdout_rms_um", 0));
    }
    gain.series = {fit, held};
    gain.note = "The gain is measured on data left out of the fit, not asserted.";
    s += figureBlock(gain);
  }
  if (doc.contains("confounded") && !doc["confounded"].empty()) {
    s += "<h2>Confounded causes</h2><table>" + row({"causes", "why", "separate with"}, true);
    for (const auto& c : doc["confounded"]) {
      std::string names;
      for (const auto& n : c["causes"]) names += (names.empty() ? "" : ", ") + escape(n.get<std::string>());
      s += row({names, escape(str(c, "why")), escape(str(c, "separate_with"))});
    }
    s += "</table>\n";
  }
  if (doc.contains("candidates") && !doc["candidates"].empty()) {
    s += "<h2>Candidates tried</h2><table>" +
         row({"cause", "variant", "parameters", "residual rms (um)", "held-out rms (um)", "chi2", "p", "verdict"}, true);
    for (const auto& c : doc["candidates"])
      s += row({escape(str(c, "cause")), escape(str(c, "variant")), escape(str(c, "parameters")),
                numCell(dbl(c, "residual_rms_um"), 3), numCell(dbl(c, "holdout_rms_um"), 3), numCell(dbl(c, "chi2"), 1),
                fmt::format("{:.3g}", dbl(c, "p", 1)), escape(str(c, "verdict"))});
    s += "</table>\n";
  }
  if (base.contains("location_errors")) {
    s += "<h2>Baseline location errors</h2>" + locationTable(base["location_errors"]);
  }
  return s;
}

std::string historyBody(const Json& doc) {
  std::string s;
  s += "<h2>Calibrations</h2><table>" + row({"#", "time (UTC)", "cycle", "method", "residual rms (um)", "report"}, true);
  if (doc.contains("calibrations"))
    for (const auto& c : doc["calibrations"])
      s += row({escape(str(c, "seq")), escape(str(c, "time_utc")), escape(str(c, "cycle")), escape(str(c, "method")),
                numCell(dbl(c, "residual_rms_um"), 3), escape(str(c, "source"))});
  s += "</table>\n";
  if (doc.contains("trends")) {
    s += "<h2>Trend of each parameter</h2><p class=\"note\">" + escape(str(doc, "test")) + "</p><table>" +
         row({"parameter", "unit", "drift", "drift rate", "chi2 / dof (drift fit)", "step", "step size", "verdict"}, true);
    for (const auto& name : paperOrder(doc["trends"])) {
      const Json& t = doc["trends"][name];
      const std::string verdict = str(t, "verdict");
      const std::string cls = verdict == "step" ? "flag-step" : verdict == "drift" ? "flag-drift" : "";
      s += fmt::format("<tr class=\"{}\">", cls);
      s += "<td>" + escape(name) + "</td><td>" + escape(str(t, "unit")) + "</td>";
      s += "<td>" + std::string(t.value("drift", false) ? "<b>yes</b>" : "no") + "</td>";
      s += "<td>" + numCell(dbl(t, "drift_per_day"), 3) + " " + escape(str(t, "unit")) + "/day</td>";
      s += "<td>" + numCell(dbl(t, "chi2_drift"), 1) + " / " + escape(str(t, "dof_drift")) + "</td>";
      s += "<td>" + (t.contains("step_after_seq") && !t["step_after_seq"].is_null() ? "after #" + escape(str(t, "step_after_seq"))
                                                                                   : std::string("no")) + "</td>";
      s += "<td>" + numCell(dbl(t, "step_size"), 3) + "</td>";
      s += "<td><b>" + escape(verdict) + "</b></td></tr>\n";
    }
    s += "</table>\n";
  }
  return s;
}

}  // namespace

std::string reportHtml(const Json& doc) {
  const std::string format = str(doc, "format");
  std::string title, body, figures_heading = "Figures";
  if (format == "rotacal-report/1") {
    title = "rotacal calibration report: " + str(doc, "cycle") + ", " + str(doc, "machine");
    body = analyzeBody(doc);
    figures_heading = "Cycle figures";
  } else if (format == "rotacal-diagnosis/1") {
    title = "rotacal diagnosis";
    body = diagnoseBody(doc);
    figures_heading = "Residuals before and after";
  } else if (format == "rotacal-history/1") {
    title = "rotacal calibration history: " + str(doc, "machine_id");
    body = historyBody(doc);
    figures_heading = "Parameters over time";
  } else {
    title = "rotacal: " + (format.empty() ? std::string("figures") : format);
  }
  body += figuresSection(doc, figures_heading);
  std::string s = "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n";
  s += "<title>" + escape(title) + "</title>\n" + kStyle + "\n" + kErrorTrap + "\n</head><body>\n";
  s += "<h1>" + escape(title) + "</h1>\n" + body + kScript + "\n</body></html>\n";
  return s;
}

}  // namespace rotacal::report
