// The runtime is generic code compiled once per model (docs/architecture.md): each compilation
// sees one model's generated headers (the include path generated/<model>) and puts everything it
// defines into the inline namespace wlx::<model>, next to that model's generated wlx::<model>::gen.
// A translation unit therefore works with one model and may call it wlx::Model, wlx::gen::...;
// a program may link several models, each under its own name (wlx::excavator::Model, ...).
#pragma once

#ifndef WLX_MODEL
#error "compile the wlx runtime for a model: define WLX_MODEL=<name> and put generated/<name> on the include path (the CMake target wlx::<name> does both)"
#endif

#define WLX_MODEL_NAMESPACE_BEGIN \
  namespace wlx {                 \
  inline namespace WLX_MODEL {
#define WLX_MODEL_NAMESPACE_END \
  }                             \
  }
