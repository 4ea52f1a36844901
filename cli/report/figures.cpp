// The report's figures (report/figures.hpp). Curves that may coincide get distinct dash patterns,
// and a legend entry says "identical to" when two curves are the same to rounding; legends sit
// outside the plots; top views show the whole machine with equal axis scales and its heading.
// Compiled once, into wlx itself: every name and number comes from the model's side
// (report/results.hpp), none from a model's generated tables.
#include "report/figures.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <wlx/support/atomic_file.hpp>
#include <wlx/support/text.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>
#include <sstream>

namespace wlx::cli::report {

namespace {

// Every text in a script, the report file's and the scenarios' names and labels included, goes in
// as a gnuplot single-quoted string: nothing in it can end the string or the command.
std::string q(std::string_view text) { return text::gnuplot_string(text); }

// The legend titles of curves given as sample vectors: "<name> (identical to <earlier>)" where a
// curve equals an earlier one to `tolerance`, since the later one is drawn over it.
std::vector<std::string> legend_titles(const std::vector<std::string>& names, const std::vector<std::vector<double>>& curves,
                                       double tolerance) {
  std::vector<std::string> titles = names;
  for (std::size_t k = 0; k < curves.size(); ++k)
    for (std::size_t e = 0; e < k; ++e) {
      double diff = 0;
      for (std::size_t i = 0; i < curves[k].size(); ++i) diff = std::max(diff, std::abs(curves[k][i] - curves[e][i]));
      if (diff <= tolerance) {
        titles[k] += " (identical to " + names[e] + ")";
        break;
      }
    }
  return titles;
}

// A dash pattern per curve index, so that coinciding curves stay distinguishable.
int dash(std::size_t k) { return static_cast<int>(k % 5) + 1; }

// A curve needs two samples: a run that stopped before its second has none (and gnuplot refuses a
// plot whose data are empty). Why `what` of a simulation with `samples` samples is not drawn, or
// "" when it is.
std::string not_drawn(const std::string& what, std::size_t samples, const std::optional<Stop>& stopped) {
  if (samples >= 2) return "";
  if (!stopped) return what + " has fewer than two samples: nothing to draw";  // a complete run has two at least
  return fmt::format("{} stopped at t = {:.4f} s {} (it never left its start), with nothing to draw: {}", what, stopped->time,
                     samples == 0 ? "before its first sample" : "after its first sample", stopped->reason);
}
std::string not_drawn(const RunResult& r) { return not_drawn(r.id, static_cast<std::size_t>(r.samples), r.stopped); }

// ". Left out: <why>; <why>" to end a caption, or "".
std::string left_out(const std::vector<std::string>& why) {
  return why.empty() ? "" : fmt::format(". Left out: {}", fmt::join(why, "; "));
}

// A figure not drawn: its sentence stands in its place in the page (FigureSpec::omitted).
FigureSpec omitted(const std::string& name, const std::string& what, const std::vector<std::string>& why) {
  return {name, fmt::format("No figure of {}: {}.", what, fmt::join(why, "; ")), "", ""};
}

struct Bounds {
  double x0 = 1e300, x1 = -1e300, y0 = 1e300, y1 = -1e300, z0 = 0, z1 = -1e300;
  void add(const Eigen::Vector3d& p) {
    x0 = std::min(x0, p.x()), x1 = std::max(x1, p.x()), y0 = std::min(y0, p.y()), y1 = std::max(y1, p.y());
    z0 = std::min(z0, p.z()), z1 = std::max(z1, p.z());
  }
  void add(double x, double y) { add(Eigen::Vector3d(x, y, 0)); }
  // gnuplot ranges with a margin, the ground z = 0 included in the side view.
  std::string xy(double margin) const {
    return fmt::format("set xrange [{:.3f}:{:.3f}]\nset yrange [{:.3f}:{:.3f}]\n", x0 - margin, x1 + margin, y0 - margin, y1 + margin);
  }
  std::string xz(double margin) const {
    return fmt::format("set xrange [{:.3f}:{:.3f}]\nset yrange [{:.3f}:{:.3f}]\n", x0 - margin, x1 + margin, z0 - margin, z1 + margin);
  }
};

class Figures {
 public:
  Figures(const Results& results, const ModelTables& tables, const ReportSpec& spec, std::string data_dir)
      : results_(results), tables_(tables), spec_(spec), data_dir_(std::move(data_dir)) {
    body_frame_ = spec.pose_frame.empty() ? 0 : tables.frame_index(spec.pose_frame);
  }

