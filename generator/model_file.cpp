#include "model_file.hpp"

#include "expr_graph.hpp"
#include "urdf_import.hpp"

#include <Eigen/Eigenvalues>
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <ginac/ginac.h>
#include <yaml-cpp/depthguard.h>
#include <yaml-cpp/eventhandler.h>
#include <yaml-cpp/yaml.h>
#include <wlx/bounded_file.hpp>
#include <wlx/yaml_key_check.hpp>
#include <wlx/text.hpp>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <numbers>
#include <set>
#include <sstream>

namespace wlx::codegen {

namespace {

// ---- messages ---------------------------------------------------------------------------------

// " (did you mean 'x'?)" when one candidate is close, else "".
std::string suggestion(const std::string& name, const std::vector<std::string>& candidates) {
  const std::string best = text::nearest(name, candidates, false);
  return best.empty() ? "" : fmt::format(" (did you mean '{}'?)", best);
}

std::string excerpt(const std::string& s) { return text::excerpt(s); }

bool is_identifier(const std::string& s) {
  if (s.empty() || !(std::isalpha(static_cast<unsigned char>(s[0])) || s[0] == '_')) return false;
  return std::all_of(s.begin(), s.end(), [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; });
}

// Macros that the compilers (GCC and clang in their GNU modes: unix, linux) and the headers the
// generated code includes (<cmath>, <cstdint>, <cstring>, <limits>, <algorithm>, Eigen, and
// through them glibc's <errno.h>, <stdio.h>, <endian.h>, ...) define with names that do not look
// like macros. A name that is one of them is replaced by the preprocessor before the compiler
// sees it: the header fails to compile far from the cause. Upper-case names are caught by
// looks_like_macro() below.
const std::set<std::string>& lower_case_macros() {
  static const std::set<std::string> names = {
      "unix", "linux", "i386", "i686", "sun", "sparc", "mips", "vax", "errno", "assert", "offsetof", "alloca",
      "setjmp", "va_arg", "va_start", "va_end", "va_copy", "stdin", "stdout", "stderr", "math_errhandling",
      "signbit", "fpclassify", "isfinite", "isinf", "isnan", "isnormal", "issubnormal", "iszero", "issignaling",
      "isgreater", "isgreaterequal", "isless", "islessequal", "islessgreater", "isunordered", "major", "minor",
      "makedev", "htobe16", "htobe32", "htobe64", "htole16", "htole32", "htole64", "be16toh", "be32toh", "be64toh",
      "le16toh", "le32toh", "le64toh", "strdupa", "strndupa", "sched_priority", "eigen_assert", "eigen_internal_assert",
      "eigen_plain_assert", "L_ctermid", "L_cuserid", "L_tmpnam", "P_tmpdir", "pthread_cleanup_push", "pthread_cleanup_pop"};
  return names;
}

// Upper-case names of three characters or more (EOF, NAN, M_PI, INT_MAX, E2BIG, EIGEN_...), and
// the families with a lower-case suffix (M_PIf, M_El, ...): the standard headers define hundreds
// of these, and which ones differs between C libraries, so the rule is by shape, not by list.
bool looks_like_macro(const std::string& n) {
  const bool upper = n.size() >= 3 && std::none_of(n.begin(), n.end(), [](char c) { return std::islower(static_cast<unsigned char>(c)); });
  const bool math_constant = n.size() > 2 && n[0] == 'M' && n[1] == '_' && std::isupper(static_cast<unsigned char>(n[2]));
  return upper || math_constant || n.rfind("EIGEN", 0) == 0 || n.rfind("ei_", 0) == 0 || n.rfind("vec2d_", 0) == 0 ||
         n.rfind("vec4f_", 0) == 0 || n.rfind("vec4i_", 0) == 0;
}

// Why a name cannot appear in the generated C++ at all (any kind: model, frame, body, limb,
// wheel, closure row, parameter, coordinate, and each part of --namespace), or "".
std::string code_name_reason(const std::string& n) {
  static const std::set<std::string> keywords = {
      "alignas", "alignof", "asm", "auto", "bool", "break", "case", "catch", "char", "char8_t", "char16_t", "char32_t",
      "class", "concept", "const", "consteval", "constexpr", "constinit", "const_cast", "continue", "co_await",
      "co_return", "co_yield", "decltype", "default", "delete", "do", "double", "dynamic_cast", "else", "enum",
      "explicit", "export", "extern", "false", "float", "for", "friend", "goto", "if", "import", "inline", "int",
      "long", "module", "mutable", "namespace", "new", "noexcept", "nullptr", "operator", "private", "protected",
      "public", "register", "reinterpret_cast", "requires", "return", "short", "signed", "sizeof", "static",
      "static_assert", "static_cast", "struct", "switch", "template", "this", "thread_local", "throw", "true", "try",
      "typedef", "typeid", "typename", "union", "unsigned", "using", "virtual", "void", "volatile", "wchar_t", "while",
      "final", "override", "and", "or", "not", "xor", "bitand", "bitor", "compl", "and_eq", "or_eq", "xor_eq", "not_eq"};
  if (keywords.count(n)) return "it is a C++ keyword";
  if (lower_case_macros().count(n)) return "the compiler or the standard headers the generated code includes define it as a macro";
  if (looks_like_macro(n))
    return "upper-case names (EOF, NAN, M_PI, INT_MAX) are the standard headers' macros: use a lower-case letter in it";
  if (n == "std" || n == "Eigen") return "it is the namespace of the standard library or of Eigen, which the generated code uses";
  if (n[0] == '_' || n.find("__") != std::string::npos) return "C++ reserves names starting with _ or containing __";
  return {};
}

// Names the emitted C++ cannot use for a parameter or coordinate: keywords, and the names the
// generated functions give their own arguments and locals.
std::string reserved_reason(const std::string& n) {
  static const std::set<std::string> keywords = {
      "alignas", "alignof", "and", "and_eq", "asm", "auto", "bitand", "bitor", "bool", "break", "case", "catch",
      "char", "char8_t", "char16_t", "char32_t", "class", "compl", "concept", "const", "consteval", "constexpr",
      "constinit", "const_cast", "continue", "co_await", "co_return", "co_yield", "decltype", "default", "delete",
      "do", "double", "dynamic_cast", "else", "enum", "explicit", "export", "extern", "false", "float", "for",
      "friend", "goto", "if", "inline", "int", "long", "mutable", "namespace", "new", "noexcept", "not", "not_eq",
      "nullptr", "operator", "or", "or_eq", "private", "protected", "public", "register", "reinterpret_cast",
      "requires", "return", "short", "signed", "sizeof", "static", "static_assert", "static_cast", "struct",
      "switch", "template", "this", "thread_local", "throw", "true", "try", "typedef", "typeid", "typename",
      "union", "unsigned", "using", "virtual", "void", "volatile", "wchar_t", "while", "xor", "xor_eq", "NULL",
      "K0"};
  static const std::set<std::string> locals = {
      "s", "sdot", "p", "zero_fill", "angle", "sin_angle", "cos_angle", "std", "Eigen", "positions", "rotations",
      "Phi", "dPhi_ds", "C", "spin", "dPhi_ds_dot_sdot", "C_dot_sdot", "com", "Jv", "Jw", "Jv_dot_sdot",
      "Jw_dot_sdot", "T", "sddot", "Qstar", "tau", "out", "Params", "Coordinates", "Pi", "pi", "sin", "cos", "tan", "asin", "acos", "atan", "sqrt",
      "exp", "log", "abs",
      // The generated functions' template parameter, outputs and lane types (a parameter or
      // coordinate of that name compiled into a header that does not compile).
      "Scalar", "M", "b_velocity", "B_bias", "Q_gravity", "L", "LW", "detail", "gen", "wlx", "trig_detail", "NonDeduced"};
  if (keywords.count(n)) return "it is a C++ keyword";
  if (locals.count(n)) return "the generated functions use that name themselves";
  if (n.size() > 1 && n[0] == 't' && std::all_of(n.begin() + 1, n.end(), [](char c) { return std::isdigit(static_cast<unsigned char>(c)); }))
    return "t<number> names the generated code's intermediate terms";
  if (n.rfind("sin_", 0) == 0 || n.rfind("cos_", 0) == 0) return "sin_<angle> and cos_<angle> name the generated code's sines and cosines";
  if (n.rfind("kane_", 0) == 0 || n.rfind("ik_", 0) == 0)
    return "kane_<...> and ik_<...> name the generated code's dynamics sums and inverse kinematics terms";
  if (n.size() > 4 && n.compare(n.size() - 4, 4, "_dot") == 0) return "<coordinate>_dot names the generated code's rates";
  if (n[0] == '_' || n.find("__") != std::string::npos) return "C++ reserves names starting with _ or containing __";
  return {};
}

// ---- places, items and fields -----------------------------------------------------------------

using Env = std::map<std::string, std::string>;

struct Source {
  std::string name;

  [[noreturn]] void fail(const YAML::Mark& mark, const std::string& path, const std::string& reason) const {
    const std::string field = path.empty() ? "" : path + ": ";
    // The file's name as one line: a name with a line break must not forge a message line.
    std::string shown;
    for (const char c : name) shown += static_cast<unsigned char>(c) < 0x20 || c == 0x7f ? fmt::format("\\x{:02x}", static_cast<unsigned char>(c)) : std::string(1, c);
    if (mark.is_null()) throw ModelFileError(fmt::format("{}: {}{}", shown, field, reason));
    throw ModelFileError(fmt::format("{}:{}:{}: {}{}", shown, mark.line + 1, mark.column + 1, field, reason));
  }
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
  std::string text() const {
    if (!node_.IsDefined() || node_.IsNull()) fail("missing: give a value");
    if (!node_.IsScalar()) fail("must be a single value, not a list or map");
    const std::string& s = node_.Scalar();
    std::string out;
    for (std::size_t i = 0; i < s.size();) {
      const std::size_t close = s[i] == '<' ? s.find('>', i) : std::string::npos;
      if (close != std::string::npos && is_identifier(s.substr(i + 1, close - i - 1))) {
        const std::string var = s.substr(i + 1, close - i - 1);
        const auto it = env_.find(var);
        if (it == env_.end()) {
          std::vector<std::string> names;
          for (const auto& kv : env_) names.push_back(kv.first);
          fail(fmt::format("'<{}>' is not a repetition variable here{}{}", var, suggestion(var, names),
                           env_.empty() ? " (the entry has no `for`)" : ""));
        }
        out += it->second;
        i = close + 1;
      } else {
        out += s[i++];
      }
    }
    // Text reaches generated comments and string literals (quoted there, emit.cpp): one line of
    // printable UTF-8, checked after the repetition variables are put in (their values are text
    // of the file too). A backslash would continue a // comment onto the next generated line.
    if (std::string why = text::check_one_line(out); !why.empty() || out.find('\\') != std::string::npos)
      fail(fmt::format("'{}' {}; text here is one plain line", excerpt(out), why.empty() ? "has a backslash" : why));
    return out;
  }
  std::string name() const {
    const std::string s = text();
    if (!is_identifier(s))
      fail(fmt::format("'{}' is not a name: use letters, digits and _, not starting with a digit", excerpt(s)));
    // Every name of the file reaches the generated code (as an identifier, a namespace or a
    // string): none may be a keyword, a macro or std/Eigen. K0, the ground, is the one name
    // the file may refer to without defining it.
    if (const std::string why = code_name_reason(s); !why.empty() && s != "K0")
      fail(fmt::format("'{}' cannot be used as a name: {}", s, why));
    return s;
  }
  // A number; with `constant`, also an expression of numbers (such as <sign>*0.5).
  double number(bool constant = false) const {
    const std::string s = text();
    double v = 0;
    const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
    if ((ec != std::errc() || end != s.data() + s.size()) && constant && s.size() < 64 &&
        s.find_first_of("^abcdefghijklmnopqrstuvwxyzABCDFGHIJKLMNOPQRSTUVWXYZ_") == std::string::npos) {
      try {
        GiNaC::parser reader(GiNaC::symtab{}, true);
        const ex e = GiNaC::evalf(reader(s));
        if (GiNaC::is_a<GiNaC::numeric>(e) && GiNaC::ex_to<GiNaC::numeric>(e).is_real()) {
          v = GiNaC::ex_to<GiNaC::numeric>(e).to_double();
          if (!std::isfinite(v)) fail(fmt::format("must be a finite number, got {}", excerpt(s)));
          return v;
        }
      } catch (const std::exception&) {
      }
      fail(fmt::format("'{}' is not a number", excerpt(s)));
    }
    if (ec != std::errc() || end != s.data() + s.size()) fail(fmt::format("'{}' is not a number", excerpt(s)));
    if (!std::isfinite(v)) fail(fmt::format("must be a finite number, got {}", excerpt(s)));
    return v;
  }
  std::vector<Item> list() const {
    if (!node_.IsSequence()) fail("must be a list [a, b, ...]");
    std::vector<Item> out;
    for (std::size_t k = 0; k < node_.size(); ++k) out.push_back(element(k));
    return out;
  }

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
  Fields(const Item& item, std::vector<std::string> allowed) : item_(item), allowed_(std::move(allowed)) {
    if (!item.is_map()) item.fail("must be a map of fields (key: value)");
    for (const auto& kv : item.node()) {
      const std::string key = kv.first.Scalar();
      if (key == "for") continue;  // the repetition, already expanded
      if (std::find(allowed_.begin(), allowed_.end(), key) == allowed_.end())
        item.source().fail(kv.first.Mark(), item.path(),
                           fmt::format("unknown field '{}'{}; the fields here are: {}", excerpt(key),
                                       suggestion(key, allowed_), fmt::join(allowed_, ", ")));
    }
  }
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

Axis axis_of(const Item& it) {
  const std::string a = it.text();
  if (a == "x") return Axis::X;
  if (a == "y") return Axis::Y;
  if (a == "z") return Axis::Z;
  it.fail(fmt::format("'{}' is not an axis: use x, y or z", excerpt(a)));
}

// FNV-1a, 64 bits: a stable fingerprint of the model file for the generated banners.
std::uint64_t fingerprint(const std::string& text) {
  std::uint64_t h = 1469598103934665603ull;
  for (unsigned char c : text) h = (h ^ c) * 1099511628211ull;
  return h;
}

// ---- the parser -------------------------------------------------------------------------------

class Parser {
 public:
  Parser(std::string source, std::string directory = {}, std::string urdf_path = {})
      : src_{std::move(source)}, directory_(std::move(directory)), urdf_override_(std::move(urdf_path)) {}

