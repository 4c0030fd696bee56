#pragma once
// A plot as the `figures` array of REPORT.json / DIAGNOSIS.json describes it (schema agreed
// between the analyses, docs/reports.md): labelled axes with units, series drawn as a polyline
// or a point set with optional standard uncertainties, and optional bands (e.g. U = +-(A + K L)).
#include <string>
#include <vector>

#include "core/json_io.hpp"

namespace rotacal::report {

struct PlotAxis {
  std::string label;
  std::string unit;
  /// Category names: x values are indices 0..n-1 into them (e.g. the faces of the test piece).
  std::vector<std::string> categories;
};

struct PlotSeries {
  std::string name;
  std::string style = "line";  // "line" | "points"
  std::vector<double> x, y, u;  // u empty, or one standard uncertainty per point (unit of y)
};

struct PlotBand {
  std::string name;
  std::vector<double> x, lo, hi;
};

struct Figure {
  std::string id, title, note;
  PlotAxis x, y;
  std::vector<PlotSeries> series;
  std::vector<PlotBand> bands;

  /// Empty when drawable; otherwise what is wrong (lengths that differ, a bad style, ...).
  std::string problem() const;
};

/// Reads one element of `figures`; throws std::invalid_argument naming the field that is wrong.
Figure figureFromJson(const Json& j);
Json figureToJson(const Figure& f);

}  // namespace rotacal::report