  ReportFigures all() {
    ReportFigures f;
    write_poses();
    ik(f.ik);
    nonholonomic(f.nonholonomic);
    runs(f.kinematic);
    dynamics(f.dynamics);
    forward(f.forward, f.closed_loop);
    engine(f.engine);
    poses(f.poses);
    return f;
  }

 private:
  // The runs of one motion under weightings other than the model file's: the same poses.
  static bool duplicate_motion(const RunResult& r) { return r.weighting > 1; }
  static std::string title_of(const RunResult& r) { return r.scenario_id; }
  const std::string& coordinate_name(int c) const { return tables_.coordinates.at(static_cast<std::size_t>(c)); }
  const std::string& body_frame_name() const { return tables_.frames.at(static_cast<std::size_t>(body_frame_)); }

  // data/<run>-pose.dat: index 0 the start, index 1 the end; in each, the body outline then one
  // segment per frame from its parent (the skeleton), blank lines between segments; index 2 the
  // body frame's path.
  void write_poses() {
    for (const auto& r : results_.runs) {
      if (duplicate_motion(r) || r.poses.empty()) continue;  // no pose: poses() says so
      std::ostringstream out;
      for (const Pose& p : r.poses) {
        Bounds& b = bounds_[r.id];
        for (const auto& q : p.frames) b.add(q);
        for (const auto& q : p.outline) b.add(q);
        out << "# body outline\n";
        for (const auto& q : p.outline) out << fmt::format("{},{},{}\n", q.x(), q.y(), q.z());
        out << "\n";
        for (std::size_t f = 0; f < p.frames.size(); ++f) {
          const int parent = tables_.frame_parents.at(f);
          if (parent < 0) continue;
          for (std::size_t g : {static_cast<std::size_t>(parent), f}) {
            const auto& q = p.frames[g];
            out << fmt::format("{},{},{}\n", q.x(), q.y(), q.z());
          }
          out << "\n";
        }
        out << "\n";  // two blank lines: the next gnuplot index
        headings_[r.id].push_back({p.frames[static_cast<std::size_t>(body_frame_)], p.heading});
      }
      // Index 2: the path of the body frame, every sample.
      out << "# body frame path\n";
      for (const Eigen::Vector3d& q : r.body_path) {
        out << fmt::format("{},{},{}\n", q.x(), q.y(), q.z());
        bounds_[r.id].add(q);
      }
      write_file_atomically(data_dir_ + "/" + r.id + "-pose.dat", out.str());
    }
  }

  // gnuplot arrows for the heading at the start (gray) and the end (blue), in the view (a, b).
  std::string heading_arrows(const std::string& run, int a, int b, double length) {
    std::string s;
    const auto& h = headings_[run];
    for (std::size_t k = 0; k < h.size(); ++k) {
      const Eigen::Vector3d from = h[k].first, to = h[k].first + length * h[k].second;
      s += fmt::format("set arrow from {:.4f},{:.4f} to {:.4f},{:.4f} head filled size screen 0.015,25 lw 3 lc rgb '{}' front\n", from(a),
                       from(b), to(a), to(b), k == 0 ? "gray50" : "#b4371f");
    }
    return s;
  }

  // ", <value> with lines ... title '<label>'" for the report file's line of that key, or "".
  std::string reference_line(const std::string& key) const {
    const auto it = spec_.reference_lines.find(key);
    if (it == spec_.reference_lines.end()) return "";
    return fmt::format(", {:g} with lines dt 2 lw 2 lc rgb 'gray40' title {}", it->second.value, q(it->second.label));
  }