  Model parse(const YAML::Node& file_root) {
    const YAML::Node root = with_urdf(file_root);
    const Item top(src_, root, "", {});
    const Fields f(top, {"model", "description", "repeat", "parameters", "coordinates", "frames", "bodies", "closure",
                         "limbs", "wheels", "nonholonomic", "dynamics", "clearance", "contacts", "nominal", "ik_sweeps",
                         "limits"});
    m_.name = f["model"].name();
    if (const std::string why = model_name_problem(m_.name); !why.empty())
      f["model"].fail(fmt::format("'{}' cannot be the model's name: {}", m_.name, why));
    m_.source = src_.name;
    if (auto d = f.optional("description")) m_.description = d->text();
    if (auto r = f.optional("repeat"); r && repeat_.empty()) repeats(*r);
    parameters(f["parameters"]);
    coordinates(f["coordinates"]);
    frames(f["frames"]);
    if (auto b = f.optional("bodies")) bodies(*b);
    // Wheels before the closure: a wheel on a hub adds its contact frame, which closure rows place.
    if (auto w = f.optional("wheels")) wheels(*w);
    if (auto c = f.optional("closure")) closure(*c);
    limbs(f.optional("limbs"), top);
    nonholonomic(f.optional("nonholonomic"), top);
    limits(f.optional("limits"));
    if (auto d = f.optional("dynamics")) dynamics(*d);
    if (auto c = f.optional("clearance")) clearance(*c);
    if (auto c = f.optional("contacts")) contacts(*c);
    nominal(f.optional("nominal"));
    sweeps(f.optional("ik_sweeps"));
    return std::move(m_);
  }

