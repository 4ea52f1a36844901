// The precompiled header of a model file's plugin's commands (cli/commands/, compiled at -O0): the
// headers of plugin_prelude.hpp, and the templates of theirs that the commands instantiate whatever
// the model: nlohmann-json's parsing, lookups, conversions and building of objects, the standard
// containers of names and numbers, fmt's joins. wlx's build precompiles this header with
// -fpch-instantiate-templates and -fpch-codegen, and compiles the result once, a section per
// function, into an archive (plugin_prelude-O0.a, CMakeLists.txt): a unit that loads it neither
// instantiates these templates nor generates their code again, and the plugin links the archive
// (cli/shell/model_plugin.cpp). That took about a sixth off the commands' compile (alternating,
// medians of three: an excavator copy's 12.2 s of CPU to 10.4 s, 2026-12-07), where the same for
// the runtime's -O3 parts made them slower (a larger header to load, and code the optimizer
// inlines anyway): they load plugin_prelude.hpp alone (unless WLX_PLUGIN_CXXFLAGS gives both parts
// the commands' flags: then both load this one).
// Nothing here may depend on a model; nothing calls these functions.
#pragma once

#include "plugin_prelude.hpp"

namespace wlx::plugin_prelude {

// What the commands do with a JSON value of either kind (the inputs' nlohmann::json, the answers'
// ordered_json): each expression instantiates the member templates it names, here once.
template <class Json>
inline void json_instances(Json& j, const std::string& s, double x, long n, bool b, const std::vector<std::string>& names,
                           const std::vector<double>& values) {
  j = Json::parse(s);
  (void)j.dump();
  (void)j.dump(2);
  for (const auto& [key, value] : j.items()) (void)key, (void)value;
  for (const auto& value : j) (void)value;
  (void)(j == "text");
  (void)(j == 1);
  (void)(j == s);
  (void)(j != s);
  (void)j.at(s);
  (void)j.at(0);
  (void)j.contains(s);
  (void)j.contains(s.c_str());
  (void)j.find(s);
  (void)j.size();
  (void)j.empty();
  (void)j.type_name();
  (void)j.template get<double>();
  (void)j.template get<std::string>();
  (void)j.template get<bool>();
  (void)j.template get<int>();
  (void)j.template get<long>();
  (void)j.template get<unsigned long>();
  (void)j.template get<long long>();
  (void)j.template get<unsigned long long>();
  (void)j.template get<std::vector<double>>();
  (void)j.template get<std::vector<std::string>>();
  (void)j.template get_ref<const std::string&>();
  (void)j.value(s, s);
  (void)j.value(s, x);
  (void)j.value(s, b);
  j[s] = x;
  j[s] = s;
  j[s] = "text";
  j[s] = b;
  j[s] = n;
  j[s] = 1;
  j[s] = names;
  j[s] = values;
  j[s] = Json::object();
  j[s] = Json::array();
  j["text"] = x;
  j[0] = x;
  j.push_back(x);
  j.push_back(s);
  j.push_back(Json(x));
  j.push_back(Json::object());
  j.emplace_back(x);
  Json copy = j;
  Json moved = std::move(copy);
  Json from_names(names), from_values(values), from_string(s), from_literal("text"), from_x(x), from_n(n), from_b(b);
  // Objects and arrays written as initializer lists, with keys of every length up to 24 characters
  // (each length is a type of its own: const char (&)[N]).
  Json object = {{"a", x}, {"ab", x}, {"abc", x}, {"abcd", x}, {"abcde", x}, {"abcdef", x}, {"abcdefg", x}, {"abcdefgh", x},
                 {"abcdefghi", x}, {"abcdefghij", x}, {"abcdefghijk", x}, {"abcdefghijkl", x}, {"abcdefghijklm", x},
                 {"abcdefghijklmn", x}, {"abcdefghijklmno", x}, {"abcdefghijklmnop", x}, {"abcdefghijklmnopq", x},
                 {"abcdefghijklmnopqr", x}, {"abcdefghijklmnopqrs", x}, {"abcdefghijklmnopqrst", x},
                 {"abcdefghijklmnopqrstu", x}, {"abcdefghijklmnopqrstuv", x}, {"abcdefghijklmnopqrstuvw", x},
                 {"abcdefghijklmnopqrstuvwx", x}, {s, s}, {s, n}, {s, b}, {s, names}, {s, values}};
  Json list = {x, n, s};
  (void)moved;
  (void)object;
  (void)list;
}

inline void instances(nlohmann::json& j, nlohmann::ordered_json& o, const std::string& s, std::string_view view, double x, long n,
                      bool b, const std::vector<std::string>& names, const std::vector<double>& values) {
  json_instances(j, s, x, n, b, names, values);
  json_instances(o, s, x, n, b, names, values);
  std::vector<std::string> v = names;
  v.push_back(s);
  v.emplace_back("text");
  v.emplace_back(view);
  v.insert(v.end(), names.begin(), names.end());
  std::sort(v.begin(), v.end());
  (void)std::find(v.begin(), v.end(), s);
  std::vector<double> w = values;
  w.push_back(x);
  w.insert(w.end(), values.begin(), values.end());
  std::vector<std::pair<int, double>> pairs;
  pairs.emplace_back(1, x);
  std::map<std::string, double> by_name;
  by_name[s] = x;
  (void)by_name.find(s);
  std::map<std::string, std::vector<double>> columns;
  columns[s].push_back(x);
  std::map<std::string, std::string> texts;
  texts[s] = s;
  std::set<std::string> set(v.begin(), v.end());
  (void)set.count(s);
  (void)fmt::format("{}", fmt::join(v, ", "));
  (void)fmt::format("{}", fmt::join(w, ", "));
}

}  // namespace wlx::plugin_prelude