  void ik(std::vector<FigureSpec>& out) {
    for (const auto& s : results_.sweeps) {
      const std::vector<std::string>& joints = s.joints;
      const auto titles = legend_titles(joints, s.joint_values, 1e-9);
      const double xs = s.degrees ? kDegPerRad : 1;
      const std::string file = data_path(s.id + ".csv");
      std::string b = "set multiplot layout 2,1\nset key outside right top\n";
      b += fmt::format("set xlabel {}\nset ylabel 'joint angle (deg)'\nset title {}\nplot ",
                       q(fmt::format("{} ({})", s.input, s.degrees ? "deg" : "m")),
                       q(s.id + (s.closed_form ? ": dependent joints (closed form)"
                                                     : ": dependent joints (Newton; no closed form)")));
      for (std::size_t k = 0; k < joints.size(); ++k)
        b += fmt::format("{}{} using {}:{} with lines lw 2 dt {} title {}", k ? ", " : "", q(file), column(s.input, xs),
                         column(joints[k], kDegPerRad), dash(k), q(titles[k]));
      b += "\nset logscale y\nset format y '1e%L'\nset yrange [1e-18:1e-3]\nset ylabel 'analytic check error (m)'\n";
      b += fmt::format("set title {}\n", q(s.id + ": |target - FK(solution)| (zeros drawn at 1e-18)"));
      if (s.closed_form)
        b += fmt::format(
            "plot {0} using {1}:{2} with lines lw 2 title 'closed form', {0} using {1}:{3} with points pt 7 ps 0.4 "
            "title 'Newton'{4}\n",
            q(file), column(s.input, xs), log_column("check_error_closed_form"), log_column("check_error_newton"),
            reference_line("ik_check_error"));
      else  // no closed form: Newton's alone (the CSV has no closed-form column)
        b += fmt::format("plot {0} using {1}:{2} with points pt 7 ps 0.4 title 'Newton'{3}\n", q(file),
                         column(s.input, xs), log_column("check_error_newton"), reference_line("ik_check_error"));
      b += "unset multiplot\n";
      out.push_back(
          {"ik-" + s.id,
           fmt::format("{}: {} swept; {}", s.id, s.input,
                       s.closed_form ? "closed form and Newton" : "Newton's method (the limb has no closed form)"),
           "1000,800", b});
    }
  }

  void nonholonomic(std::vector<FigureSpec>& out) {
    std::vector<const RunResult*> runs;
    std::vector<std::string> why;
    for (const auto& r : results_.runs) {
      if (!r.nonholonomic_verification) continue;
      const std::string reason = not_drawn(r);
      if (reason.empty()) runs.push_back(&r);
      else why.push_back(reason);
    }
    if (runs.empty()) {
      if (!why.empty()) out.push_back(omitted("nh-residuals", "the wheel constraint residuals", why));
      return;
    }
    std::string b = fmt::format("set multiplot layout {},1\nset logscale y\nset format y '1e%L'\nset yrange [1e-19:1e-3]\n"
                                "set key outside right top\n",
                                runs.size());
    for (const RunResult* r : runs) {
      const std::string file = data_path(r->csv);
      b += fmt::format("set title {}\nset xlabel 't (s)'\nset ylabel 'm/s'\nplot ", q(r->id + ": |v_W . n_W|"));
      for (std::size_t w = 0; w < tables_.wheels.size(); ++w)
        b += fmt::format("{}{} using {}:{} with lines lw 2 dt {} title {}", w ? ", " : "", q(file), column("t"),
                         log_column("nh_residual_" + tables_.wheels[w]), dash(w), q("wheel " + tables_.wheels[w]));
      b += reference_line("wheel_residual") + "\n";
    }
    b += "unset multiplot\n";
    out.push_back({"nh-residuals", "Wheel constraint residual per wheel (zeros drawn at 1e-19)" + left_out(why),
                   fmt::format("1000,{}", 260 * runs.size()), b});
  }