 public:
  // The model file as it would be written by hand: a file with `urdf:` gets the URDF's parameters
  // (masses, inertias), dependent joints, frames and bodies spliced into its own sections; a file
  // without is returned as it is. The file's own nodes keep their places for messages.
  YAML::Node with_urdf(const YAML::Node& root) {
    if (!(root.IsMap() && (root["urdf"].IsDefined() || !urdf_override_.empty()))) {
      if (root.IsMap())
        for (const char* key : {"rename", "base"})
          if (root[key].IsDefined())
            Item(src_, root[key], key, {}).fail("only a model file that reads a URDF (`urdf: robot.urdf`) has this field");
      return root;
    }
    const Item top(src_, root, "", {});
    const Fields f(top, {"model", "description", "urdf", "rename", "base", "repeat", "parameters", "coordinates", "frames",
                         "bodies", "closure", "limbs", "wheels", "nonholonomic", "dynamics", "clearance", "contacts",
                         "nominal", "ik_sweeps", "limits"});
    if (auto r = f.optional("repeat")) repeats(*r);
    // The inputs are the YAML file's to name (the URDF's moving joints become the dependent ones):
    // missing, they are said to be here, where the file is, not in the document made from it.
    static_cast<void>(Fields(f["coordinates"], {"inputs", "dependent"})["inputs"]);
    const std::optional<Item> urdf_item = f.optional("urdf");
    const Item& where = urdf_item ? *urdf_item : top;
    std::string path = urdf_override_;
    if (path.empty()) {
      path = urdf_item->text();
      if (!directory_.empty() && !std::filesystem::path(path).is_absolute()) path = (std::filesystem::path(directory_) / path).string();
    }
    const std::string shown = urdf_override_.empty() ? urdf_item->text() : urdf_override_;
    if (!urdf_import_available())
      where.fail("URDF import is unavailable: this wlx-gen was built without liburdfdom (install Debian's liburdfdom-dev "
                 "and configure again), or write the model by hand (docs/model-format.md)");
    // Bounded before it is read: a regular file (not a device or a pipe) of at most 64 MB.
    std::error_code error;
    if (!std::filesystem::is_regular_file(path, error) || !std::ifstream(path))
      where.fail(fmt::format("cannot open the URDF file '{}'", excerpt(path)));
    if (std::filesystem::file_size(path, error) > (64u << 20)) where.fail(fmt::format("'{}' is larger than 64 MB", excerpt(path)));
    UrdfRobot robot = read_urdf(path, shown);
    urdf_file_ = path;
    {
      std::ifstream in(path, std::ios::binary);
      std::ostringstream text;
      text << in.rdbuf();
      urdf_fingerprint_ = fmt::format("{}, fingerprint {:016x}", shown, fingerprint(text.str()));
    }
    const auto urdf_fail = [&](int line, const std::string& element, const std::string& reason) {
      throw ModelFileError(fmt::format("{}:{}: {}: {}", shown, line, element, reason));
    };

    // Renames first: every later check and every generated name sees the new names.
    if (auto rename = f.optional("rename")) {
      if (!rename->is_map()) rename->fail("must map URDF link or joint names to new names {old: new}");
      std::vector<std::string> names;
      for (const auto& l : robot.links) names.push_back(l.name);
      for (const auto& j : robot.joints) names.push_back(j.name);
      for (const auto& kv : rename->node()) {
        const std::string from = kv.first.Scalar();
        const Item to_item = rename->child(from);
        const std::string to = to_item.name();
        if (std::find(names.begin(), names.end(), from) == names.end())
          Item(src_, kv.first, rename->path(), {}).fail(fmt::format("the URDF has no link or joint '{}'{}", excerpt(from), suggestion(from, names)));
        for (auto& l : robot.links)
          if (l.name == from) l.name = to;
        for (auto& j : robot.joints) {
          if (j.name == from) j.name = to;
          if (j.parent == from) j.parent = to;
          if (j.child == from) j.child = to;
        }
      }
    }
    // `suffix` makes a name that is already an identifier (but taken or reserved) a new one.
    const auto rename_hint = [&](const std::string& n, const std::string& suffix) {
      std::string fixed;
      for (char c : n) fixed += std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
      if (fixed.empty() || std::isdigit(static_cast<unsigned char>(fixed[0])) || fixed[0] == '_') fixed = "n" + fixed;
      while (fixed.find("__") != std::string::npos) fixed.replace(fixed.find("__"), 2, "_");
      if (fixed == n) fixed += suffix;
      return fmt::format("rename it in the URDF, or in {}: `rename: {{\"{}\": {}}}`", src_.name, excerpt(n), fixed);
    };

    // What the file says about the URDF's joints, read before the sections are built: the names of
    // its parameters and inputs (an input that names a URDF joint makes that joint an input), and
    // the hubs of its wheels (a wheel's continuous joint is its spin, not a coordinate).
    std::set<std::string> file_parameters, file_inputs;
    std::map<std::string, Item> hubs;
    std::set<std::string> hubs_with_radius;  // the wheels that give their radius themselves
    if (auto list = f.optional("parameters"))
      each(*list, [&](const Item& it) { if (it.has("name")) file_parameters.insert(it.child("name").text()); });
    if (auto c = f.optional("coordinates")) {
      const Fields cf(*c, {"inputs", "dependent"});
      if (auto d = cf.optional("dependent"))
        d->fail("with a URDF the dependent joints are the URDF's moving joints (those not listed as inputs): leave "
                "`dependent` out");
      each(cf["inputs"], [&](const Item& it) { if (it.has("name")) file_inputs.insert(it.child("name").text()); });
    }
    if (auto w = f.optional("wheels"))
      each(*w, [&](const Item& it) {
        if (!it.has("hub")) return;
        hubs.emplace(it.child("hub").text(), it.child("hub"));
        if (it.has("radius")) hubs_with_radius.insert(it.child("hub").text());
      });

    // The shortest decimal within two units in the last place: an angle that went through
    // urdfdom's quaternion (0.2 comes back as 0.20000000000000004) or a diagonalised moment reads
    // as it was written; exact values are kept exactly.
    const auto number = [](double x) {
      if (x == 0) return std::string("0");
      for (int digits = 1; digits < 17; ++digits) {
        const double y = std::stod(fmt::format("{:.{}g}", x, digits));
        if (std::abs(y - x) <= 4.5e-16 * std::abs(x)) return fmt::format("{}", y);
      }
      return fmt::format("{}", x);
    };
    const auto step = [](const char* op, const std::string& arg) {
      YAML::Node n(YAML::NodeType::Map);
      n[op] = arg;
      return n;
    };
    const auto flow = [](YAML::Node n) {
      n.SetStyle(YAML::EmitterStyle::Flow);
      return n;
    };
    const char* letters[] = {"x", "y", "z"};
    // The principal axis a unit vector lies along (-1 if none), and its sign.
    const auto principal = [](const std::array<double, 3>& a, int& sign) {
      for (int i = 0; i < 3; ++i)
        if (std::abs(std::abs(a[i]) - 1) < 1e-12 && std::abs(a[(i + 1) % 3]) < 1e-12 && std::abs(a[(i + 2) % 3]) < 1e-12) {
          sign = a[i] > 0 ? 1 : -1;
          return i;
        }
      return -1;
    };
    // Fixed turns rz, ry, rx (URDF's rpy: roll about x, pitch about y, yaw about z, fixed axes)
    // for a rotation matrix; angles below 1e-12 rad are the rounding of a quaternion, left out.
    // Fixed turns rz, ry, rx (URDF's rpy: roll about x, pitch about y, yaw about z, fixed axes)
    // for a rotation matrix; angles below 1e-12 rad are the rounding of a quaternion, left out.
    // `argument` writes the angle (a number, or the name of a parameter it makes).
    const auto turns = [&](YAML::Node& chain, const Matrix3Rows& R, const std::function<std::string(const char*, double)>& argument) {
      double yaw, pitch, roll;
      const double s = std::clamp(-R[6], -1.0, 1.0);
      pitch = std::asin(s);
      if (std::abs(s) < 1 - 1e-12) {
        yaw = std::atan2(R[3], R[0]);
        roll = std::atan2(R[7], R[8]);
      } else {
        yaw = 0;
        roll = std::atan2(-R[5], R[4]);
      }
      for (const auto& [op, which, angle] : {std::tuple{"rz", "yaw", yaw}, std::tuple{"ry", "pitch", pitch}, std::tuple{"rx", "roll", roll}})
        if (std::abs(angle) > 1e-12) chain.push_back(flow(step(op, argument(which, angle))));
    };

    std::map<std::string, int> link_of;  // name -> index
    for (std::size_t k = 0; k < robot.links.size(); ++k) link_of[robot.links[k].name] = static_cast<int>(k);
    // Wheels: their hubs are the child links of continuous joints.
    std::set<int> wheel_joints;
    for (const auto& [hub, item] : hubs) {
      const auto l = link_of.find(hub);
      if (l == link_of.end()) continue;  // a frame of the file's own: checked with the wheels
      const int j = robot.links[static_cast<std::size_t>(l->second)].parent_joint;
      if (j < 0 || robot.joints[static_cast<std::size_t>(j)].type != UrdfJoint::Type::Continuous)
        item.fail(fmt::format("URDF link '{}' {}: a wheel's hub is the child link of the wheel's continuous joint", hub,
                              j < 0 ? "is the root link" : fmt::format("hangs on joint '{}', which is not continuous", robot.joints[static_cast<std::size_t>(j)].name)));
      const UrdfJoint& joint = robot.joints[static_cast<std::size_t>(j)];
      int sign = 1;
      const int axis = principal(joint.axis, sign);
      if (axis < 0)
        urdf_fail(joint.line, fmt::format("joint '{}' axis", joint.name),
                  "a wheel turns about an axis of its joint frame (x, y or z, either sign): turn the joint's origin (rpy) so "
                  "that the axle lies along one");
      wheel_joints.insert(j);
      urdf_axle_[hub] = {static_cast<Axis>(axis), fmt::format("{}:{}", shown, joint.line), joint.name};
    }

    // Names: C++ identifiers; joints (coordinates) share a namespace with the parameters.
    std::set<std::string> generated_parameters;
    for (const auto& l : robot.links) {
      if (!is_identifier(l.name) || l.name == "K0")
        urdf_fail(l.line, fmt::format("link '{}'", excerpt(l.name)),
                  fmt::format("'{}' cannot name a frame (a C++ identifier, not K0): {}", excerpt(l.name), rename_hint(l.name, "_link")));
    }
    for (std::size_t k = 0; k < robot.joints.size(); ++k) {
      const UrdfJoint& j = robot.joints[k];
      if (j.type == UrdfJoint::Type::Fixed || wheel_joints.count(static_cast<int>(k))) continue;
      const std::string element = fmt::format("joint '{}'", excerpt(j.name));
      if (!is_identifier(j.name))
        urdf_fail(j.line, element, fmt::format("'{}' cannot name a coordinate (a C++ identifier): {}", excerpt(j.name), rename_hint(j.name, "_joint")));
      if (const std::string why = reserved_reason(j.name); !why.empty())
        urdf_fail(j.line, element, fmt::format("'{}' cannot name a coordinate: {}; {}", j.name, why, rename_hint(j.name, "_joint")));
      if (file_parameters.count(j.name))
        urdf_fail(j.line, element, fmt::format("'{}' is also the name of a parameter in {}: {}", j.name, src_.name, rename_hint(j.name, "_joint")));
    }

    // The joints' <limit>s, by their (renamed) names: the `limits` section reads them, and the file's
    // own entries take precedence (limits() below); a wheel's continuous joint gives its drive's effort.
    for (const UrdfJoint& j : robot.joints)
      if (j.type != UrdfJoint::Type::Fixed && (j.lower || j.effort || j.velocity))
        urdf_limits_[j.name] = {j.lower, j.upper, j.effort, j.velocity, fmt::format("{}:{}", shown, j.limit_line)};

    // Rigid groups: a link and the links fixed to it (fixed joints collapse). Each moving joint's
    // child (and the root) starts a group; its body carries the group's mass.
    const std::size_t n = robot.links.size();
    std::vector<int> group(n, -1);
    std::vector<RigidPose> in_group(n);  // the link's pose in its group's root frame
    for (std::size_t k = 0; k < n; ++k) {
      const int pj = robot.links[k].parent_joint;
      if (pj < 0 || robot.joints[static_cast<std::size_t>(pj)].type != UrdfJoint::Type::Fixed) {
        group[k] = static_cast<int>(k);
        continue;
      }
      const UrdfJoint& j = robot.joints[static_cast<std::size_t>(pj)];
      const int parent = link_of.at(j.parent);  // earlier in the depth-first order
      group[k] = group[static_cast<std::size_t>(parent)];
      const RigidPose& p = in_group[static_cast<std::size_t>(parent)];
      RigidPose& q = in_group[k];
      for (int r = 0; r < 3; ++r) {
        q.translation[r] = p.translation[r];
        for (int c = 0; c < 3; ++c) {
          q.translation[r] += p.rotation[3 * r + c] * j.origin.translation[c];
          double sum = 0;
          for (int a = 0; a < 3; ++a) sum += p.rotation[3 * r + a] * j.origin.rotation[3 * a + c];
          q.rotation[3 * r + c] = sum;
        }
      }
    }

    YAML::Node parameters(YAML::NodeType::Sequence), dependent(YAML::NodeType::Sequence), frames(YAML::NodeType::Sequence),
        bodies(YAML::NodeType::Sequence);
    if (auto list = f.optional("parameters"))
      for (const auto& e : list->node()) parameters.push_back(e);
    if (auto list = f.optional("frames"))
      for (const auto& e : list->node()) frames.push_back(e);
    if (auto list = f.optional("bodies"))
      for (const auto& e : list->node()) bodies.push_back(e);
    // `owner` is the link or joint whose number it is ("link", "base"), for the message.
    const auto add_parameter = [&](int line, const char* kind_of_owner, const std::string& owner, const std::string& name, double value,
                                   const char* kind, const char* unit, const std::string& meaning) {
      if (file_parameters.count(name) || file_inputs.count(name) || generated_parameters.count(name) || robot.joint_index(name) >= 0)
        urdf_fail(line, fmt::format("{} '{}'", kind_of_owner, owner),
                  fmt::format("its parameter '{}' is already a name in the model: {}", name, rename_hint(owner, std::string("_") + kind_of_owner)));
      if (const std::string why = reserved_reason(name); !why.empty())
        urdf_fail(line, fmt::format("{} '{}'", kind_of_owner, owner),
                  fmt::format("its parameter '{}' cannot be used as a name: {}; {}", name, why, rename_hint(owner, std::string("_") + kind_of_owner)));
      generated_parameters.insert(name);
      YAML::Node p(YAML::NodeType::Map);
      p["name"] = name;
      p["value"] = number(value);
      p["unit"] = unit;
      p["kind"] = kind;
      p["meaning"] = meaning;
      parameters.push_back(flow(p));
    };

    for (std::size_t k = 0; k < n; ++k) {
      const UrdfLink& l = robot.links[k];
      YAML::Node frame(YAML::NodeType::Map);
      frame["name"] = l.name;
      YAML::Node chain(YAML::NodeType::Sequence);
      if (l.parent_joint < 0) {
        frame["meaning"] = fmt::format("URDF root link {}", l.name);
        frame["parent"] = "K0";
        if (auto base = f.optional("base")) {
          const Fields bf(*base, {"chain"});
          chain = bf["chain"].node();  // the file's own steps, with their places
        }
      } else {
        const UrdfJoint& j = robot.joints[static_cast<std::size_t>(l.parent_joint)];
        const bool wheel = wheel_joints.count(l.parent_joint) != 0;
        const bool moving = j.type != UrdfJoint::Type::Fixed && !wheel;
        frame["meaning"] = fmt::format("URDF link {} ({} joint {})", l.name,
                                       wheel ? "wheel hub, not spinning, of" : moving ? "after" : "fixed by", j.name);
        frame["parent"] = j.parent;
        // The origin's numbers become parameters (kinds offset and angle), as a hand-written
        // model names its geometry: symbols keep GiNaC from distributing numbers over sums (about
        // 13% fewer operations), and the geometry stays adjustable at run time, or --bake-defaults.
        const auto& t = j.origin.translation;
        if (t[0] != 0 || t[1] != 0 || t[2] != 0) {
          YAML::Node v(YAML::NodeType::Sequence);
          for (int a = 0; a < 3; ++a) {
            if (t[a] == 0) {
              v.push_back("0");
              continue;
            }
            const std::string p = fmt::format("{}_{}", j.name, letters[a]);
            add_parameter(j.line, "joint", j.name, p, t[a], "offset", "m",
                          fmt::format("origin of joint {}: {} in link {}", j.name, letters[a], j.parent));
            v.push_back(p);
          }
          YAML::Node s(YAML::NodeType::Map);
          s["translate"] = flow(v);
          chain.push_back(flow(s));
        }
        turns(chain, j.origin.rotation, [&](const char* which, double angle) {
          const std::string p = fmt::format("{}_{}", j.name, which);
          add_parameter(j.line, "joint", j.name, p, angle, "angle", "rad", fmt::format("origin of joint {}: rpy {}", j.name, which));
          return p;
        });
        if (moving) {
          const char* kind = j.type == UrdfJoint::Type::Prismatic ? "t" : "r";
          int sign = 1;
          const int axis = principal(j.axis, sign);
          const std::string q = (sign < 0 ? "-" : "") + j.name;
          if (axis >= 0) {
            chain.push_back(flow(step(fmt::format("{}{}", kind, letters[axis]).c_str(), q)));
          } else {
            // An oblique axis: turn z onto it, move about (along) z, turn back, so that the
            // child link keeps URDF's axes.
            const double theta = std::acos(std::clamp(j.axis[2], -1.0, 1.0));
            const double phi = std::atan2(j.axis[1], j.axis[0]);
            if (std::abs(phi) > 1e-12) chain.push_back(flow(step("rz", number(phi))));
            chain.push_back(flow(step("ry", number(theta))));
            chain.push_back(flow(step(fmt::format("{}z", kind).c_str(), j.name)));
            chain.push_back(flow(step("ry", number(-theta))));
            if (std::abs(phi) > 1e-12) chain.push_back(flow(step("rz", number(-phi))));
          }
          if (!file_inputs.count(j.name)) {
            YAML::Node c(YAML::NodeType::Map);
            c["name"] = j.name;
            c["unit"] = j.type == UrdfJoint::Type::Prismatic ? "m" : "rad";
            c["meaning"] = fmt::format("URDF {} joint {}", j.type == UrdfJoint::Type::Prismatic ? "prismatic" : "revolute", j.name);
            dependent.push_back(flow(c));
          }
        }
      }
      frame["chain"] = flow(chain);
      frames.push_back(frame);
    }

    // A wheel without `radius` rolls on its hub link's collision cylinder (about the axle) or sphere:
    // parameters <hub>_radius and <hub>_offset (the centre's place along the axle, which moves the
    // rolling plane), which the wheel then takes (wheels() below).
    for (const auto& [hub, item] : hubs) {
      const auto l = link_of.find(hub);
      if (l == link_of.end() || hubs_with_radius.count(hub)) continue;
      const UrdfLink& link = robot.links[static_cast<std::size_t>(l->second)];
      const UrdfAxle& axle = urdf_axle_.at(hub);
      if (!link.round_shape)
        item.fail(fmt::format("the wheel on '{}' has no `radius`, and the URDF's link '{}' has no collision cylinder or sphere to "
                              "read one from (a mesh has none): give `radius: PARAMETER`",
                              hub, hub));
      const UrdfRoundShape& shape = *link.round_shape;
      const auto a = static_cast<std::size_t>(axle.axis);
      if (shape.cylinder && !(std::abs(shape.axis[a]) >= 1 - 1e-9))
        urdf_fail(shape.line, fmt::format("link '{}' collision", hub),
                  fmt::format("the cylinder's axis ({:.6g}, {:.6g}, {:.6g}) is not the wheel's axle ({} of the link): it gives no "
                              "rolling radius; turn its <origin rpy>, or give the wheel a `radius`",
                              shape.axis[0], shape.axis[1], shape.axis[2], "xyz"[a]));
      const std::string place = fmt::format("{}:{}", shown, shape.line);
      add_parameter(shape.line, "link", hub, hub + "_radius", shape.radius, "length", "m",
                    fmt::format("rolling radius of the wheel on {} (its collision {}, {})", hub, shape.cylinder ? "cylinder" : "sphere", place));
      add_parameter(shape.line, "link", hub, hub + "_offset", shape.center[a], "offset", "m",
                    fmt::format("the wheel's rolling plane along the axle {} of {} (its collision {}'s centre, {})", "xyz"[a], hub,
                                shape.cylinder ? "cylinder" : "sphere", place));
      urdf_wheel_shape_[hub] = {hub + "_radius", hub + "_offset"};
    }

    // Bodies: each group's mass, centre of mass and inertia (the parallel-axis theorem moves every
    // member's tensor to the group's centre of mass), its principal axes by diagonalisation.
    for (std::size_t g = 0; g < n; ++g) {
      if (group[g] != static_cast<int>(g)) continue;
      double mass = 0;
      Eigen::Vector3d moment = Eigen::Vector3d::Zero();
      std::vector<std::string> members;
      for (std::size_t k = 0; k < n; ++k)
        if (group[k] == static_cast<int>(g) && robot.links[k].inertial && robot.links[k].inertial->mass > 0) {
          const auto& i = *robot.links[k].inertial;
          const Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> R(in_group[k].rotation.data());
          const Eigen::Vector3d c = Eigen::Vector3d(in_group[k].translation.data()) + R * Eigen::Vector3d(i.com.data());
          mass += i.mass;
          moment += i.mass * c;
          if (k != g) members.push_back(robot.links[k].name);
        }
      if (!(mass > 0)) continue;
      const Eigen::Vector3d com = moment / mass;
      Eigen::Matrix3d I = Eigen::Matrix3d::Zero();
      for (std::size_t k = 0; k < n; ++k)
        if (group[k] == static_cast<int>(g) && robot.links[k].inertial && robot.links[k].inertial->mass > 0) {
          const auto& i = *robot.links[k].inertial;
          const Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> R(in_group[k].rotation.data());
          const Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> J(i.inertia.data());
          const Eigen::Vector3d d = Eigen::Vector3d(in_group[k].translation.data()) + R * Eigen::Vector3d(i.com.data()) - com;
          I += R * J * R.transpose() + i.mass * (d.squaredNorm() * Eigen::Matrix3d::Identity() - d * d.transpose());
        }
      const UrdfLink& root_link = robot.links[g];
      const double scale = I.diagonal().cwiseAbs().maxCoeff();
      const double off = std::max({std::abs(I(0, 1)), std::abs(I(0, 2)), std::abs(I(1, 2))});
      Eigen::Vector3d principal_moments = I.diagonal();
      Eigen::Matrix3d V = Eigen::Matrix3d::Identity();
      if (off > 1e-12 * scale) {
        const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(I);
        // The permutation and signs of the eigenvectors nearest the link's own axes, so that a
        // slightly turned inertial reads as small turns.
        const Eigen::Matrix3d E = solver.eigenvectors();
        const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
        double best = -1;
        for (const auto& p : perms) {
          const double score = std::abs(E(0, p[0])) + std::abs(E(1, p[1])) + std::abs(E(2, p[2]));
          if (score > best) {
            best = score;
            for (int c = 0; c < 3; ++c) {
              V.col(c) = E.col(p[c]) * (E(c, p[c]) < 0 ? -1.0 : 1.0);
              principal_moments[c] = solver.eigenvalues()[p[c]];
            }
          }
        }
        if (V.determinant() < 0) {  // a proper rotation: flip the axis that is least like its own
          int worst = 0;
          for (int c = 1; c < 3; ++c)
            if (std::abs(V(c, c)) < std::abs(V(worst, worst))) worst = c;
          V.col(worst) *= -1;
        }
      }
      const std::string members_text = members.empty() ? "" : fmt::format(" (with {})", fmt::join(members, ", "));
      const std::string body_name = root_link.name;
      if (principal_moments.minCoeff() <= 1e-12 * std::max(scale, 1e-300))
        urdf_fail(root_link.line, fmt::format("link '{}' inertial", root_link.name),
                  fmt::format("the principal moments of inertia{} are {}, {}, {} kg*m^2: wlx's bodies need every one positive "
                              "(give a point mass a small inertia about each axis)",
                              members_text, principal_moments[0], principal_moments[1], principal_moments[2]));
      add_parameter(root_link.line, "link", root_link.name, "m_" + body_name, mass, "mass", "kg", fmt::format("mass of URDF link {}{}", body_name, members_text));
      for (int a = 0; a < 3; ++a)
        add_parameter(root_link.line, "link", root_link.name, fmt::format("I{}_{}", a + 1, body_name), principal_moments[a], "inertia", "kg*m^2",
                      fmt::format("principal moment {} of URDF link {}{}", a + 1, body_name, members_text));
      YAML::Node b(YAML::NodeType::Map);
      b["name"] = body_name;
      b["meaning"] = fmt::format("URDF link {}{}", body_name, members_text);
      b["frame"] = root_link.name;
      YAML::Node c(YAML::NodeType::Sequence);
      for (int a = 0; a < 3; ++a) c.push_back(number(std::abs(com[a]) < 1e-15 ? 0.0 : com[a]));
      b["com"] = flow(c);
      if (!V.isIdentity(0)) {
        Matrix3Rows Vr;
        for (int r = 0; r < 3; ++r)
          for (int cc = 0; cc < 3; ++cc) Vr[3 * r + cc] = V(r, cc);
        YAML::Node rotation(YAML::NodeType::Sequence);
        turns(rotation, Vr, [&](const char*, double angle) { return number(angle); });
        if (rotation.size() > 0) b["rotation"] = flow(rotation);
      }
      b["mass"] = "m_" + body_name;
      YAML::Node inertia(YAML::NodeType::Sequence);
      for (int a = 0; a < 3; ++a) inertia.push_back(fmt::format("I{}_{}", a + 1, body_name));
      b["inertia"] = flow(inertia);
      bodies.push_back(flow(b));
    }

    YAML::Node merged(YAML::NodeType::Map);
    for (const char* key : {"model", "description", "repeat"})
      if (root[key].IsDefined()) merged[key] = root[key];
    merged["parameters"] = parameters;
    YAML::Node coordinates(YAML::NodeType::Map);
    if (root["coordinates"].IsMap() && root["coordinates"]["inputs"].IsDefined()) coordinates["inputs"] = root["coordinates"]["inputs"];
    if (dependent.size() > 0) coordinates["dependent"] = dependent;
    merged["coordinates"] = coordinates;
    merged["frames"] = frames;
    if (bodies.size() > 0) merged["bodies"] = bodies;
    for (const char* key : {"wheels", "closure", "limbs", "nonholonomic", "dynamics", "clearance", "contacts", "nominal",
                            "ik_sweeps", "limits"})
      if (root[key].IsDefined()) merged[key] = root[key];
    return merged;
  }

