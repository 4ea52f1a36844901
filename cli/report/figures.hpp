// The report's figures, as gnuplot plot commands over the CSV files in data/ (report/gnuplot.hpp
// renders them). What is plotted together comes from the report file (run_figures, torque_figures,
// pose); without one every run still gets its figures. Compiled once, into wlx itself: it reads
// what the model's side computed (report/results.hpp).
#pragma once

#include "report/gnuplot.hpp"
#include "report/results.hpp"
#include "report/spec.hpp"

#include <string>
#include <vector>

namespace wlx::cli::report {

struct ReportFigures {
  std::vector<FigureSpec> ik, nonholonomic, kinematic, dynamics, forward, closed_loop, engine, poses;
};

// Also writes data/<run>-pose.dat (the skeletons at the start and the end of each run).
ReportFigures make_figures(const Results& results, const ModelTables& tables, const ReportSpec& spec, const std::string& data_dir);

}  // namespace wlx::cli::report
