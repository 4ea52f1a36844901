// Emission of header-only C++ (Eigen fixed-size types only) from derived functions.
#pragma once

#include "derivations.hpp"
#include "expr_graph.hpp"

#include <map>
#include <string>
#include <utility>
#include <vector>

namespace wlx::codegen {

struct EmitOptions {
  std::string generator_version;
  // C++ namespace of the emitted code. Empty: wlx::<model>::gen, with <model> an inline namespace,
  // so that code using one model may write wlx::gen:: and code using several names the model.
  std::string name_space;
  std::string model_name;  // set from the model
  // Parameters replaced by numeric constants (name -> value); empty: all read from Params.
  std::map<std::string, double> baked;
  // The model file's numbers (parameters' values, nominal state, Newton's starts, IK sweeps,
  // weights, torque limits, friction) left out of the code: the headers then depend on the model's
  // structure alone, and a plugin reads the numbers from model.json at run time, so that editing
  // them compiles nothing (wlx --model-file). Off: they are compiled in (settings.hpp), for embedding.
  bool data_at_run_time = false;
};

struct FunctionStats {
  std::string name;
  int intermediates = 0;
  OpCount before_cse;  // the outputs as trees, without any sharing
  OpCount after_cse;   // what the emitted code evaluates (all outputs requested)
  double seconds = 0;  // derivation + CSE + printing
};

struct EmittedFile {
  std::string path;  // relative to the output root, e.g. "wlx/gen/closure.hpp"
  std::string text;
};

// The banner every emitted header opens with (what it is, by what, from what, do not edit).
std::string banner(const Model& m, const EmitOptions& opt, const std::string& what);
std::string namespace_open(const EmitOptions& opt);
std::string namespace_close(const EmitOptions& opt);
// Text as a C++ string literal, quotes included (", \ and anything outside printable ASCII escaped).
std::string quoted(const std::string& text);
// Text for a // or /* */ comment of a generated header (wlx::text::cpp_comment).
std::string comment(const std::string& text);
// A double as a C++ literal that round-trips exactly (always with a '.', 'e' or "nan"/"inf").
std::string literal(double v);

// trig.hpp: sin and cos of a fixed-size array of angles in one branch-free SIMD pass.
EmittedFile emit_trig_header(const Model& m, const EmitOptions& opt);
// Headers describing the model itself: parameters and coordinate/frame/body names and types.
std::vector<EmittedFile> emit_model_headers(const Model& m, const EmitOptions& opt);
// Contacts with the ground: every frame that closure rows tie to K0 (point rows carry a force,
// level rows a moment) and every wheel's contact frame (its rolling row carries the lateral
// force, its drive the longitudinal one), in the order of the generated kContacts.
struct GroundContact {
  std::string name;  // in output columns: the frame's name without underscores, unless two collide
  int frame = -1;
  int wheel = -1;  // -1: a foot
  std::array<int, 3> point{-1, -1, -1}, level{-1, -1, -1};  // closure rows (-1: none)
  double friction = 0;  // the model file's contacts.friction for its kind
};
std::vector<GroundContact> ground_contacts(const Model& m);

// structure.hpp: every fact about the model's structure the runtime needs, as constexpr tables
// (limbs, wheels, dependent pairs, inverse-dynamics set-up, body Jacobian columns, contacts).
EmittedFile emit_structure_header(const Model& m, const EmitOptions& opt);
// settings.hpp: the model file's run-time settings compiled in (nominal state, Newton's starts, IK
// sweeps, weights, torque limits, friction); written unless opt.data_at_run_time (then model.json
// alone holds them).
EmittedFile emit_settings_header(const Model& m, const EmitOptions& opt);
// model.json: the description of the model as data (docs/model-format.md, "The description"):
// its names and structure, and every number of the model file that no generated function holds
// (parameters' values, nominal state, starts, sweeps, weights, torque limits, friction), with
// `code_key`, a fingerprint of the code (every other emitted file), which a plugin's cache is keyed by.
EmittedFile emit_description(const Model& m, const EmitOptions& opt, const std::vector<EmittedFile>& code);
// ik.hpp: the closed-form inverse kinematics of every limb whose chain matches one of the solvable
// patterns (ik_patterns.cpp documents them), with all its branches; `report` receives one line per
// limb: the pattern used, or why none applies (that limb is then left to Newton's method).
EmittedFile emit_ik_header(const Model& m, const EmitOptions& opt, std::vector<std::string>& report);
// The chain from K0 to `frame` from its first dependent joint on, in the canonical form the IK
// patterns match on (ik_chains.cpp): per gap between joints one translation (if any) then the turns,
// offsets slid along the joint axes they commute with, identities dropped. The steps before the
// first dependent joint are left out (they stay as written).
std::vector<ChainStep> canonical_ik_chain(const Model& m, const std::string& frame);
// The double overload of the function template `name` (parameters: declaration and default value,
// each): it calls name<double>(), or on x86-64 with GCC or clang its AVX2 + FMA build when the CPU
// has those (types.hpp: WLX_GEN_MULTIVERSION). `why`: what the overload is for, in its comment.
// In the model's own namespace it is only declared where WLX_GEN_COMPILED_<model> is defined (a
// library compiles it once, types.hpp).
std::string double_overload(const EmitOptions& opt, const std::string& name, const std::string& result,
                            const std::vector<std::pair<std::string, std::string>>& parameters, const std::string& why);
// One header per derived function; `stats` receives the numbers written into its banner.
EmittedFile emit_function(const Model& m, const FunctionSpec& fn, const EmitOptions& opt, FunctionStats& stats);
// The umbrella header including everything, with the operation-count table.
EmittedFile emit_umbrella(const Model& m, const std::vector<FunctionSpec>& fns,
                          const std::vector<FunctionStats>& stats, const EmitOptions& opt);

}  // namespace wlx::codegen