  const std::string& urdf_fingerprint() const { return urdf_fingerprint_; }
  // The URDF's path as opened (empty without one).
  const std::string& urdf_file() const { return urdf_file_; }

 private:
  // ---- repetition ----
  void repeats(const Item& r) {
    if (!r.is_map()) r.fail("must map each repetition variable to its rows");
    for (const auto& kv : r.node()) {
      const std::string table = kv.first.Scalar();
      const Item rows(src_, kv.second, "repeat." + table, {});
      if (!is_identifier(table)) rows.fail(fmt::format("'{}' is not a name", excerpt(table)));
      if (!rows.is_sequence() || rows.size() == 0) rows.fail("must be a non-empty list of rows {variable: value, ...}");
      std::vector<Env> envs;
      for (const Item& row : rows.list()) {
        if (!row.is_map()) row.fail("a row must map variable names to values");
        Env env;
        for (const auto& v : row.node()) {
          const std::string var = v.first.Scalar();
          if (!is_identifier(var)) row.fail(fmt::format("'{}' is not a variable name", excerpt(var)));
          if (!v.second.IsScalar()) row.fail(fmt::format("variable '{}' must have a single value", var));
          env[var] = v.second.Scalar();
        }
        if (!envs.empty()) {
          std::set<std::string> a, b;
          for (const auto& kv2 : envs.front()) a.insert(kv2.first);
          for (const auto& kv2 : env) b.insert(kv2.first);
          if (a != b) row.fail("every row of a repetition must define the same variables as the first");
        }
        envs.push_back(std::move(env));
      }
      repeat_[table] = std::move(envs);
    }
  }

  // Calls fn for every entry of a list, writing out entries with `for:` once per row (nested
  // repetitions multiply; `items:` repeats a block of entries).
  void each(const Item& list, const std::function<void(const Item&)>& fn) {
    if (!list.defined()) return;
    const auto counted = [&](const Item& entry) {
      if (++expanded_entries_ > kMaxExpandedEntries)
        entry.fail(fmt::format("the file expands to more than {} list entries in all: beyond any machine", kMaxExpandedEntries));
      fn(entry);
    };
    for (const Item& e : list.list()) {
      if (!(e.is_map() && e.has("for"))) {
        counted(e);
        continue;
      }
      const Item spec = e.child("for");
      std::vector<std::string> tables;
      if (spec.is_sequence())
        for (const Item& t : spec.list()) tables.push_back(t.name());
      else
        tables.push_back(spec.name());
      for (const auto& t : tables)
        if (!repeat_.count(t)) {
          std::vector<std::string> names;
          for (const auto& kv : repeat_) names.push_back(kv.first);
          spec.fail(fmt::format("no repetition '{}' under `repeat:`{}", t, suggestion(t, names)));
        }
      // The product of the tables' rows, checked before any is written out: 10^9 rows from a
      // 1.6 KB file once took the generator past 1.2 GB.
      std::size_t product = 1;
      for (const auto& t : tables) {
        product *= repeat_[t].size();
        if (product > kMaxExpandedEntries)
          spec.fail(fmt::format("repeats its entry more than {} times (the product of the rows of {}): beyond any machine", kMaxExpandedEntries,
                                fmt::join(tables, ", ")));
      }
      std::vector<std::size_t> index(tables.size(), 0);
      while (true) {
        Env env = e.env();
        std::string suffix = "{";
        for (std::size_t k = 0; k < tables.size(); ++k) {
          const Env& row = repeat_[tables[k]][index[k]];
          for (const auto& [var, value] : row) {
            if (env.count(var)) spec.fail(fmt::format("repetition variable '{}' is defined twice here", var));
            env[var] = value;
          }
          // The row by its own value where the table has a variable of its name (side=l), else its index.
          const auto own = row.find(tables[k]);
          suffix += fmt::format("{}{}={}", k ? "," : "", tables[k], own != row.end() ? own->second : std::to_string(index[k]));
        }
        suffix += "}";
        const Item instance = e.with(env, suffix);
        if (e.has("items")) {
          const Fields only(instance, {"items"});
          each(only["items"], fn);
        } else {
          counted(instance);
        }
        std::size_t k = tables.size();
        while (k > 0 && ++index[k - 1] == repeat_[tables[k - 1]].size()) index[--k] = 0;
        if (k == 0) break;
      }
    }
  }

  // ---- names ----
  void claim_symbol_name(const Item& it, const std::string& n) {
    if (const std::string why = reserved_reason(n); !why.empty()) it.fail(fmt::format("'{}' cannot be used as a name: {}", n, why));
    if (const auto found = symbol_kind_.find(n); found != symbol_kind_.end())
      it.fail(fmt::format("'{}' is already the name of a {}", n, found->second));
  }

  int coordinate_index(const Item& it, bool inputs_only = false, bool dependents_only = false) const {
    const std::string n = it.name();
    for (const auto& c : m_.coordinates)
      if (c.name == n) {
        if (inputs_only && c.index >= m_.input_count) it.fail(fmt::format("'{}' is a dependent joint; an input is needed here", n));
        if (dependents_only && c.index < m_.input_count) it.fail(fmt::format("'{}' is an input; a dependent joint is needed here", n));
        return c.index;
      }
    std::vector<std::string> names;
    for (const auto& c : m_.coordinates) names.push_back(c.name);
    it.fail(fmt::format("no coordinate '{}'{}", n, suggestion(n, names)));
  }

  const Parameter& parameter(const Item& it, std::optional<ParameterKind> kind = std::nullopt) const {
    const std::string n = it.name();
    for (std::size_t k = 0; k < m_.parameters.size(); ++k)
      if (m_.parameters[k].name == n) {
        if (kind && m_.parameter_kinds[k] != *kind)
          it.fail(fmt::format("'{}' is a parameter of kind {}; one of kind {} is needed here", n,
                              kind_name(m_.parameter_kinds[k]), kind_name(*kind)));
        return m_.parameters[k];
      }
    std::vector<std::string> names;
    for (const auto& p : m_.parameters) names.push_back(p.name);
    it.fail(fmt::format("no parameter '{}'{}", n, suggestion(n, names)));
  }

  int frame_index(const Item& it) const {
    const std::string n = it.name();
    const int k = m_.frame_index(n);
    if (k >= 0) return k;
    std::vector<std::string> names;
    for (const auto& f : m_.frames) names.push_back(f.name);
    it.fail(fmt::format("no frame '{}'{}", n, suggestion(n, names)));
  }

  // ---- expressions ----
  // An expression of parameters (and, where allowed, coordinates), parsed by GiNaC's parser
  // against a strict table. Identifiers are checked first so that a typo gets a suggestion.
  ex expression(const Item& it, bool allow_coordinates) const {
    const std::string s = it.text();
    // GiNaC's parser and every pass over the tree recurse on its depth: bounded before parsing.
    if (s.size() > kMaxExpressionBytes)
      it.fail(fmt::format("an expression of {} bytes; at most {} (a long formula belongs in parameters)", s.size(), kMaxExpressionBytes));
    {
      // Runs of signs (- - - x) nest like parentheses.
      int depth = 0, deepest = 0, signs = 0;
      for (const char c : s) {
        if (c == '(') deepest = std::max(deepest, ++depth), signs = 0;
        else if (c == ')') --depth, signs = 0;
        else if (c == '-' || c == '+') deepest = std::max(deepest, depth + ++signs);
        else if (c != ' ') signs = 0;
      }
      if (deepest > kMaxExpressionDepth)
        it.fail(fmt::format("in '{}': parentheses and signs nest more than {} deep", excerpt(s), kMaxExpressionDepth));
    }
    static const std::set<std::string> functions = {"sin", "cos", "tan", "asin", "acos", "atan", "sqrt", "exp", "log"};
    for (std::size_t i = 0; i < s.size();) {
      const auto c = static_cast<unsigned char>(s[i]);
      if (std::isdigit(c) || (s[i] == '.' && i + 1 < s.size() && std::isdigit(static_cast<unsigned char>(s[i + 1])))) {
        while (i < s.size() && (std::isdigit(static_cast<unsigned char>(s[i])) || s[i] == '.')) ++i;
        if (i < s.size() && (s[i] == 'e' || s[i] == 'E')) {
          ++i;
          if (i < s.size() && (s[i] == '+' || s[i] == '-')) ++i;
          while (i < s.size() && std::isdigit(static_cast<unsigned char>(s[i]))) ++i;
        }
        continue;
      }
      if (std::isalpha(c) || s[i] == '_') {
        std::size_t j = i;
        while (j < s.size() && (std::isalnum(static_cast<unsigned char>(s[j])) || s[j] == '_')) ++j;
        const std::string id = s.substr(i, j - i);
        std::size_t k = j;
        while (k < s.size() && s[k] == ' ') ++k;
        const bool call = k < s.size() && s[k] == '(';
        if (call) {
          if (!functions.count(id))
            it.fail(fmt::format("unknown function '{}' in '{}'; the functions are {}", id, excerpt(s), fmt::join(functions, ", ")));
        } else if (id != "Pi" && !params_.count(id)) {
          const bool coordinate = coordinates_.count(id) != 0;
          if (coordinate && !allow_coordinates)
            it.fail(fmt::format("'{}' is a coordinate; only parameters may appear in '{}'", id, excerpt(s)));
          if (!coordinate) {
            std::vector<std::string> names;
            for (const auto& kv : params_) names.push_back(kv.first);
            if (allow_coordinates)
              for (const auto& kv : coordinates_) names.push_back(kv.first);
            it.fail(fmt::format("unknown symbol '{}' in '{}'{}", id, excerpt(s), suggestion(id, names)));
          }
        }
        i = j;
        continue;
      }
      ++i;
    }
    // GiNaC evaluates integer powers exactly, so 9^9^9 would not finish: exponents are small
    // integer literals.
    for (std::size_t i = s.find('^'); i != std::string::npos; i = s.find('^', i + 1)) {
      std::size_t j = i + 1;
      while (j < s.size() && s[j] == ' ') ++j;
      if (j < s.size() && s[j] == '-') ++j;
      const std::size_t digits = j;
      while (j < s.size() && std::isdigit(static_cast<unsigned char>(s[j]))) ++j;
      const std::size_t count = j - digits;
      while (j < s.size() && s[j] == ' ') ++j;
      if (count == 0 || count > 2 || (j < s.size() && (s[j] == '^' || s[j] == '.')))
        it.fail(fmt::format("in '{}': an exponent is a small integer (x^2, x^-1), not an expression", excerpt(s)));
    }
    GiNaC::symtab table = params_;
    if (allow_coordinates) table.insert(coordinates_.begin(), coordinates_.end());
    table["Pi"] = GiNaC::Pi;
    ex e;
    try {
      GiNaC::parser reader(table, true);
      e = reader(s);
    } catch (const std::exception& error) {
      it.fail(fmt::format("cannot read the expression '{}': {}", excerpt(s), error.what()));
    }
    check_at_defaults(it, s, e);
    return e;
  }

