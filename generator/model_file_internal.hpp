// Internal to the model file's reader (model_file*.cpp): the names it accepts, a YAML node with
// its place (Item) and a map's fields (Fields), and the Parser that turns a model file into a
// Model. Its members are defined by job: repetition, names and expressions in
// model_file_references.cpp, the sections in model_file_machine.cpp, model_file_closure.cpp and
// model_file_operation.cpp, a URDF written into the file in model_file_urdf.cpp, the whole file in
// model_file.cpp.
#pragma once

#include "model_file.hpp"

#include <fmt/format.h>
#include <ginac/ginac.h>
#include <yaml-cpp/yaml.h>
#include <wlx/support/text.hpp>

#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

namespace wlx::codegen {
struct UrdfRobot;  // urdf_import.hpp
}

namespace wlx::codegen::model_file_detail {

// ---- names (model_file_names.cpp) -------------------------------------------------------------

// " (did you mean 'x'?)" when one candidate is close, else "".
std::string suggestion(const std::string& name, const std::vector<std::string>& candidates);

inline std::string excerpt(const std::string& s) { return text::excerpt(s); }

bool is_identifier(const std::string& s);

// Why a name cannot appear in the generated C++ at all (any kind: model, frame, body, limb,
// wheel, closure row, parameter, coordinate, and each part of --namespace), or "".
std::string code_name_reason(const std::string& n);

// Names the emitted C++ cannot use for a parameter or coordinate: keywords, and the names the
// generated functions give their own arguments and locals.
std::string reserved_reason(const std::string& n);

// ---- places, items and fields (model_file_fields.cpp) -----------------------------------------

using Env = std::map<std::string, std::string>;

struct Source {
  std::string name;

  [[noreturn]] void fail(const YAML::Mark& mark, const std::string& path, const std::string& reason) const;
};

// A YAML node with its place and the repetition variables in force.
class Item {
 public:
  Item(const Source& src, YAML::Node node, std::string path, Env env, YAML::Mark fallback = YAML::Mark::null_mark())
      : src_(&src), node_(std::move(node)), path_(std::move(path)), env_(std::move(env)), fallback_(fallback) {}

  const YAML::Node& node() const { return node_; }
  const std::string& path() const { return path_; }
  const Env& env() const { return env_; }
  const Source& source() const { return *src_; }
  YAML::Mark mark() const { return node_.IsDefined() && !node_.Mark().is_null() ? node_.Mark() : fallback_; }
  [[noreturn]] void fail(const std::string& reason) const { src_->fail(mark(), path_, reason); }

  bool defined() const { return node_.IsDefined() && !node_.IsNull(); }
  bool is_map() const { return node_.IsMap(); }
  bool is_sequence() const { return node_.IsSequence(); }
  bool has(const std::string& key) const { return node_.IsMap() && node_[key].IsDefined(); }
  std::size_t size() const { return node_.size(); }

  Item child(const std::string& key) const {
    return Item(*src_, node_[key], path_.empty() ? key : path_ + "." + key, env_, mark());
  }
  Item element(std::size_t k) const { return Item(*src_, node_[k], fmt::format("{}[{}]", path_, k), env_, mark()); }
  Item with(Env env, const std::string& suffix) const { return Item(*src_, node_, path_ + suffix, std::move(env), fallback_); }

  // The scalar, with repetition variables <name> substituted.
  std::string text() const;
  std::string name() const;
  // A number; with `constant`, also an expression of numbers (such as <sign>*0.5).
  double number(bool constant = false) const;
  std::vector<Item> list() const;
  // A branch of a closed form: a whole number from 0 to 1023.
  int branch() const;

 private:
  const Source* src_;
  YAML::Node node_;
  std::string path_;
  Env env_;
  YAML::Mark fallback_;
};

// The fields of a map: reports unknown keys (with the nearest known one) and missing ones.
class Fields {
 public:
  Fields(const Item& item, std::vector<std::string> allowed);
  Item operator[](const std::string& key) const {
    if (!item_.has(key)) item_.fail(fmt::format("missing field '{}'", key));
    return item_.child(key);
  }
  std::optional<Item> optional(const std::string& key) const {
    if (!item_.has(key)) return std::nullopt;
    return item_.child(key);
  }

