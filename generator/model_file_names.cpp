// The names a model file may give (each reaches the generated C++: not a keyword, a macro, std or
// Eigen, nor a name the generated functions use themselves), and the "did you mean" of messages.
#include "model_file_internal.hpp"

#include <algorithm>
#include <cctype>
#include <set>

namespace wlx::codegen {

namespace model_file_detail {

std::string suggestion(const std::string& name, const std::vector<std::string>& candidates) {
  const std::string best = text::nearest(name, candidates, false);
  return best.empty() ? "" : fmt::format(" (did you mean '{}'?)", best);
}

bool is_identifier(const std::string& s) {
  if (s.empty() || !(std::isalpha(static_cast<unsigned char>(s[0])) || s[0] == '_')) return false;
  return std::all_of(s.begin(), s.end(), [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; });
}

namespace {

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

}  // namespace

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

}  // namespace model_file_detail

using model_file_detail::code_name_reason;
using model_file_detail::is_identifier;

std::string cpp_name_problem(const std::string& name) { return is_identifier(name) ? code_name_reason(name) : "it is not an identifier"; }

std::string model_name_problem(const std::string& name) {
  // The model names namespaces: wlx::<model> (inline), next to the runtime's own.
  static const std::set<std::string> taken = {"wlx", "gen", "detail", "cli", "commands", "report", "text", "dopri", "codegen"};
  if (taken.count(name)) return "wlx and its runtime use that namespace name themselves";
  return cpp_name_problem(name);
}

std::string did_you_mean(const std::string& name, const std::vector<std::string>& candidates) {
  return model_file_detail::suggestion(name, candidates);
}

}  // namespace wlx::codegen
