// What a run's samples add up to that does not depend on the model's sizes: its sample count and
// last time, its worst condition and clearance, its lowest contact margins with where and when,
// and its first slip and lift-off. The per-model summary (cli/commands/run_summary.hpp) adds to it
// sample by sample; the report (cli/report) shows it as it is.
#pragma once

namespace wlx::cli {

// The lowest value of a margin over a run, its contact (or, for a tip-over edge, its two contacts)
// and its time.
struct Lowest {
  double value = 0, t = 0;
  int contact = -1, other = -1;  // -1: none (the run has no such value)
  void add(double v, int c, double time, int d = -1) {
    if (contact < 0 || v < value) value = v, contact = c, other = d, t = time;
  }
};

struct RunExtremes {
  long samples = 0;
  double last_t = 0;  // the last sample's t (0 without samples)
  // Maxima and minima over the samples, meaningful once samples > 0 (a run that stopped at its
  // first step has none: callers print "-", never an initial value such as 1e300).
  double worst_cond = 0;      // max cond(J_beta)
  double min_clearance = 0;   // m (+infinity without a clearance box)
  double worst_momentum = 0;  // max momentum-balance residual (dynamics runs with contacts)
  // Dynamics runs of a model with contacts: the lowest normal force, friction margin and tip angle,
  // and the first sample where a contact slips (friction margin < 0) or pulls (normal force < 0).
  Lowest normal, friction, tip;
  int first_slip = -1, first_pull = -1;  // the contact, or -1
  double slip_t = 0, pull_t = 0;
};

}  // namespace wlx::cli
