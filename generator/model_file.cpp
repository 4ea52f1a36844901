// Reading a model file as a whole: the YAML document (its keys checked, its size bounded), the
// parser's order of sections, and the public entries (parse_model, load_model_file,
// print_model_file).
#include "model_file_internal.hpp"

#include <yaml-cpp/depthguard.h>
#include <yaml-cpp/eventhandler.h>
#include <wlx/support/bounded_file.hpp>
#include <wlx/support/yaml_key_check.hpp>

#include <cmath>
#include <sstream>

namespace wlx::codegen {

namespace model_file_detail {

Model Parser::parse(const YAML::Node& file_root) {
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

}  // namespace model_file_detail

using model_file_detail::excerpt;
using model_file_detail::fingerprint;
using model_file_detail::Parser;
using model_file_detail::Source;

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
