// A model's description (model.json, written by wlx-gen beside its headers) read into the
// runtime's settings (wlx/settings.hpp): how a model file's plugin gets the numbers its compiled
// code leaves out (wlx-gen --data-at-run-time).
#pragma once

#include "per_model.hpp"

#include <wlx/settings.hpp>

#include <string>

WLX_COMMANDS_BEGIN

// The settings model.json's text gives, checked against this model's compiled structure (its
// name, parameters, inputs, dependent joints, limbs, actuators and contacts, by name and count).
// Throws wlx::Error ("model.json" and the first mismatch or bad value).
Settings settings_of_description(const std::string& json_text);

// settings_of_description(), then set_settings(): "" on success, else the message. Keeps the
// text for description_text().
std::string load_description(const std::string& json_text) noexcept;

// The model's description (model.json's text): embedded in wlx for a built-in model, the one
// load_description() was given for a model file's plugin; empty if neither.
const std::string& description_text();

WLX_COMMANDS_END
