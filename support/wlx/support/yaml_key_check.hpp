// A first pass over a YAML file's parse events, before yaml-cpp builds nodes, for the readers of
// model files (generator/) and report files (cli/report/). yaml-cpp's Node API keeps both entries
// of a key given twice but answers a lookup with one of them, and a key that is a list or a map
// has no name to report; here each key is seen with its place. Bounding the nesting here (yaml-cpp
// recurses once per level) also counts real collections only, not brackets inside quoted strings
// or comments. Header-only: yaml-cpp and fmt, which both readers link.
#pragma once

#include <fmt/format.h>
#include <yaml-cpp/eventhandler.h>
#include <yaml-cpp/yaml.h>

#include <cstddef>
#include <functional>
#include <map>
#include <string>
#include <utility>
#include <vector>

namespace wlx {

class YamlKeyCheck : public YAML::EventHandler {
 public:
  static constexpr std::size_t kMaxNesting = 64;

  // `fail` reports a problem at a place and a path ("frames[3].chain") and must not return (it throws).
  using Fail = std::function<void(const YAML::Mark& mark, const std::string& path, const std::string& reason)>;
  explicit YamlKeyCheck(Fail fail) : fail_(std::move(fail)) {}

  void OnDocumentStart(const YAML::Mark&) override {}
  void OnDocumentEnd() override {}
  void OnScalar(const YAML::Mark& mark, const std::string&, YAML::anchor_t, const std::string& value) override {
    if (at_key()) key(mark, value);
    else value_done();
  }
  void OnNull(const YAML::Mark& mark, YAML::anchor_t) override {
    if (at_key()) fail_(mark, stack_.back().path, "a key is empty: keys are names");
    value_done();
  }
  void OnAlias(const YAML::Mark& mark, YAML::anchor_t) override {
    if (at_key()) fail_(mark, stack_.back().path, "a key is an alias (*name): keys are names");
    value_done();
  }
  void OnSequenceStart(const YAML::Mark& mark, const std::string&, YAML::anchor_t, YAML::EmitterStyle::value) override {
    open(mark, false);
  }
  void OnMapStart(const YAML::Mark& mark, const std::string&, YAML::anchor_t, YAML::EmitterStyle::value) override {
    open(mark, true);
  }
  void OnSequenceEnd() override { close(); }
  void OnMapEnd() override { close(); }

 private:
  struct Level {
    bool map;
    std::string path;
    std::size_t index = 0;                // a list's next element
    bool expecting_key = true;            // a map's next event is a key
    std::string key;                      // a map's current key
    std::map<std::string, int> key_line;  // a map's keys so far, with their lines
  };

  bool at_key() const { return !stack_.empty() && stack_.back().map && stack_.back().expecting_key; }

  // The path of the value that starts now (the parser's own paths: frames[3].chain).
  std::string child_path() const {
    if (stack_.empty()) return "";
    const Level& top = stack_.back();
    if (!top.map) return fmt::format("{}[{}]", top.path, top.index);
    return top.path.empty() ? top.key : top.path + "." + top.key;
  }

  void key(const YAML::Mark& mark, const std::string& name) {
    Level& top = stack_.back();
    top.key = name;
    const auto [first, added] = top.key_line.emplace(name, mark.line + 1);
    if (!added) fail_(mark, child_path(), fmt::format("given twice (first at line {})", first->second));
    top.expecting_key = false;
  }

  void value_done() {
    if (stack_.empty()) return;
    Level& top = stack_.back();
    if (top.map) top.expecting_key = true;
    else ++top.index;
  }

  void open(const YAML::Mark& mark, bool map) {
    if (at_key())
      fail_(mark, stack_.back().path, fmt::format("a key is a {}: keys are names", map ? "map" : "list"));
    // The place says where; a path 64 levels long would not say more.
    if (stack_.size() >= kMaxNesting)
      fail_(mark, "", fmt::format("lists and maps nest more than {} levels deep (the limit)", kMaxNesting));
    stack_.push_back({map, child_path(), 0, true, {}, {}});
  }

  void close() {
    stack_.pop_back();
    value_done();
  }

  Fail fail_;
  std::vector<Level> stack_;
};

}  // namespace wlx
