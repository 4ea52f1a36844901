// The Python module wlx._wlx: wlx.Error, the built-in models (the registry the wlx program uses),
// and load(), a user's model file compiled into a plugin on first use (cli/shell/model_plugin.hpp)
// and loaded like `wlx --model-file` loads it. Every model is reached through its ModelApi
// (cli/shell/model_api.hpp): this file names no model and compiles once.
#include "commands.hpp"
#include "model_api.hpp"
#include "model_plugin.hpp"

#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <wlx/error.hpp>

#include <dlfcn.h>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#ifndef WLX_VERSION
#error "CMakeLists.txt defines WLX_VERSION"
#endif

namespace py = pybind11;

namespace {

using wlx::Error;
using wlx::cli::ModelApi;

// One model's computations, with its tables parsed once.
struct ModelHandle {
  const ModelApi* api = nullptr;
  py::dict info;
  long actuators = 0, coordinates = 0, frames = 0, commanded = 0;
};

// The model at one set of parameters with its Data (ModelApi::new_workspace), for the calls
// without JSON: made once per parameters by wlx.Model, freed with it.
struct Workspace {
  const ModelApi* api;
  void* data;
  Workspace(const ModelApi* a, void* d) : api(a), data(d) {}
  Workspace(const Workspace&) = delete;
  Workspace& operator=(const Workspace&) = delete;
  ~Workspace() { api->delete_workspace(data); }
};

using Array = py::array_t<double, py::array::c_style | py::array::forcecast>;

// The rows of a state array (one state, or count x n), checked against the model's n ("has 3
// entries; the model has 32 coordinates", as the single-state calls say).
long rows_of(const Array& a, long n, const char* field, const char* what) {
  if (a.ndim() == 1 && a.shape(0) == n) return 1;
  if (a.ndim() == 2 && a.shape(1) == n) return static_cast<long>(a.shape(0));
  if (a.ndim() == 1)
    throw Error(field, "has " + std::to_string(a.shape(0)) + " entries; the model has " + std::to_string(n) + " " + what);
  if (a.ndim() == 2)
    throw Error(field, "has rows of " + std::to_string(a.shape(1)) + " entries; the model has " + std::to_string(n) + " " + what);
  throw Error(field, "must be one state or an array of rows, one state a row (" + std::to_string(a.ndim()) + " dimensions given)");
}
// An output of `rows` rows of `shape` (none but the shape for a single state).
Array output(long rows, bool single, std::vector<py::ssize_t> shape) {
  if (!single) shape.insert(shape.begin(), rows);
  return Array(shape);
}

ModelHandle handle_of(const wlx::cli::ModelCommands& commands) {
  if (commands.api == nullptr) throw Error("model", std::string(commands.name) + " has no computations for Python");
  ModelHandle h;
  h.api = commands.api;
  h.info = py::module_::import("json").attr("loads")(commands.api->info());
  h.actuators = static_cast<long>(py::len(h.info["actuators"]));
  h.coordinates = static_cast<long>(py::len(h.info["coordinates"]));
  h.frames = static_cast<long>(py::len(h.info["frames"]));
  h.commanded = static_cast<long>(py::len(h.info["commanded"]));
  return h;
}

std::filesystem::path this_module() {
  Dl_info info{};
  if (::dladdr(reinterpret_cast<void*>(&this_module), &info) == 0 || info.dli_fname == nullptr) return {};
  return std::filesystem::path(info.dli_fname);
}

// A model file's plugin resolves the shell's functions (bounded input, output checks, the report's
// writers) from the program that loads it, as the wlx program exports them. Python loads this
// module privately (RTLD_LOCAL); before the first plugin, it is made global, which it then stays.
// The plugin binds its own calls to itself (-Bsymbolic), so a built-in model of the same name here
// is never called by it.
void export_shell_to_plugins() {
  static bool done = false;
  if (done) return;
  const std::filesystem::path self = this_module();
  if (self.empty() || ::dlopen(self.c_str(), RTLD_NOW | RTLD_NOLOAD | RTLD_GLOBAL) == nullptr) {
    const char* why = ::dlerror();  // once: a second call returns null
    throw Error("load", "cannot make wlx's module visible to a model's plugin (" + std::string(why != nullptr ? why : "dladdr found no file") + ")");
  }
  // wlx-gen and the sources: beside an installed module's bin folder, else this build's.
  std::error_code ec;
  const std::filesystem::path installed = (self.parent_path() / WLX_BIN_FROM_PYTHON_MODULE).lexically_normal();
  wlx::cli::set_plugin_host_bin_dir(std::filesystem::is_regular_file(installed / "wlx-gen", ec) ? installed.string()
                                                                                              : std::string(WLX_BUILD_BIN_DIR));
  done = true;
}

py::dict to_dict(const wlx::cli::NamedArrays& arrays) {
  py::dict out;
  for (const auto& a : arrays) out[py::str(a.name)] = a.is_vector ? py::object(py::cast(Eigen::VectorXd(a.value.col(0)))) : py::object(py::cast(a.value));
  return out;
}

}  // namespace

