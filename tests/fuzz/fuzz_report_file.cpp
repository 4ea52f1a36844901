// Fuzz target: the report-file reader (--claims). Any text either reads into a ReportSpec whose
// every text is one line of printable UTF-8 (what the gnuplot scripts and the page may receive,
// quoted again there) or is refused with a wlx::Error; no other exception, crash or hang.
#include "report/spec.hpp"

#include <wlx/error.hpp>
#include <wlx/support/text.hpp>

#include <cstdint>
#include <cstdlib>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* bytes, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(bytes), size);
  try {
    const wlx::cli::report::ReportSpec spec = wlx::cli::report::parse_report_spec(text, "fuzz.yaml");
    const auto one_line = [](const std::string& s) {
      if (!wlx::text::check_one_line(s).empty()) std::abort();
    };
    one_line(spec.title);
    for (const auto& [key, line] : spec.reference_lines) one_line(line.label);
    for (const auto& c : spec.claims) {
      one_line(c.id);
      one_line(c.claim);
      one_line(c.why);
    }
    for (const auto& f : spec.run_figures) one_line(f.id);
  } catch (const wlx::Error&) {
  }
  return 0;
}