  // An expression of parameters alone is evaluated at their defaults: acos(2) or sqrt(-a) would be
  // emitted as code that yields NaN, 1/(a - b) with a = b as an Inf, so each is an error here,
  // naming the field. (An expression with coordinates is a joint step, checked where it is used.)
  void check_at_defaults(const Item& it, const std::string& s, const ex& e) const {
    for (const auto& kv : coordinates_)
      if (e.has(kv.second)) return;
    std::string problem;
    try {
      const ex v = e.subs(param_defaults_).evalf();
      if (!GiNaC::is_a<GiNaC::numeric>(v)) {
        problem = "does not evaluate to a number";
      } else {
        const GiNaC::numeric n = GiNaC::ex_to<GiNaC::numeric>(v);
        std::ostringstream shown;
        shown << n;
        if (!n.is_real()) problem = fmt::format("is complex ({})", excerpt(shown.str()));
        else if (!std::isfinite(n.to_double())) problem = fmt::format("is not finite ({})", n.to_double());
      }
    } catch (const std::exception& error) {  // GiNaC's pole_error: 1/0, log(0), tan(Pi/2)
      problem = fmt::format("is singular ({})", error.what());
    }
    if (!problem.empty()) it.fail(fmt::format("'{}' at the default parameters {}", excerpt(s), problem));
    // Exact arithmetic can be finite where double is not (exp(1000)/exp(999)): the emitted code
    // computes in double, so the expression is also evaluated so, as the printed code would.
    ExprGraph graph;
    int root = 0;
    try {
      root = graph.add(e.subs(GiNaC::Pi == GiNaC::Pi.evalf()));  // the graph takes numbers, not constants
    } catch (const std::exception& error) {  // what the emitted code cannot compute (a power of a parameter's power)
      it.fail(fmt::format("'{}' cannot be written as code: {}", excerpt(s), error.what()));
    }
    std::map<std::string, double> defaults;
    for (const Parameter& p : m_.parameters) defaults[p.name] = p.default_value;
    const DoubleValues values = evaluate_in_double(graph, defaults);
    if (!std::isfinite(values.value[static_cast<std::size_t>(root)]))
      it.fail(fmt::format("'{}' evaluates to {} in double at the default parameters ({}: {})", excerpt(s), values.shown(root),
                          values.why, node_text(graph, values.first_bad)));
  }

  Vec3 vector3(const Item& it) const {
    if (!it.is_sequence() || it.size() != 3) it.fail("must be a list of 3 expressions [x, y, z]");
    return {expression(it.element(0), false), expression(it.element(1), false), expression(it.element(2), false)};
  }

  // ---- sections ----
  void parameters(const Item& list) {
    each(list, [&](const Item& it) {
      const Fields f(it, {"name", "value", "unit", "kind", "meaning"});
      const std::string n = f["name"].name();
      claim_symbol_name(f["name"], n);
      const Item kind_item = f["kind"];
      const std::string kind = kind_item.text();
      static const std::map<std::string, std::pair<ParameterKind, const char*>> kinds = {
          {"length", {ParameterKind::length, "m"}},   {"offset", {ParameterKind::offset, "m"}},
          {"angle", {ParameterKind::angle, "rad"}},   {"mass", {ParameterKind::mass, "kg"}},
          {"inertia", {ParameterKind::inertia, "kg*m^2"}}, {"gravity", {ParameterKind::gravity, "m/s^2"}},
          {"other", {ParameterKind::other, nullptr}}};
      const auto k = kinds.find(kind);
      if (k == kinds.end()) {
        std::vector<std::string> names;
        for (const auto& kv : kinds) names.push_back(kv.first);
        kind_item.fail(fmt::format("unknown kind '{}'{}; the kinds are {}", excerpt(kind), suggestion(kind, names), fmt::join(names, ", ")));
      }
      const std::string unit = f["unit"].text();
      if (k->second.second != nullptr && unit != k->second.second)
        f["unit"].fail(fmt::format("a parameter of kind {} has unit {}, not '{}'", kind, k->second.second, excerpt(unit)));
      const double value = f["value"].number();
      const ParameterKind pk = k->second.first;
      if (const std::string why = parameter_value_problem(pk, value); !why.empty())
        f["value"].fail(fmt::format("{} {}, got {}", pk == ParameterKind::gravity ? "gravity" : "a " + kind, why, value));
      m_.parameters.push_back({n, value, unit, f.optional("meaning") ? f["meaning"].text() : "", GiNaC::realsymbol(n)});
      m_.parameter_kinds.push_back(pk);
      params_[n] = m_.parameters.back().symbol;
      param_defaults_[m_.parameters.back().symbol] = value;
      symbol_kind_[n] = "parameter";
    });
    if (m_.parameters.empty()) list.fail("a model needs at least one parameter");
  }

  void coordinate(const Item& it) {
    const Fields f(it, {"name", "unit", "meaning"});
    const std::string n = f["name"].name();
    claim_symbol_name(f["name"], n);
    const std::string unit = f["unit"].text();
    if (unit != "m" && unit != "rad") f["unit"].fail(fmt::format("a coordinate is in m or rad, not '{}'", excerpt(unit)));
    if (m_.coordinates.size() == kMaxCoordinates) it.fail(fmt::format("a model has at most {} coordinates", kMaxCoordinates));
    const int index = static_cast<int>(m_.coordinates.size());
    m_.coordinates.push_back({n, index, GiNaC::realsymbol(n), GiNaC::realsymbol(n + "_dot"), unit,
                              f.optional("meaning") ? f["meaning"].text() : ""});
    coordinates_[n] = m_.coordinates.back().q;
    symbol_kind_[n] = "coordinate";
  }

  void coordinates(const Item& c) {
    const Fields f(c, {"inputs", "dependent"});
    each(f["inputs"], [&](const Item& it) { coordinate(it); });
    m_.input_count = static_cast<int>(m_.coordinates.size());
    if (m_.input_count == 0) f["inputs"].fail("a model needs at least one input");
    if (auto d = f.optional("dependent")) each(*d, [&](const Item& it) { coordinate(it); });
  }

  // Frames may name parents listed after them; they are built parents first, with cycles found.
  void frames(const Item& list) {
    std::vector<Item> entries;
    each(list, [&](const Item& it) { entries.push_back(it); });
    if (entries.empty()) list.fail("a model needs at least one frame");
    if (entries.size() > kMaxFrames) list.fail(fmt::format("has {} frames; a model has at most {}", entries.size(), kMaxFrames));
    std::map<std::string, std::size_t> by_name;
    std::vector<std::string> names;
    for (std::size_t k = 0; k < entries.size(); ++k) {
      const Fields f(entries[k], {"name", "meaning", "parent", "chain"});
      const std::string n = f["name"].name();
      if (n == "K0") f["name"].fail("K0 is the ground frame and cannot be defined");
      if (by_name.count(n)) f["name"].fail(fmt::format("frame '{}' is defined twice", n));
      by_name[n] = k;
      names.push_back(n);
    }
    m_.frames.resize(entries.size());
    // Each frame is built after its parent. The order comes from walking up the parents without
    // recursion, so no file decides the depth of the generator's stack (10^5 chained frames once
    // overflowed it); the depth of a chain is bounded too (its expressions grow with it).
    std::vector<int> state(entries.size(), 0);  // 0 not built, 1 on the walk, 2 built
    std::vector<std::size_t> parent_of(entries.size(), entries.size());  // entries.size(): K0
    std::vector<std::size_t> depth_of(entries.size(), 0);  // frames from K0, once built
    const auto build_one = [&](std::size_t k) {
      NamedFrame& out = m_.frames[k];
      const Item& it = entries[k];
      const Fields f(it, {"name", "meaning", "parent", "chain"});
      out.name = names[k];
      out.meaning = f.optional("meaning") ? f["meaning"].text() : "";
      Frame frame = parent_of[k] == entries.size() ? Frame::ground() : m_.frames[parent_of[k]].frame;
      for (const Item& step : f["chain"].list()) {
        if (!step.is_map() || step.size() != 1)
          step.fail("a chain step is one of tx, ty, tz, rx, ry, rz: <coordinate or expression>, or translate: [x, y, z]");
        const std::string op = step.node().begin()->first.Scalar();
        const Item arg = step.child(op);
        ChainStep cs;
        if (op == "translate") {
          cs.kind = ChainStep::Kind::Translate;
          cs.offset = vector3(arg);
          frame = frame.translated(cs.offset);
        } else if (op.size() == 2 && (op[0] == 't' || op[0] == 'r') && op[1] >= 'x' && op[1] <= 'z') {
          cs.axis = static_cast<Axis>(op[1] - 'x');
          const ex e = expression(arg, true);
          const bool rotation = op[0] == 'r';
          // `rz: q` is a joint; so is `rz: -q`, about (along) the negative axis (URDF's axis 0 0 -1).
          const auto joint_symbol = [&](const ex& x) {
            return GiNaC::is_a<GiNaC::symbol>(x) && coordinates_.count(GiNaC::ex_to<GiNaC::symbol>(x).get_name());
          };
          const int sign = joint_symbol(e) ? 1 : joint_symbol(-e) ? -1 : 0;
          if (sign != 0) {
            const Coordinate& c = m_.coordinate(GiNaC::ex_to<GiNaC::symbol>(sign > 0 ? e : -e).get_name());
            if (rotation && c.unit != "rad") arg.fail(fmt::format("'{}' turns a revolute joint, so its unit must be rad, not {}", c.name, c.unit));
            if (!rotation && c.unit != "m") arg.fail(fmt::format("'{}' drives a prismatic joint, so its unit must be m, not {}", c.name, c.unit));
            for (const auto& [user, at] : joint_users_)
              if (user == c.index) arg.fail(fmt::format("coordinate '{}' already drives a joint (at {})", c.name, at));
            joint_users_.emplace_back(c.index, arg.path());
            cs.kind = rotation ? ChainStep::Kind::Rotate : ChainStep::Kind::Slide;
            cs.coordinate = c.index;
            cs.sign = sign;
            frame = rotation ? frame.rotated(cs.axis, c, sign) : frame.slid(cs.axis, c, sign);
          } else {
            for (const auto& kv : coordinates_)
              if (e.has(kv.second))
                arg.fail(fmt::format("a joint is driven by one coordinate alone (or its negative); '{}' mixes coordinate '{}' with other terms",
                                     excerpt(arg.text()), kv.first));
            if (rotation) {
              cs.kind = ChainStep::Kind::Turn;
              cs.angle = e;
              frame = frame.turned(cs.axis, e);
            } else {
              cs.kind = ChainStep::Kind::Translate;
              cs.offset[static_cast<int>(cs.axis)] = e;
              frame = frame.translated(cs.offset);
            }
          }
        } else {
          step.fail(fmt::format("unknown chain step '{}'{}; the steps are tx, ty, tz, rx, ry, rz, translate", excerpt(op),
                                suggestion(op, {"tx", "ty", "tz", "rx", "ry", "rz", "translate"})));
        }
        out.chain.push_back(cs);
      }
      out.frame = std::move(frame);
      state[k] = 2;
    };
    std::vector<std::size_t> walk;
    for (std::size_t k = 0; k < entries.size(); ++k) {
      walk.clear();
      for (std::size_t j = k; j != entries.size() && state[j] != 2;) {
        const Fields f(entries[j], {"name", "meaning", "parent", "chain"});
        if (state[j] == 1) {
          // The cycle is the walk from j's first visit; shown in full when short, else its ends.
          const auto first = std::find(walk.begin(), walk.end(), j);
          std::vector<std::string> cycle;
          for (auto w = first; w != walk.end(); ++w) cycle.push_back(names[*w]);
          cycle.push_back(names[j]);
          const std::string shown = cycle.size() <= 12 ? fmt::format("{}", fmt::join(cycle, " -> "))
                                                       : fmt::format("{} -> ... -> {} ({} frames)", fmt::join(cycle.begin(), cycle.begin() + 5, " -> "),
                                                                     fmt::join(cycle.end() - 5, cycle.end(), " -> "), cycle.size() - 1);
          f["parent"].fail(fmt::format("the frames' parents form a cycle: {}", shown));
        }
        state[j] = 1;
        walk.push_back(j);
        m_.frames[j].parent = f["parent"].name();
        if (m_.frames[j].parent == "K0") {
          parent_of[j] = entries.size();
          break;
        }
        const auto p = by_name.find(m_.frames[j].parent);
        if (p == by_name.end())
          f["parent"].fail(fmt::format("no frame '{}' (K0 is the ground){}", m_.frames[j].parent, suggestion(m_.frames[j].parent, names)));
        parent_of[j] = p->second;
        j = p->second;
      }
      // The walk ends at K0 or at a built frame: every frame on it is that much further from K0.
      const std::size_t end = walk.empty() ? entries.size() : parent_of[walk.back()];
      const std::size_t base = end == entries.size() ? 0 : depth_of[end];
      if (base + walk.size() > kMaxChainDepth)
        Fields(entries[k], {"name", "meaning", "parent", "chain"})["parent"].fail(
            fmt::format("frame '{}' is {} frames away from K0, more than {}: chains this deep are not a machine, and their "
                        "expressions would grow without bound",
                        names[k], base + walk.size(), kMaxChainDepth));
      for (std::size_t w = walk.size(); w-- > 0;) {
        depth_of[walk[w]] = base + walk.size() - w;
        build_one(walk[w]);
      }
    }
  }