  void runs(std::vector<FigureSpec>& out) {
    for (const auto& g : spec_.run_figures) {
      std::vector<const RunResult*> runs;
      std::vector<std::string> why;
      for (const auto& id : g.runs) {
        const RunResult* r = results_.find_run(id);
        if (!r) continue;  // not in this report (--quick)
        const std::string reason = not_drawn(*r);
        if (reason.empty()) runs.push_back(r);
        else why.push_back(reason);
      }
      if (runs.empty()) {
        if (!why.empty()) out.push_back(omitted("run-" + g.id, g.id, why));
        continue;
      }
      const int x = tables_.coordinate_index(g.x);
      std::string b = fmt::format("set multiplot layout 1,{}\nset key outside right top\n", g.y.size());
      for (const auto& name : g.y) {
        const int y = tables_.coordinate_index(name);
        b += fmt::format("set title {}\nset xlabel {}\nset ylabel {}\nplot ", q(fmt::format("{}: {} over {}", g.id, name, g.x)),
                         q(fmt::format("{} ({})", g.x, tables_.unit(x))), q(fmt::format("{} ({})", name, tables_.unit(y))));
        for (std::size_t k = 0; k < runs.size(); ++k)
          b += fmt::format("{}{} using {}:{} with lines lw 2 dt {} title {}", k ? ", " : "", q(data_path(runs[k]->csv)),
                           column(g.x, tables_.scale(x)), column(name, tables_.scale(y)), dash(k), q(runs[k]->id));
        b += "\n";
      }
      b += "unset multiplot\n";
      std::string caption = fmt::format("{}: {} over the driving input {}", g.id, fmt::format("{}", fmt::join(g.y, " and ")), g.x);
      if (!g.reference.empty()) caption += "; cf. " + g.reference;
      out.push_back({"run-" + g.id, caption + left_out(why), "1100,450", b});
      out.push_back(top_view(g.id, runs));
    }
  }

  // The contact paths and the body frame's path seen from above, with the machine at the start and the
  // end of each run, on equal axis scales.
  FigureSpec top_view(const std::string& id, const std::vector<const RunResult*>& runs) {
    Bounds b;
    std::string arrows;
    for (const RunResult* r : runs) {
      const Bounds& rb = bounds_[r->id];
      b.add(rb.x0, rb.y0), b.add(rb.x1, rb.y1);
      if (r->contact_x0 <= r->contact_x1) b.add(r->contact_x0, r->contact_y0), b.add(r->contact_x1, r->contact_y1);
      arrows += heading_arrows(r->id, 0, 1, 1.0);
    }
    std::string t = fmt::format("set title {}\n"
                                "set xlabel 'x (m)'\nset ylabel 'y (m)'\nset size ratio -1\nset key outside right top\n{}{}plot ",
                                q(id + ": top view (K0): paths, and the machine at the start and the end; arrows: heading"), b.xy(0.4), arrows);
    const std::string start_pose = data_path(runs.front()->id + "-pose.dat");
    t += fmt::format("{} index 0 using 1:2 with lines lw 1 lc rgb 'gray60' title 'machine at t = 0'", q(start_pose));
    for (std::size_t k = 0; k < runs.size(); ++k) {
      const std::string file = data_path(runs[k]->csv);
      t += fmt::format(", {} index 1 using 1:2 with lines lw 1 dt {} lc {} title {}", q(data_path(runs[k]->id + "-pose.dat")), dash(k),
                       k + 1, q(runs[k]->id + " machine at the end"));
      t += fmt::format(", {} index 2 using 1:2 with lines lw 3 dt {} lc {} title {}", q(data_path(runs[k]->id + "-pose.dat")), dash(k),
                       k + 1, q(fmt::format("{} {} path", runs[k]->id, body_frame_name())));
      for (std::size_t w = 0; w < tables_.wheels.size(); ++w) {
        const std::string& wheel = tables_.wheels[w];
        t += fmt::format(", {} using {}:{} with lines lw 2 dt {} lc {} title {}", q(file), column("x_W" + wheel), column("y_W" + wheel),
                         dash(k), k + 3 + 2 * static_cast<int>(w), q(fmt::format("{} wheel {} contact", runs[k]->id, wheel)));
      }
    }
    t += "\n";
    return {"run-" + id + "-top", fmt::format("{}: wheel contact paths and the path of frame {} seen from above, with the machine at the start "
                                              "and the end", id, body_frame_name()),
            "1100,650", t};
  }