 private:
  const Item& item_;
  std::vector<std::string> allowed_;
};

Axis axis_of(const Item& it);

// FNV-1a, 64 bits: a stable fingerprint of the model file for the generated banners.
std::uint64_t fingerprint(const std::string& text);

// ---- what a URDF gives the sections (model_file_urdf.cpp) -------------------------------------

struct UrdfAxle {
  Axis axis;
  std::string place, joint;
};
struct UrdfLimit {
  std::optional<double> lower, upper, effort, velocity;
  std::string place;  // file:line of the <limit>
};
struct UrdfWheelShape {
  std::string radius, offset;  // the parameters with_urdf made from the hub's collision shape
};
struct UrdfFileFacts;  // what the file says about the URDF's joints

// ---- the parser -------------------------------------------------------------------------------

class Parser {
 public:
  Parser(std::string source, std::string directory = {}, std::string urdf_path = {})
      : src_{std::move(source)}, directory_(std::move(directory)), urdf_override_(std::move(urdf_path)) {}

  Model parse(const YAML::Node& file_root);  // model_file.cpp

  // The model file as it would be written by hand: a file with `urdf:` gets the URDF's parameters
  // (masses, inertias), dependent joints, frames and bodies spliced into its own sections; a file
  // without is returned as it is. The file's own nodes keep their places for messages.
  YAML::Node with_urdf(const YAML::Node& root);  // model_file_urdf.cpp

  const std::string& urdf_fingerprint() const { return urdf_fingerprint_; }
  // The URDF's path as opened (empty without one).
  const std::string& urdf_file() const { return urdf_file_; }

 private:
  // ---- a URDF written into the file (model_file_urdf.cpp) ----
  UrdfRobot open_urdf(const Item& where, const std::optional<Item>& urdf_item, const std::string& shown);
  UrdfFileFacts urdf_file_facts(const Fields& f);

  // ---- repetition, names and expressions (model_file_references.cpp) ----
  void repeats(const Item& r);
  // Calls fn for every entry of a list, writing out entries with `for:` once per row (nested
  // repetitions multiply; `items:` repeats a block of entries).
  void each(const Item& list, const std::function<void(const Item&)>& fn);
  void claim_symbol_name(const Item& it, const std::string& n);
  int coordinate_index(const Item& it, bool inputs_only = false, bool dependents_only = false) const;
  const Parameter& parameter(const Item& it, std::optional<ParameterKind> kind = std::nullopt) const;
  int frame_index(const Item& it) const;
  // An expression of parameters (and, where allowed, coordinates), parsed by GiNaC's parser
  // against a strict table. Identifiers are checked first so that a typo gets a suggestion.
  ex expression(const Item& it, bool allow_coordinates) const;
  void check_at_defaults(const Item& it, const std::string& s, const ex& e) const;
  Vec3 vector3(const Item& it) const;

  // ---- the machine: parameters, coordinates, frames, bodies, wheels (model_file_machine.cpp) ----
  void parameters(const Item& list);
  void coordinate(const Item& it);
  void coordinates(const Item& c);
  void frames(const Item& list);
  void bodies(const Item& list);
  void wheels(const Item& list);

  // ---- the closure, its limbs, the wheels' rates (model_file_closure.cpp) ----
  void closure(const Item& list);
  std::set<int> row_dependents(const ClosureCondition& c) const;
  void limbs(const std::optional<Item>& list, const Item& top);
  void nonholonomic(const std::optional<Item>& section, const Item& top);

  // ---- dynamics, clearance, contacts, limits, nominal state, sweeps (model_file_operation.cpp) ----
  void dynamics(const Item& section);
  void clearance(const Item& section);
  void contacts(const Item& section);
  void limits(const std::optional<Item>& section);
  void nominal(const std::optional<Item>& section);
  void sweeps(const std::optional<Item>& section);

  Source src_;
  std::string directory_, urdf_override_, urdf_fingerprint_, urdf_file_;
  std::map<std::string, UrdfAxle> urdf_axle_;  // a wheel's hub link -> its URDF joint's axis
  std::map<std::string, UrdfLimit> urdf_limits_;  // a URDF joint's name -> its <limit>
  std::map<std::string, UrdfWheelShape> urdf_wheel_shape_;  // a hub link -> its wheel's radius and offset
  Model m_;
  GiNaC::symtab params_, coordinates_;
  GiNaC::exmap param_defaults_;  // each parameter's symbol -> its default, for check_at_defaults
  std::map<std::string, std::string> symbol_kind_;
  std::map<std::string, std::vector<Env>> repeat_;
  std::size_t expanded_entries_ = 0;
  std::vector<std::pair<int, std::string>> joint_users_;
  std::map<int, double> limb_start_;  // the limbs' `start` values, by coordinate
  std::optional<Item> rows_item_;
};

}  // namespace wlx::codegen::model_file_detail
