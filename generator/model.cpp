#include "model.hpp"

#include <stdexcept>

namespace wlx::codegen {

const char* kind_name(ParameterKind kind) noexcept {
  switch (kind) {
    case ParameterKind::length: return "length";
    case ParameterKind::offset: return "offset";
    case ParameterKind::angle: return "angle";
    case ParameterKind::mass: return "mass";
    case ParameterKind::inertia: return "inertia";
    case ParameterKind::gravity: return "gravity";
    case ParameterKind::other: return "other";
  }
  return "other";
}

const Parameter& Model::parameter(const std::string& n) const {
  for (const auto& p : parameters)
    if (p.name == n) return p;
  throw std::out_of_range("model has no parameter '" + n + "'");
}

const Coordinate& Model::coordinate(const std::string& n) const {
  for (const auto& c : coordinates)
    if (c.name == n) return c;
  throw std::out_of_range("model has no coordinate '" + n + "'");
}

int Model::frame_index(const std::string& n) const {
  for (std::size_t k = 0; k < frames.size(); ++k)
    if (frames[k].name == n) return static_cast<int>(k);
  return -1;
}

const Frame& Model::frame(const std::string& n) const {
  const int k = frame_index(n);
  if (k < 0) throw std::out_of_range("model has no frame '" + n + "'");
  return frames[static_cast<std::size_t>(k)].frame;
}

const DependentPair& Model::pair(const std::string& n) const {
  for (const auto& p : pairs)
    if (p.name == n) return p;
  throw std::out_of_range("model has no dependent pair '" + n + "'");
}

}  // namespace wlx::codegen
