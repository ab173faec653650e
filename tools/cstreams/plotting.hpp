#pragma once
#include <nlohmann/json.hpp>

#include <string>

namespace cstreams::cli {

// Runs an embedded matplotlib script on `data` to write the PNG `target`; throws
// naming the command when no python3 with matplotlib can draw it.
void draw_plot(const char* script, const nlohmann::json& data, const std::string& target);

}  // namespace cstreams::cli