  void bodies(const Item& list) {
    std::set<std::string> seen;
    each(list, [&](const Item& it) {
      const Fields f(it, {"name", "meaning", "frame", "com", "rotation", "mass", "inertia"});
      Body b;
      b.name = f["name"].name();
      if (!seen.insert(b.name).second) f["name"].fail(fmt::format("body '{}' is defined twice", b.name));
      b.meaning = f.optional("meaning") ? f["meaning"].text() : "";
      const int frame = frame_index(f["frame"]);
      b.frame = m_.frames[static_cast<std::size_t>(frame)].name;
      b.com = vector3(f["com"]);
      b.com_frame = m_.frames[static_cast<std::size_t>(frame)].frame.translated(b.com);
      // The principal axes, turned from the frame's (a URDF inertial's rpy, or the axes that
      // diagonalise its tensor): fixed turns of parameter expressions, applied in order.
      if (auto rotation = f.optional("rotation"))
        for (const Item& step : rotation->list()) {
          const std::string op = step.is_map() && step.size() == 1 ? step.node().begin()->first.Scalar() : "";
          if (op != "rx" && op != "ry" && op != "rz")
            step.fail("a rotation step is rx, ry or rz: <expression of parameters> (a fixed turn about the axes turned so far)");
          b.principal_turns.emplace_back(static_cast<Axis>(op[1] - 'x'), expression(step.child(op), false));
          b.com_frame = b.com_frame.turned(b.principal_turns.back().first, b.principal_turns.back().second);
        }
      b.mass = parameter(f["mass"], ParameterKind::mass).name;
      const Item inertia = f["inertia"];
      if (!inertia.is_sequence() || inertia.size() != 3)
        inertia.fail("must list the 3 principal moments about the CoM, in the frame's axes: [Ixx, Iyy, Izz]");
      for (std::size_t k = 0; k < 3; ++k) b.inertia[k] = parameter(inertia.element(k), ParameterKind::inertia).name;
      m_.bodies.push_back(std::move(b));
    });
  }

  void closure(const Item& list) {
    std::set<std::string> seen;
    each(list, [&](const Item& it) {
      const Item type_item = it.is_map() && it.has("type") ? it.child("type") : it;
      const std::string type = it.is_map() && it.has("type") ? type_item.text() : "";
      ClosureCondition c;
      using K = ClosureCondition::Kind;
      if (type == "point") {
        const Fields f(it, {"name", "type", "frame", "component", "equals"});
        c.name = f["name"].name();
        c.kind = K::PointEqualsCoordinate;
        c.frame = m_.frames[static_cast<std::size_t>(frame_index(f["frame"]))].name;
        c.axis = axis_of(f["component"]);
        c.target = coordinate_index(f["equals"], true);
        if (m_.coordinates[static_cast<std::size_t>(c.target)].unit != "m")
          f["equals"].fail(fmt::format("'{}' is an angle; a point's component equals a length coordinate (m)",
                                       m_.coordinates[static_cast<std::size_t>(c.target)].name));
      } else if (type == "level") {
        const Fields f(it, {"name", "type", "frame", "axis"});
        c.name = f["name"].name();
        c.kind = K::AttachedDirectionLevel;
        const NamedFrame& frame = m_.frames[static_cast<std::size_t>(frame_index(f["frame"]))];
        if (frame.derived_from_wheel >= 0)
          f["frame"].fail(fmt::format("'{}' is the contact frame of wheel '{}', level by construction: a level row on it "
                                      "would fix nothing",
                                      frame.name, m_.wheels[static_cast<std::size_t>(frame.derived_from_wheel)].name));
        c.frame = frame.name;
        c.axis = axis_of(f["axis"]);
      } else if (type == "sum") {
        const Fields f(it, {"name", "type", "coordinates"});
        c.name = f["name"].name();
        c.kind = K::CoordinateSum;
        for (const Item& ci : f["coordinates"].list()) c.coordinates.push_back(coordinate_index(ci));
        if (c.coordinates.empty()) f["coordinates"].fail("must name at least one coordinate");
      } else {
        (it.is_map() && it.has("type") ? type_item : it)
            .fail(fmt::format("a closure condition needs `type: point`, `level` or `sum`{}",
                              type.empty() ? "" : fmt::format(", not '{}'{}", excerpt(type), suggestion(type, {"point", "level", "sum"}))));
      }
      if (!seen.insert(c.name).second) it.child("name").fail(fmt::format("closure condition '{}' is defined twice", c.name));
      m_.closure.push_back(std::move(c));
    });
    rows_item_ = list;
  }

  // The dependent coordinates a closure row involves (structurally, without differentiating).
  std::set<int> row_dependents(const ClosureCondition& c) const {
    std::set<int> out;
    if (c.kind == ClosureCondition::Kind::CoordinateSum) {
      out.insert(c.coordinates.begin(), c.coordinates.end());
    } else {
      for (const auto& j : m_.frame(c.frame).joints) out.insert(j.coordinate);
      if (c.target >= 0) out.insert(c.target);
    }
    std::set<int> dependents;
    for (int k : out)
      if (k >= m_.input_count) dependents.insert(k);
    return dependents;
  }

  void limbs(const std::optional<Item>& list, const Item& top) {
    const int dependents = static_cast<int>(m_.coordinates.size()) - m_.input_count;
    if (static_cast<int>(m_.closure.size()) != dependents)
      (rows_item_ ? *rows_item_ : top)
          .fail(fmt::format("{} closure conditions for {} dependent joints: the closure needs exactly one equation per "
                            "dependent joint",
                            m_.closure.size(), dependents));
    if (!list) {
      if (dependents > 0) top.fail("missing field 'limbs': group the closure rows and dependent joints into limbs");
      return;
    }
    std::map<int, std::string> row_owner, joint_owner;
    each(*list, [&](const Item& it) {
      const Fields f(it, {"name", "title", "closure", "joints", "start", "branch"});
      Limb limb;
      // The branch of its closed form every command takes unless told otherwise (checked against
      // the branches wlx-gen finds, which come later: emit_ik.cpp).
      if (auto b = f.optional("branch")) {
        const double v = b->number();
        if (!(v >= 0 && v <= 1023 && v == std::floor(v))) b->fail(fmt::format("a branch is a whole number from 0, got {}", v));
        limb.branch = static_cast<int>(v);
        const YAML::Mark mark = b->mark();
        limb.branch_place = fmt::format("{}:{}:{}: {}", src_.name, mark.line + 1, mark.column + 1, b->path());
      }
      limb.name = f["name"].name();
      for (const auto& l : m_.limbs)
        if (l.name == limb.name) f["name"].fail(fmt::format("limb '{}' is defined twice", limb.name));
      limb.title = f.optional("title") ? f["title"].text() : limb.name;
      for (const Item& r : f["closure"].list()) {
        const std::string n = r.name();
        int row = -1;
        std::vector<std::string> names;
        for (std::size_t k = 0; k < m_.closure.size(); ++k) {
          names.push_back(m_.closure[k].name);
          if (m_.closure[k].name == n) row = static_cast<int>(k);
        }
        if (row < 0) r.fail(fmt::format("no closure condition '{}'{}", n, suggestion(n, names)));
        if (row_owner.count(row)) r.fail(fmt::format("closure condition '{}' already belongs to limb '{}'", n, row_owner[row]));
        row_owner[row] = limb.name;
        limb.rows.push_back(row);
      }
      for (const Item& j : f["joints"].list()) {
        const int k = coordinate_index(j, false, true);
        if (joint_owner.count(k))
          j.fail(fmt::format("joint '{}' already belongs to limb '{}'", m_.coordinates[static_cast<std::size_t>(k)].name, joint_owner[k]));
        joint_owner[k] = limb.name;
        limb.joints.push_back(k);
      }
      // Where Newton's method starts for this limb's joints (a bent knee, not a straight leg).
      if (auto start = f.optional("start")) {
        if (!start->is_map()) start->fail("must map the limb's joints to start values");
        for (const auto& kv : start->node()) {
          const Item key(src_, kv.first, start->path(), start->env());  // keys may name <variables> too
          const int k = coordinate_index(key, false, true);
          if (std::find(limb.joints.begin(), limb.joints.end(), k) == limb.joints.end())
            key.fail(fmt::format("'{}' is not one of limb '{}''s joints", m_.coordinates[static_cast<std::size_t>(k)].name, limb.name));
          limb_start_[k] = start->child(kv.first.Scalar()).number(true);  // <sign>*0.6 too, as in ik_sweeps
        }
      }
      if (limb.rows.size() != limb.joints.size() || limb.rows.empty())
        it.fail(fmt::format("limb '{}' has {} closure conditions and {} joints: a limb's block of dPhi/ds must be square and "
                            "non-empty",
                            limb.name, limb.rows.size(), limb.joints.size()));
      for (int row : limb.rows)
        for (int k : row_dependents(m_.closure[static_cast<std::size_t>(row)]))
          if (std::find(limb.joints.begin(), limb.joints.end(), k) == limb.joints.end())
            f["closure"].fail(fmt::format("closure condition '{}' depends on joint '{}', which is not one of limb '{}''s joints: "
                                          "the limbs must decouple",
                                          m_.closure[static_cast<std::size_t>(row)].name,
                                          m_.coordinates[static_cast<std::size_t>(k)].name, limb.name));
      m_.limbs.push_back(std::move(limb));
    });
    for (std::size_t k = 0; k < m_.closure.size(); ++k)
      if (!row_owner.count(static_cast<int>(k)))
        list->fail(fmt::format("closure condition '{}' belongs to no limb", m_.closure[k].name));
    for (int k = m_.input_count; k < static_cast<int>(m_.coordinates.size()); ++k)
      if (!joint_owner.count(k)) list->fail(fmt::format("dependent joint '{}' belongs to no limb", m_.coordinates[static_cast<std::size_t>(k)].name));
  }

  // Two forms: a wheel on a hub (`hub`, `axle`: wlx-gen derives the contact frame `contact`,
  // default contact_<name>), or a contact frame the file builds itself (`contact`, `forward`,
  // `lateral`: virtual joints and level rows keep it on the rim's lowest point).
  void wheels(const Item& list) {
    each(list, [&](const Item& it) {
      const bool on_hub = it.is_map() && it.has("hub");
      const Fields f(it, on_hub ? std::vector<std::string>{"name", "hub", "axle", "radius", "offset", "ground", "contact"}
                                : std::vector<std::string>{"name", "contact", "forward", "lateral", "radius", "ground"});
      NonholonomicWheel w;
      w.name = f["name"].name();
      for (const auto& other : m_.wheels)
        if (other.name == w.name) f["name"].fail(fmt::format("wheel '{}' is defined twice", w.name));
      // On a hub, a URDF's collision cylinder or sphere may give the radius and the offset (with_urdf).
      const auto shape = on_hub ? urdf_wheel_shape_.find(it.child("hub").text()) : urdf_wheel_shape_.end();
      w.radius = f.optional("radius") || shape == urdf_wheel_shape_.end() ? parameter(f["radius"], ParameterKind::length).name
                                                                          : shape->second.radius;
      if (auto o = f.optional("offset")) w.offset = parameter(*o, ParameterKind::offset).name;
      else if (shape != urdf_wheel_shape_.end() && !f.optional("radius")) w.offset = shape->second.offset;
      w.ground = coordinate_index(f["ground"], true);
      if (m_.coordinates[static_cast<std::size_t>(w.ground)].unit != "m")
        f["ground"].fail(fmt::format("'{}' is an angle; the ground level is a height (m)", m_.coordinates[static_cast<std::size_t>(w.ground)].name));
      if (!on_hub) {
        w.contact = m_.frames[static_cast<std::size_t>(frame_index(f["contact"]))].name;
        w.forward = axis_of(f["forward"]);
        w.lateral = axis_of(f["lateral"]);
        if (w.forward == w.lateral) f["lateral"].fail("the lateral axis must differ from the forward axis");
        m_.wheels.push_back(std::move(w));
        return;
      }
      const NamedFrame& hub = m_.frames[static_cast<std::size_t>(frame_index(f["hub"]))];
      if (hub.derived_from_wheel >= 0) f["hub"].fail(fmt::format("'{}' is a wheel's contact frame, not a hub", hub.name));
      w.hub = hub.name;
      w.axle = axis_of(f["axle"]);
      if (const auto u = urdf_axle_.find(w.hub); u != urdf_axle_.end() && u->second.axis != w.axle)
        f["axle"].fail(fmt::format("the URDF's joint '{}' ({}) turns the wheel about {} of '{}', not {}", u->second.joint,
                                   u->second.place, "xyz"[static_cast<int>(u->second.axis)], w.hub, "xyz"[static_cast<int>(w.axle)]));
      w.contact = f.optional("contact") ? f["contact"].name() : "contact_" + w.name;
      const Item& where = f.optional("contact") ? f["contact"] : f["name"];
      if (w.contact == "K0" || m_.frame_index(w.contact) >= 0)
        where.fail(fmt::format("the contact frame '{}' that wlx-gen derives for this wheel is already a frame: name it "
                               "with `contact:`",
                               w.contact));
      NamedFrame contact;
      contact.name = w.contact;
      contact.meaning = fmt::format("contact point of wheel {} (derived: the rim point nearest the ground)", w.name);
      contact.parent = hub.name;
      contact.frame = wheel_contact_frame(hub.frame, w.axle, m_.parameter(w.radius).symbol,
                                          w.offset.empty() ? ex(0) : ex(m_.parameter(w.offset).symbol), m_.coordinates);
      contact.derived_from_wheel = static_cast<int>(m_.wheels.size());
      m_.frames.push_back(std::move(contact));
      m_.wheels.push_back(std::move(w));
    });
  }

