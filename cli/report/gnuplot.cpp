// Writing and running the report's gnuplot scripts (report/gnuplot.hpp).
#include "report/gnuplot.hpp"

#include "interrupt.hpp"
#include "output_checks.hpp"
#include "process.hpp"

#include <fmt/format.h>
#include <wlx/support/atomic_file.hpp>
#include <wlx/error.hpp>
#include <wlx/support/text.hpp>

#include <atomic>
#include <filesystem>
#include <thread>
#include <unistd.h>

namespace wlx::cli::report {

namespace fs = std::filesystem;

std::string data_path(const std::string& file) { return "../data/" + file; }

// Column names come from scenario files too: quoted like any text.
std::string column(const std::string& name, double scale) {
  const std::string quoted = text::gnuplot_string(name);
  return scale == 1 ? fmt::format("(column({}))", quoted) : fmt::format("(column({})*{})", quoted, scale);
}

std::string log_column(const std::string& name) {
  return fmt::format("(abs(column({0})) > 1e-18 ? abs(column({0})) : 1e-18)", text::gnuplot_string(name));
}

std::string script(const FigureSpec& f) {
  const std::string common = "set datafile separator ','\nset grid\nset key box opaque\nset encoding utf8\n";
  std::string gp = fmt::format(
      "# Renders ../fig/{0}.png and ../fig/{0}.svg from the CSV files in ../data/: run `gnuplot {0}.gp`\n"
      "# in this folder (plots/). wlx itself passes temporary output names with -e and renames the\n"
      "# finished images.\n"
      "if (!exists(\"png\")) png = '../fig/{0}.png'\nif (!exists(\"svg\")) svg = '../fig/{0}.svg'\n",
      f.name);
  gp += fmt::format("set terminal pngcairo size {} font 'DejaVu Sans,10' noenhanced\nset output png\n{}{}", f.size, common, f.body);
  gp += "reset\n";
  gp += fmt::format("set terminal svg size {} font 'DejaVu Sans,10' noenhanced\nset output svg\n{}{}", f.size, common, f.body);
  return gp;
}

void render(const std::string& root_dir, const std::vector<FigureSpec>& figures) {
  const fs::path root(root_dir);
  if (!run_program({"gnuplot", "--version"}).ok())
    throw Error("gnuplot", "not found: install Debian's gnuplot-nox (tools/setup.sh does)");
  const fs::path scripts = root / "plots";
  prepare_out_dir("--out", scripts.string());
  for (const auto& f : figures) {
    // Figure names go into gnuplot strings ('...') and -e: wlx's own identifiers, kept to a set
    // of characters that needs no quoting, so no name can inject gnuplot commands.
    if (f.name.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789+-_.") != std::string::npos)
      throw Error("report", fmt::format("figure name '{}' has a character gnuplot would need quoted", f.name));
    write_file_atomically((scripts / (f.name + ".gp")).string(), script(f));
  }
  // Two at a time: these machines have two cores.
  std::atomic<std::size_t> next{0};
  std::vector<std::string> failures(figures.size());
  const auto worker = [&] {
    for (std::size_t k; interrupt_signal() == 0 && (k = next++) < figures.size();) {
      const std::string& name = figures[k].name;
      const std::string png = fmt::format("{}.png.{}.tmp", name, static_cast<long>(::getpid()));
      const std::string svg = fmt::format("{}.svg.{}.tmp", name, static_cast<long>(::getpid()));
      const ProgramRun run = run_program({"gnuplot", "-e", fmt::format("png='../fig/{}'; svg='../fig/{}'", png, svg), name + ".gp"},
                                         scripts.string(), (scripts / (name + ".log")).string());
      const fs::path fig = root / "fig";
      std::error_code ec;
      bool ok = run.ok() && fs::file_size(fig / png, ec) > 0 && !ec && fs::file_size(fig / svg, ec) > 0 && !ec;
      if (ok) {
        fs::rename(fig / png, fig / (name + ".png"), ec);
        ok = !ec;
        if (ok) fs::rename(fig / svg, fig / (name + ".svg"), ec);
        ok = ok && !ec;
      }
      if (!ok) failures[k] = name;
      fs::remove(fig / png, ec);  // only a leftover temporary remains to remove
      fs::remove(fig / svg, ec);
    }
  };
  std::thread a(worker), b(worker);
  a.join();
  b.join();
  throw_if_interrupted();  // a figure failed because its gnuplot was interrupted too: say that instead
  for (const auto& f : failures)
    if (!f.empty()) throw Error("gnuplot", fmt::format("failed on {}: see {}", f, (scripts / (f + ".log")).string()));
}

}  // namespace wlx::cli::report
