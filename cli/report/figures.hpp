// The report's figures for one model, as gnuplot plot commands over the CSV files in data/
// (report/gnuplot.hpp renders them). What is plotted together comes from the report file
// (run_figures, torque_figures, pose); without one every run still gets its figures.
#pragma once

#include "per_model.hpp"
#include "report/gnuplot.hpp"
#include "report/runner.hpp"

#include <string>
#include <vector>

WLX_COMMANDS_BEGIN

struct ReportFigures {
  std::vector<report::FigureSpec> ik, nonholonomic, kinematic, dynamics, forward, closed_loop, engine, poses;
};

// Also writes data/<run>-pose.dat (the skeletons at the start and the end of each run).
ReportFigures make_figures(ReportRunner& runner, const report::ReportSpec& spec, const std::string& data_dir);

WLX_COMMANDS_END
