// The IK patterns' view of a chain: the steps from K0 to a frame, and their canonical form, which
// the patterns (ik_patterns.cpp) match on and `wlx-gen --describe` shows (canonical_ik_chain).
#include "emit.hpp"
#include "ik_internal.hpp"

#include <fmt/format.h>

#include <cmath>
#include <sstream>

namespace wlx::codegen {

namespace ik {

std::vector<ChainStep> full_chain(const Model& m, const std::string& frame) {
  std::vector<const NamedFrame*> path;
  for (std::string f = frame; f != "K0";) {
    const NamedFrame& nf = m.frames[static_cast<std::size_t>(m.frame_index(f))];
    path.push_back(&nf);
    f = nf.parent;
  }
  std::vector<ChainStep> out;
  for (auto it = path.rbegin(); it != path.rend(); ++it) out.insert(out.end(), (*it)->chain.begin(), (*it)->chain.end());
  return out;
}

Frame apply(const Model& m, const Frame& f, const ChainStep& st) {
  switch (st.kind) {
    case ChainStep::Kind::Translate: return f.translated(st.offset);
    case ChainStep::Kind::Rotate: return f.rotated(st.axis, m.coordinates[static_cast<std::size_t>(st.coordinate)], st.sign);
    case ChainStep::Kind::Slide: return f.slid(st.axis, m.coordinates[static_cast<std::size_t>(st.coordinate)], st.sign);
    case ChainStep::Kind::Turn: return f.turned(st.axis, st.angle);
  }
  return f;
}

bool driven(const ChainStep& st) { return st.kind == ChainStep::Kind::Rotate || st.kind == ChainStep::Kind::Slide; }

void require_plain_chain(const Model& m, const std::string& frame, const std::vector<ChainStep>& chain, const char* pattern) {
  if (wheel_of_contact(m, frame) != nullptr)
    throw Unsolvable{std::string(pattern) + ": " + frame + " is a wheel's derived contact point"};
  for (const ChainStep& st : chain)
    if (driven(st) && st.sign < 0)
      throw Unsolvable{std::string(pattern) + ": " + m.coordinates[static_cast<std::size_t>(st.coordinate)].name +
                       " turns about a negative axis"};
}

std::vector<Rot> merge(const std::vector<Rot>& seq) {
  std::vector<Rot> out;
  for (const Rot& r : seq) {
    if (!out.empty() && out.back().axis == r.axis) out.back().angle = (out.back().angle + r.angle).expand();
    else out.push_back({r.axis, r.angle.expand()});
    if (out.back().angle.is_zero()) out.pop_back();
  }
  return out;
}

Mat3 product(const std::vector<Rot>& seq) {
  Mat3 R = Mat3::identity();
  for (const Rot& r : seq) R = R * rot(r.axis, r.angle);
  return R;
}

// ---- canonical chains ---------------------------------------------------------------------------
//
// The patterns test geometry (do two axes meet, are they parallel), not the wording of the file:
// before matching, a chain is brought to a canonical form. From the first dependent joint on, the
// fixed steps between consecutive joints become one rigid transform (an offset, then the turns),
// with consecutive translations added up, consecutive turns about one axis merged and zero offsets
// and zero turns dropped. Then every offset's component along the axis of the joint just before it
// slides to before that joint (a translation along a joint's axis commutes with the joint), from
// the last joint to the first, so that offsets gather as near the root as they can; and turns about
// that joint's axis right after it (with no offset left in front of them) slide before it too.
// `translate: [0, 0, 0]` between two joints, a translation split over two steps, a hub offset
// written along the knee axis after the knee: all give the same canonical chain.

bool identically_zero(const ex& e) { return e.expand().is_zero(); }
bool identically_zero(const Vec3& v) { return identically_zero(v[0]) && identically_zero(v[1]) && identically_zero(v[2]); }

double at_defaults(const Model& m, const ex& e) {
  GiNaC::lst values;
  for (const Parameter& p : m.parameters) values.append(p.symbol == p.default_value);
  const ex v = GiNaC::evalf(e.subs(values));
  return GiNaC::is_a<GiNaC::numeric>(v) ? GiNaC::ex_to<GiNaC::numeric>(v).to_double() : std::nan("");
}

Vec3 expanded(const Vec3& v) { return {v[0].expand(), v[1].expand(), v[2].expand()}; }

CanonicalChain canonical_chain(const Model& m, const std::vector<ChainStep>& chain) {
  CanonicalChain c;
  std::size_t first = 0;
  while (first < chain.size() && !(driven(chain[first]) && chain[first].coordinate >= m.input_count)) ++first;
  c.prefix.assign(chain.begin(), chain.begin() + static_cast<std::ptrdiff_t>(first));
  c.fixed.emplace_back();
  for (std::size_t i = first; i < chain.size(); ++i) {
    const ChainStep& st = chain[i];
    Rigid& r = c.fixed.back();
    if (driven(st)) {
      c.joints.push_back(st);
      c.fixed.emplace_back();
    } else if (st.kind == ChainStep::Kind::Translate) {
      r.offset = expanded(r.offset + product(r.turns) * st.offset);  // T(o) R T(v) = T(o + R v) R
    } else {
      r.turns.push_back({st.axis, st.angle});
      r.turns = merge(r.turns);
    }
  }
  for (std::size_t k = c.joints.size(); k-- > 0;) {
    const ChainStep& j = c.joints[k];
    if (j.coordinate < m.input_count) continue;  // the base's own steps stay as written
    const int a = static_cast<int>(j.axis);
    Rigid &before = c.fixed[k], &after = c.fixed[k + 1];
    if (!identically_zero(after.offset[a])) {
      before.offset = expanded(before.offset + product(before.turns) * (after.offset[a] * unit(j.axis)));
      after.offset[a] = 0;
    }
    if (j.kind == ChainStep::Kind::Rotate && identically_zero(after.offset))
      while (!after.turns.empty() && after.turns.front().axis == j.axis) {
        before.turns.push_back(after.turns.front());
        before.turns = merge(before.turns);
        after.turns.erase(after.turns.begin());
      }
  }
  return c;
}

namespace {

Frame apply_rigid(const Frame& f, const Rigid& r) {
  Frame out = identically_zero(r.offset) ? f : f.translated(r.offset);
  for (const Rot& t : r.turns) out = out.turned(t.axis, t.angle);
  return out;
}

}  // namespace

Frame base_frame(const Model& m, const CanonicalChain& c) {
  Frame base = Frame::ground();
  for (const ChainStep& st : c.prefix) base = apply(m, base, st);
  return apply_rigid(base, c.fixed[0]);
}

std::string describe(const Rigid& r) {
  std::vector<std::string> parts;
  if (!identically_zero(r.offset)) {
    std::ostringstream o;
    o << "translate [" << r.offset[0] << ", " << r.offset[1] << ", " << r.offset[2] << "]";
    parts.push_back(o.str());
  }
  for (const Rot& t : r.turns) {
    std::ostringstream o;
    o << "r" << axis_name(t.axis) << ": " << t.angle;
    parts.push_back(o.str());
  }
  return parts.empty() ? "nothing" : fmt::format("{}", fmt::join(parts, ", "));
}

}  // namespace ik

std::vector<ChainStep> canonical_ik_chain(const Model& m, const std::string& frame) {
  using namespace ik;
  const CanonicalChain c = canonical_chain(m, full_chain(m, frame));
  std::vector<ChainStep> out;
  const auto fixed = [&](const Rigid& r) {
    if (!identically_zero(r.offset)) {
      ChainStep st;
      st.kind = ChainStep::Kind::Translate;
      st.offset = r.offset;
      out.push_back(st);
    }
    for (const Rot& t : r.turns) {
      ChainStep st;
      st.kind = ChainStep::Kind::Turn;
      st.axis = t.axis;
      st.angle = t.angle;
      out.push_back(st);
    }
  };
  for (std::size_t k = 0; k < c.joints.size(); ++k) {
    fixed(c.fixed[k]);
    out.push_back(c.joints[k]);
  }
  fixed(c.fixed.back());
  return out;
}

}  // namespace wlx::codegen