  void nonholonomic(const std::optional<Item>& section, const Item& top) {
    if (m_.wheels.empty()) {
      if (section) section->fail("the model has no wheels, so it has no non-holonomic section");
      return;
    }
    if (!section) top.fail("missing field 'nonholonomic': a model with wheels names the candidate dependent rates and pairs");
    const Fields f(*section, {"pair_candidates", "pairs", "default_pair"});
    if (f["pair_candidates"].list().size() < m_.wheels.size())
      f["pair_candidates"].fail(fmt::format("{} wheels need at least {} candidate dependent rates, one per wheel", m_.wheels.size(),
                                            m_.wheels.size()));
    for (const Item& c : f["pair_candidates"].list()) {
      const int k = coordinate_index(c, true);
      if (std::count(m_.pair_candidates.begin(), m_.pair_candidates.end(), k)) c.fail("listed twice");
      m_.pair_candidates.push_back(k);
    }
    const Item pairs = f["pairs"];
    if (!pairs.is_map() || pairs.size() == 0) pairs.fail("must map pair names to lists of dependent rates");
    for (const auto& kv : pairs.node()) {
      DependentPair p;
      p.name = kv.first.Scalar();
      const Item list = pairs.child(p.name);
      if (!is_identifier(p.name)) list.fail(fmt::format("'{}' is not a name", excerpt(p.name)));
      if (!list.is_sequence() || list.size() != m_.wheels.size())
        list.fail(fmt::format("a dependent pair lists {} rates, one per wheel", m_.wheels.size()));
      for (std::size_t k = 0; k < list.size(); ++k) {
        const int c = coordinate_index(list.element(k), true);
        if (!std::count(m_.pair_candidates.begin(), m_.pair_candidates.end(), c))
          list.element(k).fail(fmt::format("'{}' is not one of pair_candidates", m_.coordinates[static_cast<std::size_t>(c)].name));
        if (std::count(p.coordinates.begin(), p.coordinates.end(), c))
          list.element(k).fail(fmt::format("'{}' is listed twice: the dependent rates must differ", m_.coordinates[static_cast<std::size_t>(c)].name));
        p.coordinates.push_back(c);
      }
      m_.pairs.push_back(p);
    }
    const Item def = f["default_pair"];
    m_.default_pair = def.name();
    bool found = false;
    for (const auto& p : m_.pairs) found = found || p.name == m_.default_pair;
    if (!found) def.fail(fmt::format("no pair '{}' under pairs", m_.default_pair));
  }

  void dynamics(const Item& section) {
    if (m_.bodies.empty()) section.fail("inverse dynamics needs bodies");
    const Fields f(section, {"gravity", "commanded", "pair", "actuated", "weights", "torque_limits"});
    Dynamics d;
    d.gravity = parameter(f["gravity"], ParameterKind::gravity).name;
    // The wheels' dependent rates: a named pair (any model with wheels), none without wheels.
    static const DependentPair no_pair{"none", {}};
    const DependentPair* pair = &no_pair;
    if (m_.wheels.empty()) {
      if (auto p = f.optional("pair")) p->fail("the model has no wheels, so no dependent rates: leave `pair` out");
      d.pair = no_pair.name;
    } else {
      d.pair = f["pair"].name();
      pair = nullptr;
      for (const auto& p : m_.pairs)
        if (p.name == d.pair) pair = &p;
      if (pair == nullptr) f["pair"].fail(fmt::format("no pair '{}' under nonholonomic.pairs", d.pair));
    }
    for (const Item& c : f["commanded"].list()) {
      const int k = coordinate_index(c, true);
      if (std::count(d.commanded.begin(), d.commanded.end(), k)) c.fail("listed twice");
      if (std::count(pair->coordinates.begin(), pair->coordinates.end(), k)) c.fail("a commanded rate cannot be one of the dependent pair");
      d.commanded.push_back(k);
    }
    if (d.commanded.empty()) f["commanded"].fail("name at least one commanded speed");
    // An actuator is a joint (a coordinate's name) or a wheel's drive ({wheel: NAME}, or from a URDF
    // the name of the wheel's continuous joint, which then names the drive).
    const auto wheel_of_urdf_joint = [&](const std::string& joint) {
      for (std::size_t w = 0; w < m_.wheels.size(); ++w)
        if (const auto u = urdf_axle_.find(m_.wheels[w].hub); u != urdf_axle_.end() && u->second.joint == joint)
          return static_cast<int>(w);
      return -1;
    };
    const auto wheel_named = [&](const Item& it) {
      const std::string wheel = it.name();
      std::vector<std::string> names;
      for (std::size_t w = 0; w < m_.wheels.size(); ++w) {
        if (m_.wheels[w].name == wheel) return static_cast<int>(w);
        names.push_back(m_.wheels[w].name);
      }
      it.fail(fmt::format("no wheel '{}' under wheels{}", wheel, suggestion(wheel, names)));
    };
    // The drive of wheel w; `at` is where a message points, `own_name` the file's name for it.
    const auto drive = [&](const Item& at, int w, const std::optional<Item>& own_name) {
      const NonholonomicWheel& wheel = m_.wheels[static_cast<std::size_t>(w)];
      if (wheel.hub.empty())
        at.fail(fmt::format("wheel '{}' has no hub (its contact frame is built by the file): its spin is a joint "
                            "of the file's, so actuate that joint instead; a drive needs a wheel on a hub",
                            wheel.name));
      const auto u = urdf_axle_.find(wheel.hub);
      Actuator a;
      a.wheel = w;
      a.name = own_name ? own_name->name() : u != urdf_axle_.end() ? u->second.joint : "spin_" + wheel.name;
      for (const auto& q : m_.coordinates)
        if (q.name == a.name)
          at.fail(fmt::format("the drive of wheel '{}' is named '{}', as is a coordinate: rename the coordinate",
                              wheel.name, a.name));
      return a;
    };
    for (const Item& c : f["actuated"].list()) {
      Actuator a;
      if (c.is_map()) {
        const Fields af(c, {"wheel", "name"});
        a = drive(af["wheel"], wheel_named(af["wheel"]), af.optional("name"));
      } else if (const int w = wheel_of_urdf_joint(c.text()); w >= 0) {
        a = drive(c, w, std::nullopt);
      } else {
        a.coordinate = coordinate_index(c);
        a.name = m_.coordinates[static_cast<std::size_t>(a.coordinate)].name;
      }
      for (const Actuator& b : d.actuated)
        if (b.name == a.name) c.fail("listed twice");
      d.actuated.push_back(std::move(a));
    }
    if (d.actuated.size() < d.commanded.size())
      f["actuated"].fail(fmt::format("{} actuated joints for {} commanded speeds: the actuators cannot produce every generalized "
                                     "force on the commanded speeds (give at least as many actuated joints as commanded speeds)",
                                     d.actuated.size(), d.commanded.size()));
    if (auto w = f.optional("weights")) {
      for (const Item& x : w->list()) {
        const double v = x.number();
        if (!(v > 0)) x.fail(fmt::format("a weight must be positive, got {}", v));
        d.weights.push_back(v);
      }
      if (d.weights.size() != d.actuated.size()) w->fail(fmt::format("one weight per actuated joint: {} needed", d.actuated.size()));
    } else {
      d.weights.assign(d.actuated.size(), 1.0);
    }
    // The actuators' limits, which the contact-keeping torque distribution respects. Bounded like
    // every number a model file gives: 1e9 N m is beyond any machine's drive.
    if (auto l = f.optional("torque_limits")) {
      for (const Item& x : l->list()) {
        const double v = x.number();
        if (!(v > 0 && v <= 1e9)) x.fail(fmt::format("a torque limit must be in (0, 1e9] N m, got {}", v));
        d.torque_limits.push_back(v);
      }
      if (d.torque_limits.size() != d.actuated.size())
        l->fail(fmt::format("one limit per actuator: {} needed", d.actuated.size()));
    } else {
      // Without torque_limits, the joints' efforts (`limits`, a URDF's <limit effort>) and the
      // drives' (their wheel joint's <limit effort>), when every actuator has one.
      std::vector<double> efforts;
      for (const Actuator& a : d.actuated) {
        double e = 0;
        if (a.coordinate >= 0) {
          e = m_.effort[static_cast<std::size_t>(a.coordinate)];
        } else if (const auto u = urdf_axle_.find(m_.wheels[static_cast<std::size_t>(a.wheel)].hub); u != urdf_axle_.end()) {
          if (const auto l = urdf_limits_.find(u->second.joint); l != urdf_limits_.end() && l->second.effort) e = *l->second.effort;
        }
        if (!(e > 0)) break;
        efforts.push_back(e);
      }
      if (efforts.size() == d.actuated.size()) {
        d.torque_limits = std::move(efforts);
        d.torque_limits_from_efforts = true;
      }
    }
    m_.dynamics = std::move(d);
  }

  void clearance(const Item& section) {
    const Fields f(section, {"frame", "size"});
    ClearanceBox box;
    box.frame = m_.frames[static_cast<std::size_t>(frame_index(f["frame"]))].name;
    const Vec3 size = vector3(f["size"]);
    box.size = {size[0], size[1], size[2]};
    m_.clearance = std::move(box);
  }

  // Friction coefficients per kind of contact. Bounded: no ground grips with mu above 10 (rubber on
  // dry concrete is about 1); a coefficient of 0 would make every tangential force a slip.
  void contacts(const Item& section) {
    const Fields f(section, {"friction"});
    const Item friction_item = f["friction"];  // (Fields keeps a reference)
    const Fields friction(friction_item, {"feet", "wheels"});
    for (auto [key, value] : {std::pair{"feet", &m_.friction.feet}, std::pair{"wheels", &m_.friction.wheels}}) {
      const std::optional<Item> item = friction.optional(key);
      if (!item) continue;
      const double mu = item->number();
      if (!(mu > 0 && mu <= 10))
        item->fail(fmt::format("a friction coefficient must be in (0, 10], got {}", mu));
      *value = mu;
    }
  }

  // The inputs' nominal values, and for dependent joints the start of Newton's method (a limb's
  // own `start` takes precedence).
  // The joints' limits: the URDF's <limit>s, then the file's `limits` entries, which replace what
  // they give field by field. A range is checked against nothing else here: the nominal state
  // may lie outside it (the runtime then says so), and Newton's starts are starts.
  void limits(const std::optional<Item>& section) {
    const std::size_t n = m_.coordinates.size();
    const double inf = std::numeric_limits<double>::infinity();
    m_.lower.assign(n, -inf);
    m_.upper.assign(n, inf);
    m_.effort.assign(n, 0.0);
    m_.velocity.assign(n, 0.0);
    for (const auto& entry : urdf_limits_) {
      const std::string& joint = entry.first;
      const UrdfLimit& l = entry.second;
      const auto c = std::find_if(m_.coordinates.begin(), m_.coordinates.end(), [&](const Coordinate& x) { return x.name == joint; });
      if (c == m_.coordinates.end()) continue;  // a wheel's spin: its effort is its drive's (dynamics)
      const auto k = static_cast<std::size_t>(c - m_.coordinates.begin());
      if (l.lower) m_.lower[k] = *l.lower, m_.upper[k] = *l.upper;
      if (l.effort && *l.effort > 0) m_.effort[k] = *l.effort;
      if (l.velocity && *l.velocity > 0) m_.velocity[k] = *l.velocity;
    }
    if (!section) return;
    std::set<int> given;
    each(*section, [&](const Item& it) {
      const Fields f(it, {"joint", "lower", "upper", "effort", "velocity"});
      const int k = coordinate_index(f["joint"]);
      const auto kk = static_cast<std::size_t>(k);
      if (!given.insert(k).second) f["joint"].fail(fmt::format("'{}' has limits already: give them once", m_.coordinates[kk].name));
      const auto lower = f.optional("lower"), upper = f.optional("upper");
      if (lower.has_value() != upper.has_value())
        (lower ? *lower : *upper).fail("a range needs both `lower` and `upper`");
      if (lower) {
        const double lo = lower->number(true), hi = upper->number(true);
        for (const auto& [item, v] : {std::pair{&*lower, lo}, std::pair{&*upper, hi}})
          if (!(std::abs(v) <= 1e6)) item->fail(fmt::format("must be within [-1e6, 1e6], got {}", v));
        if (!(lo < hi)) lower->fail(fmt::format("lower ({}) must be below upper ({})", lo, hi));
        m_.lower[kk] = lo;
        m_.upper[kk] = hi;
      }
      for (const auto& [key, out] : {std::pair{"effort", &m_.effort}, std::pair{"velocity", &m_.velocity}})
        if (auto x = f.optional(key)) {
          const double v = x->number(true);
          if (!(v > 0 && v <= 1e9)) x->fail(fmt::format("must be in (0, 1e9], got {}", v));
          (*out)[kk] = v;
        }
    });
  }