PYBIND11_MODULE(_wlx, m) {
  m.doc() = "wlx's C++ core; use the package wlx";
  // wlx.Error: a ValueError with the message, and `kind`, what kind of failure it is ("out-of-reach",
  // "singular", "contact", "limit" or "other": wlx::error_kind_name), so that a program acts on the
  // kind rather than on the words.
  static py::exception<Error> error_type(m, "Error", PyExc_ValueError);
  error_type.attr("kind") = "other";
  py::register_exception_translator([](std::exception_ptr thrown) {
    try {
      if (thrown) std::rethrow_exception(thrown);
    } catch (const Error& e) {
      py::object instance = py::handle(error_type.ptr())(e.what());  // an instance, to carry the kind
      instance.attr("kind") = wlx::error_kind_name(e.kind());
      PyErr_SetObject(error_type.ptr(), instance.ptr());
    }
  });

  py::class_<Workspace>(m, "Workspace", "The model at one set of parameters, with its working memory (use wlx.Model)");

  py::class_<ModelHandle>(m, "ModelHandle", "One model's computations (use wlx.Model)")
      .def("workspace",
           [](const ModelHandle& h, const std::string& params_json) { return std::make_unique<Workspace>(h.api, h.api->new_workspace(params_json)); },
           "workspace(params_json) -> the model at these parameters, for fk_many and inverse_dynamics_many")
      .def("fk_many",
           [](const ModelHandle& h, Workspace& w, const Array& s) {
             const long rows = rows_of(s, h.coordinates, "s", "coordinates");
             const bool single = s.ndim() == 1;
             Array positions = output(rows, single, {h.frames, 3}), rotations = output(rows, single, {h.frames, 3, 3});
             h.api->fk_many(w.data, s.data(), rows, positions.mutable_data(), rotations.mutable_data());
             // Each matrix was written by columns: the view with its last two axes swapped is it.
             return py::make_tuple(positions, rotations.attr("swapaxes")(-1, -2));
           },
           "fk_many(workspace, s) -> (positions, rotations): s one state or rows of states; (frames x 3, frames x 3 x 3) per state")
      .def("inverse_dynamics_many",
           [](const ModelHandle& h, Workspace& w, const Array& s, const Array& u, const Array& u_dot, const std::string& weighting_json) {
             const long rows = rows_of(s, h.coordinates, "s", "coordinates");
             if (rows_of(u, h.commanded, "u", "commanded speeds") != rows || rows_of(u_dot, h.commanded, "u_dot", "commanded speeds") != rows ||
                 u.ndim() != s.ndim() || u_dot.ndim() != s.ndim())
               throw Error("u", "s, u and u_dot must have as many rows (one state a row)");
             const bool single = s.ndim() == 1;
             Array tau = output(rows, single, {h.actuators}), qstar = output(rows, single, {h.commanded});
             h.api->inverse_dynamics_many(w.data, weighting_json, s.data(), u.data(), u_dot.data(), rows, tau.mutable_data(),
                                          qstar.mutable_data());
             return py::make_tuple(tau, qstar);
           },
           "inverse_dynamics_many(workspace, s, u, u_dot, weighting_json) -> (tau, Qstar), a row per state")
      .def_property_readonly("info", [](const ModelHandle& h) { return h.info; })
      .def("ik",
           [](const ModelHandle& h, const std::string& request_json) {
             auto [s, answer] = h.api->ik(request_json);
             return py::make_tuple(s, answer);
           },
           "ik(request_json) -> (s, result_json): what `wlx ik` answers for that request, and all coordinates")
      .def("fk",
           [](const ModelHandle& h, const Eigen::VectorXd& s, const std::string& params_json) {
             auto [positions, rotations] = h.api->fk(s, params_json);
             py::list r;
             for (const auto& R : rotations) r.append(R);
             return py::make_tuple(positions, r);
           },
           "fk(s, params_json) -> (positions (frames x 3), [rotation 3 x 3 per frame])")
      .def("dependent_rates",
           [](const ModelHandle& h, const Eigen::VectorXd& s, const Eigen::VectorXd& rates, const std::vector<std::string>& pair,
              const std::string& params_json) {
             auto [sdot, cond] = h.api->dependent_rates(s, rates, pair, params_json);
             return py::make_tuple(sdot, cond);
           },
           "dependent_rates(s, input_rates, pair, params_json) -> (sdot, cond_J_beta)")
      .def("inverse_dynamics",
           [](const ModelHandle& h, const Eigen::VectorXd& s, const Eigen::VectorXd& u, const Eigen::VectorXd& u_dot,
              const std::string& params_json, const std::string& weighting_json) {
             return to_dict(h.api->inverse_dynamics(s, u, u_dot, params_json, weighting_json));
           },
           "inverse_dynamics(s, u, u_dot, params_json, weighting_json) -> dict tau, Qstar, M, b, Q_gravity, J_beta, sdot")
      .def("forward_dynamics",
           [](const ModelHandle& h, const Eigen::VectorXd& s, const Eigen::VectorXd& u, const Eigen::VectorXd& tau,
              const std::string& params_json) { return to_dict(h.api->forward_dynamics(s, u, tau, params_json)); },
           "forward_dynamics(s, u, tau, params_json) -> dict u_dot, sddot, sdot, Qstar (= J_beta^T tau), M")
      .def(
          "simulate",
          [](const ModelHandle& h, const std::string& scenario_json, const std::string& params_json, long every, const py::object& torques) {
            // A Python function as the torque source: a controller in the loop, called at every
            // evaluation of the right-hand side. Its own exceptions reach the caller unchanged; a
            // result of the wrong shape is a TypeError, not a stopped run.
            wlx::cli::TorqueFunction function;
            if (!torques.is_none()) {
              if (!PyCallable_Check(torques.ptr())) throw Error("torques", "must be a function f(t, s, u) -> tau, or None");
              function = [f = py::function(torques), n = h.actuators](double t, const Eigen::VectorXd& s, const Eigen::VectorXd& u) {
                const py::object r = f(t, s, u);
                Eigen::VectorXd tau;
                try {
                  tau = r.cast<Eigen::VectorXd>();
                } catch (const py::cast_error&) {
                  throw py::type_error("torques: the function must return " + std::to_string(n) +
                                       " numbers (the order of .actuators), got " + std::string(py::str(py::type::of(r))));
                }
                if (tau.size() != n)
                  throw py::type_error("torques: the function returned " + std::to_string(tau.size()) + " numbers; the model has " +
                                       std::to_string(n) + " actuators (.actuators)");
                return tau;
              };
            }
            // The columns are written as the run streams its samples (no table, no copy), and
            // bounded: beyond kMaxSimulateBytes an error before anything is allocated, where
            // `wlx simulate` streams any length to a file.
            std::vector<std::string> names;
            std::vector<py::array_t<double>> columns;
            wlx::cli::SimulationSink sink;
            sink.begin = [&](const std::vector<std::string>& header, long kept) {
              constexpr double kMaxSimulateBytes = 256.0 * 1024 * 1024;
              const double bytes = static_cast<double>(kept) * static_cast<double>(header.size()) * sizeof(double);
              if (bytes > kMaxSimulateBytes)
                throw Error("every", "the run would keep " + std::to_string(kept) + " samples of " + std::to_string(header.size()) +
                                         " columns (" + std::to_string(static_cast<long>(bytes / (1024 * 1024))) +
                                         " MiB, more than 256 MiB): keep every k-th sample (every=k), shorten the run, or stream it "
                                         "to a file with `wlx simulate`");
              names = header;
              columns.reserve(header.size());
              for (std::size_t c = 0; c < header.size(); ++c) columns.emplace_back(kept);
            };
            sink.row = [&](long row, const std::vector<double>& values) {
              for (std::size_t c = 0; c < values.size() && c < columns.size(); ++c) columns[c].mutable_at(row) = values[c];
            };
            // Ctrl-C during a long run: Python's handler runs here (the GIL is held), and its
            // KeyboardInterrupt ends the run at the next sample, microseconds later.
            sink.poll = [] {
              if (PyErr_CheckSignals() != 0) throw py::error_already_set();
            };
            const wlx::cli::SimulationOutcome run = h.api->simulate(scenario_json, params_json, every, std::move(function), sink);
            py::dict out_columns;
            for (std::size_t c = 0; c < columns.size(); ++c) {
              columns[c].resize({run.rows}, false);  // a run that stopped early: only its samples
              out_columns[py::str(names[c])] = columns[c];
            }
            py::dict out;
            out["columns"] = out_columns;
            out["id"] = run.id;
            out["complete"] = run.complete;
            out["stopped"] = run.stopped;
            out["stop_kind"] = run.stop_kind;
            out["summary"] = to_dict(run.summary);
            out["evaluations"] = run.evaluations;
            return out;
          },
          py::arg("scenario_json"), py::arg("params_json") = "{}", py::arg("every") = 1, py::arg("torques") = py::none(),
          "simulate(scenario_json, params_json=\"{}\", every=1, torques=None) -> dict: columns (the CSV's, as arrays; every k-th sample), complete, "
          "stopped (why, if early), stop_kind (what kind of failure: wlx.Error's kinds), summary (over all samples: "
          "peak_cond_J_beta, min_clearance, peak_tau, rms_tau, each where the run has it); torques: a function f(t, s, u) -> tau driving the run");

  py::list models;
  for (const auto& c : wlx::cli::models()) models.append(std::string(c.name));
  m.attr("models") = models;
  m.def(
      "model",
      [](const std::string& name) {
        for (const auto& c : wlx::cli::models())
          if (c.name == name) return handle_of(c);
        throw Error("model", "unknown model '" + name + "'");
      },
      "model(name) -> the built-in model's computations");
  m.def(
      "load",
      [](const std::string& path) {
        export_shell_to_plugins();
        try {
          const wlx::cli::ModelCommands* commands = nullptr;
          {
            // A first use compiles for half a minute: other Python threads run meanwhile.
            py::gil_scoped_release unlocked;
            commands = &wlx::cli::load_model_file(path, WLX_VERSION);
          }
          return handle_of(*commands);
        } catch (const Error& e) {  // the command line's option is Python's argument here
          if (e.field() == "--model-file") throw Error("load", e.reason());
          throw;
        }
      },
      "load(path) -> the computations of the model in a model file (compiled on first use, then cached)");
  m.attr("version") = WLX_VERSION;
}
