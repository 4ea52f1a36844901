#include "command_line.hpp"

#include "bounded_input.hpp"

#include <fmt/format.h>
#include <wlx/support/diagnostics.hpp>
#include <wlx/error.hpp>

#include <optional>
#include <string>
#include <string_view>
#include <utility>

namespace wlx::cli {

namespace {

// CLI11's message `<prefix><name><separator><rest>` as (name, rest), where the name is one word
// and the rest one line; nullopt for any other message. (By hand, not by std::regex, which cost
// this file half its compile.)
std::optional<std::pair<std::string, std::string>> split_message(const std::string& text, std::string_view prefix,
                                                                 std::string_view separator) {
  if (text.compare(0, prefix.size(), prefix) != 0) return std::nullopt;
  const std::size_t at = text.find(separator, prefix.size());
  if (at == std::string::npos || at == prefix.size()) return std::nullopt;
  std::string name = text.substr(prefix.size(), at - prefix.size()), rest = text.substr(at + separator.size());
  if (name.find_first_of(" \t\r\n\f\v") != std::string::npos || rest.find_first_of("\r\n") != std::string::npos) return std::nullopt;
  return std::pair{std::move(name), std::move(rest)};
}

// Options that may be repeated on purpose (e.g. --sweep IK-L1 --sweep IK-L2).
bool repeatable(const CLI::Option* option) { return option->get_expected_max() > 1; }

std::string command_path(const CLI::App* app) {
  std::string path;
  for (const CLI::App* a = app; a != nullptr && a->get_parent() != nullptr; a = a->get_parent())
    path = a->get_name() + (path.empty() ? "" : " " + path);
  return path;
}

std::string list(const std::vector<std::string>& names) {
  std::string out;
  for (std::size_t k = 0; k < names.size(); ++k)
    out += (k == 0 ? "" : k + 1 == names.size() ? " or " : ", ") + names[k];
  return out;
}

std::vector<std::string> subcommand_names(const CLI::App* app) {
  std::vector<std::string> names;
  for (const CLI::App* sub : app->get_subcommands({})) names.push_back(sub->get_name());
  return names;
}

std::vector<std::string> option_names(const CLI::App* app) {
  std::vector<std::string> names;
  for (const CLI::Option* option : app->get_options())
    for (const auto& long_name : option->get_lnames()) names.push_back("--" + long_name);
  return names;
}

// The deepest subcommand that was given, and the chain down to it.
std::vector<CLI::App*> parsed_chain(CLI::App& app) {
  std::vector<CLI::App*> chain{&app};
  for (;;) {
    CLI::App* next = nullptr;
    for (CLI::App* sub : chain.back()->get_subcommands()) next = sub;
    if (next == nullptr) return chain;
    chain.push_back(next);
  }
}

// Checks the parse that CLI11 accepted: extras, missing subcommands, repeated options.
void check(CLI::App& app) {
  const std::vector<CLI::App*> chain = parsed_chain(app);
  for (CLI::App* a : chain) {
    const std::string where = command_path(a);
    for (const std::string& extra : a->remaining(false)) {
      if (extra.rfind("-", 0) == 0 && extra.size() > 1) {
        const std::string name = extra.substr(0, extra.find('='));
        const std::string hint = nearest(name, option_names(a));
        throw Error(excerpt(name), fmt::format("unknown option{}{}", where.empty() ? "" : " of wlx " + where,
                                               hint.empty() ? " (--help lists them)" : "; did you mean '" + hint + "'?"));
      }
      if (a == chain.back() && !a->get_subcommands({}).empty()) {
        const std::string hint = nearest(extra, subcommand_names(a));
        throw Error(excerpt(extra), fmt::format("unknown subcommand{}; {}", where.empty() ? "" : " of wlx " + where,
                                                hint.empty() ? "the subcommands are " + list(subcommand_names(a))
                                                             : "did you mean '" + hint + "'?"));
      }
      throw Error(excerpt(extra), fmt::format("unexpected argument{}", where.empty() ? "" : " to wlx " + where));
    }
    for (const CLI::Option* option : a->get_options())
      if (option->count() > 1 && !repeatable(option))
        throw Error(option->get_name(), fmt::format("given {} times; give it once", option->count()));
    // CLI11 leaves a number option at its default for "": `--dt ""` must not run with the default.
    for (const CLI::Option* option : a->get_options())
      if (option->get_type_size_max() > 0)
        for (const std::string& value : option->results())
          if (value.empty()) throw Error(option->get_name(), "an empty value; give one");
  }
  const CLI::App* last = chain.back();
  if (!last->get_subcommands({}).empty())
    throw Error(last == &app ? "subcommand" : command_path(last),
                fmt::format("missing: give one of {} (--help explains them)", list(subcommand_names(last))));
}

}  // namespace

void prepare_command_line(CLI::App& app, const std::string& version) {
  app.set_version_flag("--version", version, "print the version and exit");
  app.require_subcommand(0, 1);
  app.allow_extras();
}

std::optional<int> parse_command_line(CLI::App& app, int argc, char** argv) {
  // Subcommands were added after prepare_command_line: give them the same settings.
  std::vector<CLI::App*> pending{&app};
  while (!pending.empty()) {
    CLI::App* a = pending.back();
    pending.pop_back();
    a->allow_extras();
    if (a != &app) a->require_subcommand(0, 1);
    for (CLI::App* sub : a->get_subcommands({})) pending.push_back(sub);
  }
  try {
    app.parse(argc, argv);
    check(app);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ConversionError& e) {
    // "Could not convert: --dt = abc" -> "--dt: 'abc' is not a valid value".
    const std::string what = e.what();
    if (const auto parts = split_message(what, "Could not convert: ", " = "))
      wlx::diagnose("wlx: error: {}: '{}' is not a valid value (a number is expected)\n", parts->first, excerpt(parts->second));
    else
      wlx::diagnose("wlx: error: {}\n", excerpt(what));
    return 2;
  } catch (const CLI::ArgumentMismatch& e) {
    // A single-valued option given twice: "--dt: At Most 1 required but received 2".
    const std::string what = e.what();
    const auto parts = split_message(what, "", ": At Most 1 required but received ");
    if (parts && !parts->second.empty() && parts->second.find_first_not_of("0123456789") == std::string::npos)
      wlx::diagnose("wlx: error: {}: given {} times; give it once\n", parts->first, parts->second);
    else
      wlx::diagnose("wlx: error: {} (wlx --help)\n", what);
    return 2;
  } catch (const CLI::ParseError& e) {
    wlx::diagnose("wlx: error: {} (wlx --help)\n", e.what());
    return 2;
  } catch (const Error& e) {
    wlx::diagnose("wlx: error: {}\n", e.what());
    return 2;
  }
  return std::nullopt;
}

}  // namespace wlx::cli
