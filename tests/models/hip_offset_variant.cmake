# Writes OUT: models/excavator.yaml (IN) as a user would edit it to lower the front hips by a
# height offset: a parameter hip_z (kind offset, default -0.2 m) and the hips' translation using
# it, under the model name excavator_hip. Fails if the text it edits is not found.
file(READ "${IN}" text)
foreach(anchor "model: excavator\n" "  - {name: w, value: 0.5," "chain: [translate: [cxd/2, <sign>*cyd/2, 0], rx: psi_<side>1")
  string(FIND "${text}" "${anchor}" at)
  if(at EQUAL -1)
    message(FATAL_ERROR "hip_offset_variant.cmake: '${anchor}' not found in ${IN}")
  endif()
endforeach()
string(REPLACE "model: excavator\n" "model: excavator_hip\n" text "${text}")
string(REPLACE "  - {name: w, value: 0.5,"
               "  - {name: hip_z, value: -0.2, unit: m, kind: offset, meaning: front hips above the cabin plane}\n  - {name: w, value: 0.5,"
               text "${text}")
string(REPLACE "chain: [translate: [cxd/2, <sign>*cyd/2, 0], rx: psi_<side>1"
               "chain: [translate: [cxd/2, <sign>*cyd/2, hip_z], rx: psi_<side>1" text "${text}")
file(WRITE "${OUT}" "${text}")