  void dynamics(std::vector<FigureSpec>& out) {
    std::vector<std::vector<std::string>> panels = spec_.torque_panels;
    if (panels.empty()) {  // no report file: the actuators in two halves
      panels.resize(2);
      const auto& actuators = tables_.actuators;
      for (std::size_t k = 0; k < actuators.size(); ++k) panels[k * 2 / actuators.size()].emplace_back(actuators[k]);
    }
    for (const auto& r : results_.runs) {
      if (r.weighting == 0) continue;
      if (const std::string why = not_drawn(r); !why.empty()) {
        out.push_back(omitted("id-" + r.id, "the torques of " + r.id, {why}));
        continue;
      }
      const int weighting = r.weighting;
      const report::TorqueReference* reference = nullptr;
      for (const auto& ref : spec_.torque_references)
        if (ref.scenario == r.scenario_id && ref.weighting == weighting) reference = &ref;
      const double scale = r.largest_tau;
      std::string b = fmt::format("set multiplot layout {},1\nset xlabel 't (s)'\nset ylabel 'torque (N m)'\nset key outside right top\n",
                                  panels.size());
      for (std::size_t p = 0; p < panels.size(); ++p) {
        std::vector<std::string> names;
        std::vector<std::vector<double>> curves;
        for (const auto& joint : panels[p]) {
          const auto at = std::find(tables_.actuators.begin(), tables_.actuators.end(), joint) - tables_.actuators.begin();
          names.push_back("tau_" + joint);
          curves.push_back(r.tau.at(static_cast<std::size_t>(at)));
        }
        // Equal to rounding: 1e-9 of the largest torque of the run.
        const auto titles = legend_titles(names, curves, 1e-9 * std::max(scale, 1.0));
        b += fmt::format("set title {}\nplot ", q(fmt::format("{}, {}: torques{}", r.scenario_id, r.weighting_label,
                                                                reference ? " (cf. " + reference->figures[p] + ")" : "")));
        for (std::size_t k = 0; k < names.size(); ++k)
          b += fmt::format("{}{} using {}:{} with lines lw 2 dt {} title {}", k ? ", " : "", q(data_path(r.csv)), column("t"),
                           column(names[k]), dash(k), q(titles[k]));
        b += "\n";
      }
      b += "unset multiplot\n";
      std::string caption = fmt::format("{}: actuator torques with {}", r.scenario_id, r.weighting_label);
      if (reference) caption += fmt::format("; cf. {}", fmt::join(reference->figures, ", "));
      out.push_back({"id-" + r.id, caption, fmt::format("1100,{}", 380 * panels.size()), b});
    }
  }

