#include "bench/drawn_effect.hpp"

#include <stdexcept>

namespace rotacal::independent {

std::vector<MeasurementRun> measureWithEffect(const ProbePlan& plan, const Machine& drawn,
                                              const std::function<void(Truth*)>& effect, int repeats, double cycle_s) {
  Truth base;
  base.errors = drawn.location;
  Truth with_effect = base;
  effect(&with_effect);
  std::vector<MeasurementRun> runs;
  for (int r = 0; r < repeats; ++r) {
    Machine repeat = drawn;
    repeat.touch_seed = drawn.touch_seed + 1000003ULL * static_cast<std::uint64_t>(r);
    MeasurementRun measured = measure(plan, repeat);
    Truth b = base, e = with_effect;
    b.start_time_s = e.start_time_s = r * cycle_s;
    const MeasurementRun without = simulate(plan, b, {1});
    const MeasurementRun with = simulate(plan, e, {1});
    if (with.points.size() != measured.points.size() || without.points.size() != measured.points.size())
      throw std::logic_error("the generator and the simulator measured different numbers of touches");
    for (size_t i = 0; i < measured.points.size(); ++i) {
      if (with.points[i].point_id != measured.points[i].point_id || without.points[i].point_id != measured.points[i].point_id)
        throw std::logic_error("the generator's and the simulator's touches are in different orders");
      measured.points[i].position_m_mm += with.points[i].position_m_mm - without.points[i].position_m_mm;
      measured.points[i].t_s = with.points[i].t_s;
    }
    runs.push_back(measured);
  }
  return runs;
}

}  // namespace rotacal::independent