  void nominal(const std::optional<Item>& section) {
    m_.nominal.assign(m_.coordinates.size(), 0.0);
    if (section) {
      if (!section->is_map()) section->fail("must map coordinate names to values");
      for (const auto& kv : section->node()) {
        const Item key(src_, kv.first, section->path(), {});
        const int k = coordinate_index(key);
        if (limb_start_.count(k))
          key.fail(fmt::format("'{}' has a start value in its limb's `start` already: give it once",
                               m_.coordinates[static_cast<std::size_t>(k)].name));
        m_.nominal[static_cast<std::size_t>(k)] = section->child(kv.first.Scalar()).number(true);
      }
    }
    for (const auto& [k, value] : limb_start_) m_.nominal[static_cast<std::size_t>(k)] = value;
  }

  void sweeps(const std::optional<Item>& section) {
    m_.sweep_start.assign(m_.nominal.begin(), m_.nominal.begin() + m_.input_count);
    if (!section) return;
    const Fields f(*section, {"start", "sweeps"});
    if (auto start = f.optional("start")) {
      if (!start->is_map()) start->fail("must map input names to values");
      for (const auto& kv : start->node()) {
        const Item key(src_, kv.first, start->path(), {});
        m_.sweep_start[static_cast<std::size_t>(coordinate_index(key, true))] =
            start->child(kv.first.Scalar()).number(true);
      }
    }
    each(f["sweeps"], [&](const Item& it) {
      const Fields s(it, {"id", "input", "from", "to", "step", "unit", "limb", "branch"});
      IkSweep sw;
      sw.id = s["id"].text();
      for (const auto& other : m_.sweeps)
        if (other.id == sw.id) s["id"].fail(fmt::format("sweep '{}' is defined twice", sw.id));
      sw.input = coordinate_index(s["input"], true);
      double scale = 1;
      if (auto unit = s.optional("unit")) {
        const std::string u = unit->text();
        const std::string& own = m_.coordinates[static_cast<std::size_t>(sw.input)].unit;
        if (u == "deg" && own == "rad") {
          sw.degrees = true;
          scale = std::numbers::pi / 180;
        } else if (u != own) {
          unit->fail(fmt::format("'{}' is in {}; give the sweep in {}{}", m_.coordinates[static_cast<std::size_t>(sw.input)].name, own,
                                 own, own == "rad" ? " or deg" : ""));
        }
      }
      sw.from = s["from"].number(true) * scale;
      sw.to = s["to"].number(true) * scale;
      sw.step = s["step"].number(true) * scale;
      if (!(sw.step > 0)) s["step"].fail("a step must be positive");
      if (std::abs(sw.to - sw.from) / sw.step > 1e6) s["step"].fail("more than 10^6 points");
      const std::string limb = s["limb"].name();
      for (std::size_t k = 0; k < m_.limbs.size(); ++k)
        if (m_.limbs[k].name == limb) sw.limb = static_cast<int>(k);
      if (sw.limb < 0) s["limb"].fail(fmt::format("no limb '{}'", limb));
      // The branch the sweep checks (checked against the closed form's branches at run time, as
      // every branch a file or a request gives: settings).
      if (auto b = s.optional("branch")) {
        const double v = b->number();
        if (!(v >= 0 && v <= 1023 && v == std::floor(v))) b->fail(fmt::format("a branch is a whole number from 0, got {}", v));
        sw.branch = static_cast<int>(v);
      }
      m_.sweeps.push_back(std::move(sw));
    });
  }

  Source src_;
  std::string directory_, urdf_override_, urdf_fingerprint_, urdf_file_;
  struct UrdfAxle {
    Axis axis;
    std::string place, joint;
  };
  std::map<std::string, UrdfAxle> urdf_axle_;  // a wheel's hub link -> its URDF joint's axis
  struct UrdfLimit {
    std::optional<double> lower, upper, effort, velocity;
    std::string place;  // file:line of the <limit>
  };
  std::map<std::string, UrdfLimit> urdf_limits_;  // a URDF joint's name -> its <limit>
  struct UrdfWheelShape {
    std::string radius, offset;  // the parameters with_urdf made from the hub's collision shape
  };
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

}  // namespace

std::string cpp_name_problem(const std::string& name) { return is_identifier(name) ? code_name_reason(name) : "it is not an identifier"; }

std::string model_name_problem(const std::string& name) {
  // The model names namespaces: wlx::<model> (inline), next to the runtime's own.
  static const std::set<std::string> taken = {"wlx", "gen", "detail", "cli", "commands", "report", "text", "dopri", "codegen"};
  if (taken.count(name)) return "wlx and its runtime use that namespace name themselves";
  return cpp_name_problem(name);
}

std::string parameter_value_problem(ParameterKind kind, double value) {
  if ((kind == ParameterKind::length || kind == ParameterKind::mass || kind == ParameterKind::inertia) && !(value > 0))
    return "must be positive";
  if (kind == ParameterKind::gravity && !(value >= 0)) return "must be non-negative";
  return {};
}

std::string did_you_mean(const std::string& name, const std::vector<std::string>& candidates) {
  return suggestion(name, candidates);
}

namespace {

YAML::Node load_yaml(const std::string& text, const std::string& source_name) {
  const Source source{source_name};
  YAML::Node root;
  try {
    std::istringstream stream(text);
    YAML::Parser parser(stream);
    wlx::YamlKeyCheck check([&](const YAML::Mark& mark, const std::string& path, const std::string& reason) {
      source.fail(mark, path, reason);
    });
    parser.HandleNextDocument(check);
    root = YAML::Load(text);
  } catch (const YAML::DeepRecursion& e) {
    // yaml-cpp's own guard (its message is only "bad file"); the check above stops first.
    source.fail(e.mark, "", fmt::format("lists and maps nest more than {} levels deep (the limit)", wlx::YamlKeyCheck::kMaxNesting));
  } catch (const YAML::Exception& e) {
    source.fail(e.mark, "", fmt::format("not valid YAML: {}", e.msg));
  }
  if (!root.IsMap()) throw ModelFileError(fmt::format("{}: the model file must be a YAML map (model:, parameters:, ...)", source_name));
  return root;
}

// The model file, bounded (a regular file of at most kMaxModelFileBytes: /dev/zero, a FIFO or a
// folder is refused at once).
std::string read_text(const std::string& path) {
  const BoundedRead file = read_bounded_file(path, kMaxModelFileBytes);
  if (!file.ok()) {
    const bool opening = file.error.rfind("cannot open", 0) == 0;
    throw ModelFileError(fmt::format("{}: {}", excerpt(path), opening ? "cannot open the model file" + file.error.substr(14)
                                                                      : "the model file " + file.error));
  }
  return file.text;
}

std::string shown_name(const std::string& path) {
  const auto slash = path.find_last_of('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

std::string directory_of(const std::string& path) {
  const auto slash = path.find_last_of('/');
  return slash == std::string::npos ? std::string(".") : path.substr(0, slash + 1);
}

}  // namespace

Model parse_model(const std::string& text, const std::string& source_name, const std::string& directory,
                  const std::string& urdf_path) {
  const YAML::Node root = load_yaml(text, source_name);
  Parser parser(source_name, directory, urdf_path);
  Model m = parser.parse(root);
  m.source = fmt::format("{}, fingerprint {:016x}", source_name, fingerprint(text));
  if (!parser.urdf_fingerprint().empty()) m.source += "; " + parser.urdf_fingerprint();
  if (!parser.urdf_file().empty()) m.input_files.push_back(parser.urdf_file());
  return m;
}

Model load_model_file(const std::string& path, const std::string& urdf_path) {
  Model m = parse_model(read_text(path), shown_name(path), directory_of(path), urdf_path);
  m.input_files.insert(m.input_files.begin(), path);
  return m;
}

std::string print_model_file(const std::string& path, const std::string& urdf_path) {
  const std::string text = read_text(path);
  const std::string name = shown_name(path);
  const Model model = load_model_file(path, urdf_path);  // every check a model file gets
  Parser parser(name, directory_of(path), urdf_path);
  YAML::Node merged = parser.with_urdf(load_yaml(text, name));
  // A wheel's drive named by its URDF joint is written {wheel: NAME, name: JOINT}: without the URDF,
  // the joint's name names nothing.
  if (!parser.urdf_fingerprint().empty() && model.dynamics) {
    YAML::Node actuated(YAML::NodeType::Sequence);
    for (const Actuator& a : model.dynamics->actuated) {
      if (a.wheel < 0) {
        actuated.push_back(a.name);
        continue;
      }
      YAML::Node drive(YAML::NodeType::Map);
      drive.SetStyle(YAML::EmitterStyle::Flow);
      drive["wheel"] = model.wheels[static_cast<std::size_t>(a.wheel)].name;
      drive["name"] = a.name;
      actuated.push_back(drive);
    }
    actuated.SetStyle(YAML::EmitterStyle::Flow);
    merged["dynamics"]["actuated"] = actuated;
    // The drives' efforts come from the URDF's wheel joints, which the printed file does not have.
    if (model.dynamics->torque_limits_from_efforts) {
      YAML::Node limits(YAML::NodeType::Sequence);
      for (double v : model.dynamics->torque_limits) limits.push_back(v);
      limits.SetStyle(YAML::EmitterStyle::Flow);
      merged["dynamics"]["torque_limits"] = limits;
    }
  }
  // The wheels as the model has them: a radius and an offset read from the URDF's collision shapes
  // are parameters of the printed file, which the wheels name.
  if (!parser.urdf_fingerprint().empty() && !model.wheels.empty()) {
    YAML::Node wheels(YAML::NodeType::Sequence);
    for (const NonholonomicWheel& w : model.wheels) {
      YAML::Node e(YAML::NodeType::Map);
      e.SetStyle(YAML::EmitterStyle::Flow);
      e["name"] = w.name;
      const char* axes = "xyz";
      if (!w.hub.empty()) {
        e["hub"] = w.hub;
        e["axle"] = std::string(1, axes[static_cast<int>(w.axle)]);
        if (w.contact != "contact_" + w.name) e["contact"] = w.contact;
      } else {
        e["contact"] = w.contact;
        e["forward"] = std::string(1, axes[static_cast<int>(w.forward)]);
        e["lateral"] = std::string(1, axes[static_cast<int>(w.lateral)]);
      }
      e["radius"] = w.radius;
      if (!w.offset.empty()) e["offset"] = w.offset;
      e["ground"] = model.coordinates[static_cast<std::size_t>(w.ground)].name;
      wheels.push_back(e);
    }
    merged["wheels"] = wheels;
  }
  // The joints' limits as the model has them (the URDF's <limit>s with the file's entries).
  if (!parser.urdf_fingerprint().empty()) {
    YAML::Node limits(YAML::NodeType::Sequence);
    for (std::size_t k = 0; k < model.coordinates.size(); ++k) {
      YAML::Node l(YAML::NodeType::Map);
      l.SetStyle(YAML::EmitterStyle::Flow);
      if (!std::isinf(model.lower[k])) l["lower"] = model.lower[k], l["upper"] = model.upper[k];
      if (model.effort[k] > 0) l["effort"] = model.effort[k];
      if (model.velocity[k] > 0) l["velocity"] = model.velocity[k];
      if (l.size() == 0) continue;
      YAML::Node entry(YAML::NodeType::Map);
      entry.SetStyle(YAML::EmitterStyle::Flow);
      entry["joint"] = model.coordinates[k].name;
      for (const auto& kv : l) entry[kv.first] = kv.second;
      limits.push_back(entry);
    }
    if (limits.size() > 0) merged["limits"] = limits;
  }
  YAML::Emitter out;
  out << merged;
  return fmt::format("# The model wlx-gen reads from {}{} (wlx-gen --print-model){}.\n{}\n", name,
                     parser.urdf_fingerprint().empty() ? "" : " and its URDF",
                     parser.urdf_fingerprint().empty() ? "" : ", written as a model file that needs no URDF", out.c_str());
}

}  // namespace wlx::codegen
