// The report's figures: one gnuplot script per figure in plots/, rendered to fig/*.png and
// fig/*.svg. Model-independent: the per-model code (report/figures.cpp) writes the plot commands.
#pragma once

#include <string>
#include <vector>

namespace wlx::cli::report {

struct FigureSpec {
  std::string name;     // file stem in fig/ and plots/: letters, digits, + - _ . only
  std::string caption;  // for the HTML
  std::string size;     // gnuplot canvas size, "900,600"
  std::string body;     // plot commands, emitted once per terminal; data files named as data_path() gives them
  // An omitted figure: no body, and its caption says why (a run stopped before it had anything to
  // draw). The page shows the sentence in its place; nothing is rendered.
  bool omitted() const { return body.empty(); }
};

// A data file as the scripts name it: relative to plots/, where the scripts run (so the user's
// --out path, with whatever characters it has, never appears inside a script).
std::string data_path(const std::string& file);

// A CSV column in a gnuplot `using` clause, optionally scaled; for log axes |x| floored at 1e-18.
std::string column(const std::string& name, double scale = 1);
std::string log_column(const std::string& name);

// The whole script of one figure: PNG then SVG, outputs ../fig/<name>.png|svg unless the caller
// sets `png` and `svg` with -e (wlx does, with temporary names it renames when complete).
std::string script(const FigureSpec& figure);

// Writes <root>/plots/<name>.gp for every figure and runs gnuplot on each in <root>/plots, two at
// a time, without a shell; a figure appears under its final name only when complete. Throws
// wlx::Error naming the figure and its log (plots/<name>.log) if gnuplot fails or is missing.
void render(const std::string& root, const std::vector<FigureSpec>& figures);

}  // namespace wlx::cli::report
