// The report's index.html, rendered from a model-independent description of its contents: the
// claims in three tables (checks, inputs and set-up, observations), then one section per group of
// runs with its tables and figures, a table of contents and anchors. The per-model code
// (report/document.cpp) fills the description.
#pragma once

#include "report/gnuplot.hpp"

#include <map>
#include <string>
#include <utility>
#include <vector>

namespace wlx::cli::report {

struct Cell {
  Cell(std::string text_in, std::string href_in = {}) : text(std::move(text_in)), href(std::move(href_in)) {}
  std::string text;  // plain text (escaped when rendered)
  std::string href;  // a link, relative to index.html, if not empty
};

struct Table {
  std::vector<std::string> header;
  std::vector<std::vector<Cell>> rows;
};

// One claim of the report file with wlx's measured values (one line per test).
struct ClaimRow {
  std::string id, claim, source, why;
  std::vector<std::string> claimed;  // as each of Document::sources states it ("" where it does not)
  std::vector<std::string> measured, criteria;
  enum class Result { pass, fail, none } result = Result::none;  // none: inputs and observations
};

struct Section {
  std::string id, title;  // anchor and heading
  std::string intro;      // plain text, may be empty
  std::vector<Table> tables;
  std::vector<FigureSpec> figures;
  std::vector<Section> subsections;
};

struct Document {
  std::string title;
  std::vector<std::pair<std::string, std::string>> about;  // version, model, date, command line, ...
  Table parameters;
  std::vector<ClaimRow> checks, inputs, observations;
  Table stopped_runs;  // the simulations that ended before their duration: run, time, reason (no rows: none)
  std::vector<std::pair<std::string, std::string>> sources;  // the claims' sources: name, what it is (a column each)
  std::string claims_source;  // where the claims come from (a file), or empty: the model has none
  int skipped_claims = 0;     // claims about runs this report did not make (--quick)
  std::vector<Section> sections;
};

std::string escape(const std::string& text);
std::string render_html(const Document& document);

}  // namespace wlx::cli::report
