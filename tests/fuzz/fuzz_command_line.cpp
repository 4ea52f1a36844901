// Fuzz target: wlx's command-line parser. The input is split at newlines into arguments (at most
// 16); any argument list either parses or is refused with a message (parse_command_line returns
// the exit code), never a crash or a sanitizer finding. Nothing is run.
#include <app.hpp>
#include <command_line.hpp>

#include <cstdint>
#include <string>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* bytes, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(bytes), size);
  std::vector<std::string> args{"wlx"};
  for (std::size_t at = 0; at <= text.size() && args.size() <= 16;) {
    const std::size_t end = text.find('\n', at);
    args.push_back(text.substr(at, end == std::string::npos ? std::string::npos : end - at));
    if (end == std::string::npos) break;
    at = end + 1;
  }
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  CLI::App app{"wlx"};
  wlx::cli::Invocation inv;
  wlx::cli::define_command_line(app, inv, {"excavator", "walker"}, "fuzz");
  wlx::cli::parse_command_line(app, static_cast<int>(argv.size()), argv.data());
  return 0;
}
