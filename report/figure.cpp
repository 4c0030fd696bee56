#include "report/figure.hpp"

#include <cmath>
#include <stdexcept>

namespace rotacal::report {

namespace {

std::vector<double> numbers(const Json& j, const std::string& where) {
  if (!j.is_array()) throw std::invalid_argument(where + ": expected an array of numbers");
  std::vector<double> v;
  v.reserve(j.size());
  for (const auto& e : j) {
    if (!e.is_number()) throw std::invalid_argument(where + ": expected numbers only");
    v.push_back(e.get<double>());
  }
  return v;
}

std::string text(const Json& j, const char* key, const std::string& where, bool required) {
  const auto it = j.find(key);
  if (it == j.end()) {
    if (required) throw std::invalid_argument(where + ": missing \"" + key + "\"");
    return {};
  }
  if (!it->is_string()) throw std::invalid_argument(where + ": \"" + key + "\" must be a string");
  return it->get<std::string>();
}

PlotAxis axis(const Json& j, const char* key, const std::string& where) {
  const auto it = j.find(key);
  if (it == j.end() || !it->is_object()) throw std::invalid_argument(where + ": missing axis \"" + key + "\"");
  PlotAxis a;
  a.label = text(*it, "label", where + "." + key, true);
  a.unit = text(*it, "unit", where + "." + key, true);
  if (const auto c = it->find("categories"); c != it->end()) {
    if (!c->is_array()) throw std::invalid_argument(where + "." + key + ".categories: expected strings");
    for (const auto& s : *c) {
      if (!s.is_string()) throw std::invalid_argument(where + "." + key + ".categories: expected strings");
      a.categories.push_back(s.get<std::string>());
    }
  }
  return a;
}

bool finite(const std::vector<double>& v) {
  for (double d : v)
    if (!std::isfinite(d)) return false;
  return true;
}

}  // namespace

std::string Figure::problem() const {
  if (id.empty()) return "figure without an id";
  for (char ch : id)
    if (!((ch >= 'a' && ch <= 'z') || (ch >= '0' && ch <= '9') || ch == '_')) return "id '" + id + "' is not [a-z0-9_]";
  if (x.unit.empty() || y.unit.empty()) return "figure " + id + ": every axis needs a unit";
  if (series.empty() && bands.empty()) return "figure " + id + ": nothing to draw";
  for (const auto& s : series) {
    if (s.style != "line" && s.style != "points") return "figure " + id + ", series " + s.name + ": style must be line or points";
    if (s.x.size() != s.y.size()) return "figure " + id + ", series " + s.name + ": x and y differ in length";
    if (!s.u.empty() && s.u.size() != s.y.size()) return "figure " + id + ", series " + s.name + ": u and y differ in length";
    if (!finite(s.x) || !finite(s.y) || !finite(s.u)) return "figure " + id + ", series " + s.name + ": a number is not finite";
  }
  for (const auto& b : bands) {
    if (b.x.size() != b.lo.size() || b.x.size() != b.hi.size()) return "figure " + id + ", band " + b.name + ": x, lo, hi differ in length";
    if (!finite(b.x) || !finite(b.lo) || !finite(b.hi)) return "figure " + id + ", band " + b.name + ": a number is not finite";
  }
  return {};
}

namespace {
// Each entry of the optional array `key` of figure object `j`: its name and where it stands for
// the messages ("figure ID, series NAME").
template <class F>
void eachNamed(const Json& j, const std::string& key, const std::string& noun, const std::string& where, F&& f) {
  const auto a = j.find(key);
  if (a == j.end()) return;
  if (!a->is_array()) throw std::invalid_argument(where + ": " + key + " must be an array");
  for (const auto& e : *a) {
    const std::string name = text(e, "name", where + "." + key, false);
    f(e, name, where + ", " + noun + " " + name);
  }
}
}  // namespace

Figure figureFromJson(const Json& j) {
  if (!j.is_object()) throw std::invalid_argument("figures: each figure must be an object");
  Figure f;
  f.id = text(j, "id", "figure", true);
  const std::string where = "figure " + f.id;
  f.title = text(j, "title", where, false);
  f.note = text(j, "note", where, false);
  f.x = axis(j, "x", where);
  f.y = axis(j, "y", where);
  eachNamed(j, "series", "series", where, [&](const Json& e, const std::string& name, const std::string& w) {
    PlotSeries ps;
    ps.name = name;
    if (e.contains("style")) ps.style = text(e, "style", w, true);
    if (!e.contains("x") || !e.contains("y")) throw std::invalid_argument(w + ": needs x and y");
    ps.x = numbers(e["x"], w + ".x");
    ps.y = numbers(e["y"], w + ".y");
    if (e.contains("u")) ps.u = numbers(e["u"], w + ".u");
    f.series.push_back(std::move(ps));
  });
  eachNamed(j, "bands", "band", where, [&](const Json& e, const std::string& name, const std::string& w) {
    PlotBand pb;
    pb.name = name;
    if (!e.contains("x") || !e.contains("lo") || !e.contains("hi")) throw std::invalid_argument(w + ": needs x, lo and hi");
    pb.x = numbers(e["x"], w + ".x");
    pb.lo = numbers(e["lo"], w + ".lo");
    pb.hi = numbers(e["hi"], w + ".hi");
    f.bands.push_back(std::move(pb));
  });
  if (const std::string p = f.problem(); !p.empty()) throw std::invalid_argument(p);
  return f;
}

Json figureToJson(const Figure& f) {
  Json j;
  j["id"] = f.id;
  if (!f.title.empty()) j["title"] = f.title;
  auto ax = [](const PlotAxis& a) {
    Json o = {{"label", a.label}, {"unit", a.unit}};
    if (!a.categories.empty()) o["categories"] = a.categories;
    return o;
  };
  j["x"] = ax(f.x);
  j["y"] = ax(f.y);
  Json s = Json::array();
  for (const auto& e : f.series) {
    Json o = {{"name", e.name}, {"style", e.style}, {"x", e.x}, {"y", e.y}};
    if (!e.u.empty()) o["u"] = e.u;
    s.push_back(o);
  }
  j["series"] = s;
  if (!f.bands.empty()) {
    Json b = Json::array();
    for (const auto& e : f.bands) b.push_back({{"name", e.name}, {"x", e.x}, {"lo", e.lo}, {"hi", e.hi}});
    j["bands"] = b;
  }
  if (!f.note.empty()) j["note"] = f.note;
  return j;
}

}  // namespace rotacal::report
