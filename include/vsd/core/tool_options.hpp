#pragma once
// Options for SUMO and netconvert that a scenario file may carry.
//
// Scenario files (YAML `sumo.sumo_options` / `sumo.netconvert_options`, the
// OpenSCENARIO FileHeader properties `vsd-sumo.sumo.options` /
// `vsd-sumo.sumo.netconvert_options`) travel between teams and tools, so they carry
// data, not commands: only the options listed here are passed on — options that
// tune the simulation or the network and cannot name a file, a folder, a prefix or a
// network port. Their values are checked too (a number, true/false, or a list of
// plain words). Everything else — output options (--fcd-output,
// --plain-output-prefix, --device.ssm.file, ...), configuration and input files
// (-c, --additional-files), logs, ports, short forms — is refused with one line
// naming the file, the option and this list. Options given on vsd-sumo's own command
// line (`export --sumo-option`) are the user's and are not filtered.
//
// The list is the one place that decides; the README's "Bad input" section shows it.

#include <string>
#include <vector>

namespace vsd {

enum class SumoTool { Sumo, Netconvert };

/// Throws ConfigError "<where>: <field>[i]: '<token>' ...: expected ..." for the first
/// option outside the allow-list or value of the wrong kind.
void checkScenarioToolOptions(SumoTool tool, const std::vector<std::string>& options, const std::string& where,
                              const std::string& field);

/// The allowed options of `tool`, comma-separated (for messages and documentation).
std::string allowedToolOptions(SumoTool tool);

/// SUMO's --collision.action values a scenario may choose: none, warn, teleport, remove.
bool isCollisionAction(const std::string& action);
/// "one of none, warn, teleport, remove" (for messages).
std::string collisionActionsExpected();

}  // namespace vsd
