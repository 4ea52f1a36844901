// The facts about a model's structure that structure.hpp states, worked out from the model as data
// (structure_facts.cpp), so that emit_structure.cpp only prints them and looks nothing up.
#pragma once

#include "emit.hpp"

#include <cstddef>
#include <vector>

namespace wlx::codegen {

struct StructureFacts {
  // Per frame, in frame:: order: its parent (-1: the ground frame K0), and whether wlx-gen derived
  // it (a wheel's contact point).
  std::vector<int> frame_parents;
  std::vector<bool> frame_derived;
  // Per limb, the inputs its closure rows read; the most rows and inputs of a limb (at least 1, the
  // size of the tables' arrays).
  std::vector<std::vector<int>> limb_inputs;
  std::size_t max_limb_size = 1, max_limb_inputs = 1;
  // Per wheel, its contact frame's index and its hub frame's (-1: none).
  std::vector<int> wheel_contact_frames, wheel_hub_frames;
  // The dependent pairs (a model without wheels has one, of no rates), the default one's index and
  // the inverse dynamics' (0 when not found).
  std::vector<DependentPair> pairs;
  int default_pair = 0, dynamics_pair = 0;
  // Per coordinate, the commanded speeds its rate can depend on (rate_basis_pattern, ascending).
  std::vector<std::vector<int>> rate_basis;
  // Per body, the coordinates its velocity Jacobians have a nonzero column for; per wheel, those its
  // drive row can depend on (none for a wheel without a drive); the most of either (at least 1).
  std::vector<std::vector<int>> body_columns, drive_columns;
  std::size_t max_columns = 1;
  // Per closure row, the index of the frame it constrains (-1: none).
  std::vector<int> closure_frames;
  std::vector<GroundContact> contacts;
  int clearance_frame = -1;  // the frame the clearance box moves with (-1: none)
};

StructureFacts structure_facts(const Model& m);

}  // namespace wlx::codegen
