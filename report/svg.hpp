#pragma once
// Inline SVG drawing for the HTML report. Ours, in C++: Debian 12 packages no maintained C++
// SVG plotting library (matplot++ and sciplot are not packaged and call gnuplot; gnuplot itself
// would be a run-time dependency producing files we would then have to inline), and what the
// report needs is small: linear axes with nice ticks, labels with units, polylines, markers,
// error bars, bands, a legend.
#include <string>
#include <vector>

#include <Eigen/Core>

#include "report/figure.hpp"

namespace rotacal::report {

/// HTML/XML text escaping (&, <, >, ").
std::string escape(const std::string& s);

/// The figure as one <svg> element (width x height px), every axis labelled "label (unit)".
std::string svgPlot(const Figure& f, int width = 640, int height = 340);

/// Ticks of a linear axis: about `target` round values covering [lo, hi].
std::vector<double> niceTicks(double lo, double hi, int target);

/// The colour of series i (a fixed palette readable on white).
const char* seriesColour(size_t i);

/// One panel of the deviation views (000 Figs. 7-9): a projection of touch points, the
/// nominal as black dots, the measured as circles at nominal + magnification * deviation.
struct ProjectionPoint {
  Eigen::Vector2d nominal_mm;
  Eigen::Vector2d deviation_um;  // projected deviation vector, um (before magnification)
};
struct ProjectionPanel {
  std::string title;                    // e.g. "(II) A = 0 deg, C = 90 deg"
  std::string x_label, y_label;         // e.g. "X", "Y" (unit mm)
  std::vector<ProjectionPoint> points;
};
/// `limits_mm` (xmin, xmax, ymin, ymax) shared by the panels of one view so that they compare.
std::string svgProjection(const ProjectionPanel& panel, double magnification, const Eigen::Vector4d& limits_mm,
                          double scale_bar_um, int size_px = 260);

}  // namespace rotacal::report