  // The round trips' deviations in one figure, over time on a log axis (they span orders of
  // magnitude); the closed loops' signed tracking errors per commanded coordinate (mm, deg), one
  // panel per motion (the model file's weights; the table has every weighting).
  void forward(std::vector<FigureSpec>& trips, std::vector<FigureSpec>& loops) {
    const auto& rows = results_.forward;
    if (rows.empty()) return;
    // Why a row's round trip or closed loop has no curve: its inverse-dynamics run stopped, or it
    // stopped itself before its second sample; "" when it has one.
    const auto why_not = [](const ForwardRow& r, bool loop) {
      if (r.not_run) return fmt::format("{} {}, so it has no {}", r.id, r.not_run->describe(), loop ? "closed loop" : "round trip");
      return loop ? not_drawn("the closed loop of " + r.id, static_cast<std::size_t>(r.closed_loop_samples), r.closed_loop_stopped)
                  : not_drawn("the round trip of " + r.id, static_cast<std::size_t>(r.samples), r.round_trip_stopped);
    };
    std::vector<const ForwardRow*> drawn;
    std::vector<std::string> why;
    for (const auto& r : rows) {
      const std::string reason = why_not(r, false);
      if (reason.empty()) drawn.push_back(&r);
      else why.push_back(reason);
    }
    if (drawn.empty()) {
      trips.push_back(omitted("forward-round-trips", "the round trips", why));
    } else {
      std::string t = "set xlabel 't (s)'\nset ylabel 'max |s_forward - s_inverse| (m or rad)'\nset logscale y\nset format y '1e%L'\n"
                      "set key outside right top\nset title 'round trips: the torques of each inverse-dynamics run fed back'\nplot ";
      for (std::size_t k = 0; k < drawn.size(); ++k)
        t += fmt::format("{}{} using {}:{} with lines lw 2 dt {} title {}", k ? ", " : "", q(data_path(drawn[k]->csv)), column("t"),
                         log_column("round_trip_deviation"), dash(k), q(drawn[k]->id));
      trips.push_back({"forward-round-trips", "Round trips: the largest deviation of the forward-dynamics run from the inverse-dynamics "
                                              "run whose torques drive it, over time" + left_out(why), "1100,500", t + "\n"});
    }
    std::vector<const ForwardRow*> shown;
    std::vector<std::string> loops_why;
    for (const auto& r : rows) {
      if (r.id.size() >= 3 && r.id.substr(r.id.size() - 3) == "-w2") continue;
      const std::string reason = why_not(r, true);
      if (reason.empty()) shown.push_back(&r);
      else loops_why.push_back(reason);
    }
    if (shown.empty()) {
      if (!loops_why.empty()) loops.push_back(omitted("forward-closed-loop", "the closed loops' tracking errors", loops_why));
      return;
    }
    std::string l = fmt::format("set multiplot layout {},1\nset xlabel 't (s)'\nset ylabel 'q_ref - q (mm or deg)'\n"
                                "set key outside right top\n",
                                shown.size());
    for (const ForwardRow* r : shown) {
      l += fmt::format("set title {}\nplot ", q(r->id + ": closed-loop tracking error, computed torque + PD on a plant 10% heavier"));
      for (std::size_t j = 0; j < tables_.commanded.size(); ++j) {
        const int c = tables_.commanded[j];
        const bool angle = tables_.is_angle(c);
        l += fmt::format("{}{} using {}:{} with lines lw 2 dt {} title {}", j ? ", " : "", q(data_path(r->closed_loop_csv)), column("t"),
                         column("error_" + coordinate_name(c), angle ? kDegPerRad : 1e3), dash(j),
                         q(coordinate_name(c) + (angle ? " (deg)" : " (mm)")));
      }
      l += "\n";
    }
    l += "unset multiplot\n";
    loops.push_back({"forward-closed-loop", "A controller in the loop: the tracking error of computed torque with PD feedback on a "
                                            "plant 10% heavier than its model, from a perturbed start, per commanded coordinate" +
                                                left_out(loops_why),
                     fmt::format("1100,{}", 330 * shown.size()), l});
  }

