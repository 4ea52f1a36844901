// A model compiled without embedded runs: a model file's plugin (cli/shell/model_plugin.cpp) and a
// user's Python module (wlx_generate(PYTHON)), whose runs, report file and description come as files
// at run time. A built-in model embeds its own instead (cmake/embed_scenarios.cmake writes the
// same three definitions with its files' texts).
#include "per_model.hpp"

#include <string>
#include <utility>
#include <vector>

WLX_COMMANDS_BEGIN

extern const std::vector<std::pair<std::string, std::string>> kEmbeddedScenarios;
const std::vector<std::pair<std::string, std::string>> kEmbeddedScenarios = {};
extern const char* const kEmbeddedReportFile;
const char* const kEmbeddedReportFile = "";
extern const char* const kEmbeddedDescription;
const char* const kEmbeddedDescription = "";

WLX_COMMANDS_END
