// Rendering index.html (report/html.hpp).
#include "report/html.hpp"

#include <fmt/format.h>
#include <wlx/support/text.hpp>

namespace wlx::cli::report {

// One quoting function for all of the page (wlx/support/text.hpp): element text and attribute values.
std::string escape(const std::string& s) { return text::html(s); }

namespace {

std::string lines(const std::vector<std::string>& items) {
  std::string out;
  for (std::size_t k = 0; k < items.size(); ++k) out += (k ? "<br />" : "") + escape(items[k]);
  return out;
}

std::string cell(const Cell& c) {
  return c.href.empty() ? escape(c.text) : fmt::format("<a href=\"{}\">{}</a>", escape(c.href), escape(c.text));
}

std::string table(const Table& t) {
  std::string h = "<table>\n<tr>";
  for (const auto& col : t.header) h += "<th>" + escape(col) + "</th>";
  h += "</tr>\n";
  for (const auto& row : t.rows) {
    h += "<tr>";
    for (const auto& c : row) h += "<td>" + cell(c) + "</td>";
    h += "</tr>\n";
  }
  return h + "</table>\n";
}

// A column per source, headed by its name (the report file's), for the value as it states it.
std::string claims_table(const std::vector<ClaimRow>& rows, bool with_criterion, const std::vector<std::pair<std::string, std::string>>& sources) {
  std::string h = "<table class=\"claims\">\n<tr><th>claim</th><th>source</th>";
  for (const auto& [name, what] : sources) h += "<th>" + escape(name) + "</th>";
  h += "<th>wlx</th>";
  h += with_criterion ? "<th>criterion</th><th>result</th>" : "";
  h += "<th>why</th></tr>\n";
  for (const auto& r : rows) {
    h += fmt::format("<tr id=\"claim-{}\"><td>{}</td><td>{}</td>", escape(r.id), escape(r.claim), escape(r.source));
    for (std::size_t k = 0; k < sources.size(); ++k) h += "<td>" + escape(k < r.claimed.size() ? r.claimed[k] : std::string()) + "</td>";
    h += fmt::format("<td class=\"wlx\">{}</td>", lines(r.measured));
    if (with_criterion) {
      const bool pass = r.result == ClaimRow::Result::pass;
      h += fmt::format("<td class=\"criterion\">{}</td><td class=\"{}\">{}</td>", lines(r.criteria), pass ? "pass" : "fail", pass ? "pass" : "FAIL");
    }
    h += fmt::format("<td class=\"why\">{}</td></tr>\n", escape(r.why));
  }
  return h + "</table>\n";
}

void section(std::string& h, const Section& s, int level) {
  h += fmt::format("<h{0} id=\"{1}\">{2}</h{0}>\n", level, escape(s.id), escape(s.title));
  if (!s.intro.empty()) h += "<p>" + escape(s.intro) + "</p>\n";
  for (const auto& t : s.tables) h += table(t);
  for (const auto& f : s.figures)
    if (f.omitted())  // said in words where the figure would be
      h += fmt::format("<p id=\"fig-{}\" class=\"omitted\">{}</p>\n", escape(f.name), escape(f.caption));
    else
      h += fmt::format("<figure id=\"fig-{0}\"><a href=\"fig/{0}.svg\"><img src=\"fig/{0}.png\" alt=\"{1}\" /></a>"
                     "<figcaption>{1} (<a href=\"plots/{0}.gp\">script</a>)</figcaption></figure>\n",
                     escape(f.name), escape(f.caption));
  for (const auto& sub : s.subsections) section(h, sub, level + 1);
}

void contents(std::string& h, const std::vector<Section>& sections) {
  h += "<ul>\n";
  for (const auto& s : sections) {
    h += fmt::format("<li><a href=\"#{}\">{}</a>", escape(s.id), escape(s.title));
    if (!s.subsections.empty()) contents(h, s.subsections);
    h += "</li>\n";
  }
  h += "</ul>\n";
}

}  // namespace

std::string render_html(const Document& d) {
  std::string h;
  h += fmt::format("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\" />\n<title>wlx report: {}</title>\n",
                   escape(d.title));
  h += "<style>\nbody{font-family:sans-serif;max-width:1250px;margin:2em auto;padding:0 1em;color:#222}\n"
       "table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid #bbb;padding:4px 8px;vertical-align:top}\n"
       "th{background:#eee}.pass{color:#176b17;font-weight:bold}.fail{color:#b00;font-weight:bold}\n"
       "td.why{color:#555;font-size:90%;max-width:24em}td.wlx,td.criterion{white-space:nowrap}\n"
       "figure{margin:1.5em 0}figure img{max-width:100%;border:1px solid #ddd}figcaption{color:#555}\n"
       "p.omitted{color:#555;font-style:italic;border-left:3px solid #bbb;padding-left:0.6em}\n"
       "nav{background:#f6f6f6;padding:0.5em 1em;border:1px solid #ddd}\n"
       "code{background:#f4f4f4;padding:1px 3px}\n</style>\n</head>\n<body>\n";
  h += fmt::format("<h1>wlx report: {}</h1>\n", escape(d.title));
  h += "<table class=\"about\">\n";
  for (const auto& [key, value] : d.about) h += fmt::format("<tr><th>{}</th><td>{}</td></tr>\n", escape(key), escape(value));
  h += "</table>\n";
  h += "<p>Each figure links to its SVG and its gnuplot script; the CSV files behind the figures are in "
       "<code>data/</code>, the scripts in <code>plots/</code> (run <code>gnuplot NAME.gp</code> in that folder).</p>\n";

  std::vector<Section> toc;
  if (!d.stopped_runs.rows.empty()) toc.push_back({"stopped", "Stopped runs", "", {}, {}, {}});
  toc.push_back({"checks", "Checks", "", {}, {}, {}});
  toc.push_back({"inputs", "Inputs and set-up (not checks)", "", {}, {}, {}});
  toc.push_back({"observations", "Observations: where wlx differs from its sources", "", {}, {}, {}});
  for (const auto& s : d.sections) toc.push_back(s);
  toc.push_back({"parameters", "Parameters", "", {}, {}, {}});
  h += "<nav>\n<h2 id=\"contents\">Contents</h2>\n";
  contents(h, toc);
  h += "</nav>\n";

  if (!d.stopped_runs.rows.empty()) {
    h += fmt::format("<h2 id=\"stopped\">Stopped runs</h2>\n<p class=\"fail\">{} of the report's simulations stopped before their "
                     "end. Each is shown with what it computed up to there (its CSV, its figures where it has at least two "
                     "samples); a check that depends on one fails with its reason, and the report exits with 1.</p>\n",
                     d.stopped_runs.rows.size());
    h += table(d.stopped_runs);
  }
  std::size_t failed = 0;
  for (const auto& c : d.checks) failed += c.result != ClaimRow::Result::pass;
  h += "<h2 id=\"checks\">Checks</h2>\n";
  if (d.claims_source.empty()) {
    h += "<p>This model has no report file with claims: the report shows its runs without checks.</p>\n";
  } else {
    h += fmt::format("<p>{} of {} checks pass. Each check is a claim of the sources below that wlx's "
                     "result could fail: its criterion (in the unit shown) stands beside the measured value, its "
                     "justification in the last column. The claims and their sources are data: <code>{}</code>.{}</p>\n",
                     d.checks.size() - failed, d.checks.size(), escape(d.claims_source),
                     d.skipped_claims ? fmt::format(" {} claims concern runs this report did not make (--quick) and are left out.",
                                                    d.skipped_claims)
                                      : "");
    if (!d.sources.empty()) {
      h += "<p>Sources:";
      for (const auto& [name, what] : d.sources) h += fmt::format(" <b>{}</b>: {}.", escape(name), escape(what));
      h += "</p>\n";
    }
    h += claims_table(d.checks, true, d.sources);
  }
  h += "<h2 id=\"inputs\">Inputs and set-up (not checks)</h2>\n<p>Values the sources report that follow from the "
       "inputs of a run (a commanded rate times the duration, a coordinate held constant, a sum of input masses): "
       "wlx reproduces them by construction, so they cannot fail and are not counted as checks.</p>\n";
  if (!d.inputs.empty()) h += claims_table(d.inputs, false, d.sources);
  h += "<h2 id=\"observations\">Observations: where wlx differs from its sources</h2>\n<p>Where wlx deliberately "
       "computes something else than the source, or the source gives no number to hold wlx against.</p>\n";
  if (!d.observations.empty()) h += claims_table(d.observations, false, d.sources);
  for (const auto& s : d.sections) section(h, s, 2);
  h += "<h2 id=\"parameters\">Parameters</h2>\n" + table(d.parameters);
  h += "</body>\n</html>\n";
  return h;
}

}  // namespace wlx::cli::report