  // Per run in the physics engine: the tracking error, each contact's slip, and each contact's
  // normal force, MuJoCo's against the model's for the same torques.
  void engine(std::vector<FigureSpec>& out) {
    for (const EngineRow& r : results_.engine) {
      const std::string why = not_drawn(r.id + " in the physics engine", static_cast<std::size_t>(r.samples), r.stopped);
      if (!why.empty()) {
        out.push_back(omitted("engine-" + r.id, r.id + " in the physics engine", {why}));
        continue;
      }
      const std::string csv = q(data_path(r.csv));
      std::string g = "set multiplot layout 3,1\nset xlabel 't (s)'\nset key outside right top\n";
      g += fmt::format("set title {}\nset ylabel 'max |q_ref - q|'\nplot {} using {}:{} with lines lw 2 title 'lengths (mm)', {} using {}:{} "
                       "with lines lw 2 dt 2 title 'angles (deg)'\n",
                       q(r.id + " in MuJoCo: tracking error of the commanded coordinates"), csv, column("t"),
                       column("tracking_error_m", 1e3), csv, column("t"), column("tracking_error_rad", kDegPerRad));
      g += fmt::format("set title {}\nset ylabel 'slip (mm/s)'\nplot ", q("each contact's slip: the speed of its material point on the ground"));
      const auto& contacts = tables_.contacts;
      for (std::size_t c = 0; c < contacts.size(); ++c)
        g += fmt::format("{}{} using {}:{} with lines lw 2 dt {} title {}", c ? ", " : "", csv, column("t"),
                         column("slip_" + contacts[c], 1e3), dash(c), q(contacts[c]));
      g += fmt::format("\nset title {}\nset ylabel 'normal force (N)'\nplot ", q("normal forces: MuJoCo's (solid) and the model's (dashed)"));
      for (std::size_t c = 0; c < contacts.size(); ++c)
        g += fmt::format("{0}{1} using {2}:{3} with lines lw 2 lc {5} title {6}, {1} using {2}:{4} with lines lw 2 dt 2 lc {5} notitle",
                         c ? ", " : "", csv, column("t"), column("normal_mujoco_" + contacts[c]), column("normal_wlx_" + contacts[c]),
                         c + 1, q(contacts[c]));
      g += "\nunset multiplot\n";
      out.push_back({"engine-" + r.id,
                     r.id + " in MuJoCo: the model's computed-torque controller drives the exported machine at 1 kHz along the run; "
                            "its tracking error, each contact's slip (the model's rolling and feet hold it at zero) and the normal "
                            "forces, MuJoCo's against the model's for the same torques",
                     "1100,990", g});
    }
  }

  void poses(std::vector<FigureSpec>& out) {
    for (const auto& r : results_.runs) {
      if (duplicate_motion(r)) continue;
      if (r.poses.empty()) {  // one sample still shows where it stood
        out.push_back(omitted("pose-" + title_of(r), "the poses of " + r.id, {not_drawn(r)}));
        continue;
      }
      const std::string dat = data_path(r.id + "-pose.dat");
      const Bounds& bounds = bounds_[r.id];
      const std::string title = title_of(r);
      const double end = r.last_t;
      std::string b = "set multiplot layout 1,2\nset size ratio -1\nset key outside bottom center horizontal\n";
      b += fmt::format("set title {}\nset xlabel 'x (m)'\nset ylabel 'z (m)'\n{}{}", q(title + ": side view"), bounds.xz(0.3),
                       heading_arrows(r.id, 0, 2, 1.0));
      b += fmt::format("plot {0} index 0 using 1:3 with linespoints lw 2 pt 7 ps 0.6 lc rgb 'gray60' title 'start t = 0', {0} index 1 "
                       "using 1:3 with linespoints lw 2 pt 7 ps 0.6 lc rgb '#1f5fb4' title 'end t = {1} s', 0 with lines lc rgb 'black' "
                       "title 'ground z = 0'\n",
                       q(dat), end);
      b += fmt::format("unset arrow\nset title {}\nset xlabel 'x (m)'\nset ylabel 'y (m)'\n{}{}", q(title + ": top view; arrows: heading"),
                       bounds.xy(0.3), heading_arrows(r.id, 0, 1, 1.0));
      b += fmt::format("plot {0} index 0 using 1:2 with linespoints lw 2 pt 7 ps 0.6 lc rgb 'gray60' title 'start', {0} index 1 using "
                       "1:2 with linespoints lw 2 pt 7 ps 0.6 lc rgb '#1f5fb4' title 'end'\n",
                       q(dat));
      b += "unset multiplot\n";
      out.push_back({"pose-" + title, title + ": the machine (body outline and the frames of the generated forward kinematics, each joined "
                                              "to its parent) at the start and the end",
                     "1200,450", b});
    }
  }

  const Results& results_;
  const ModelTables& tables_;
  const ReportSpec& spec_;
  std::string data_dir_;
  int body_frame_ = 0;
  std::map<std::string, Bounds> bounds_;
  std::map<std::string, std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>>> headings_;
};

}  // namespace

ReportFigures make_figures(const Results& results, const ModelTables& tables, const ReportSpec& spec, const std::string& data_dir) {
  return Figures(results, tables, spec, data_dir).all();
}

}  // namespace wlx::cli::report
