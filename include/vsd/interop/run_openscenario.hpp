#pragma once
// `vsd-sumo run FILE.xosc`: simulate one concrete scenario read from OpenSCENARIO.

#include "vsd/interop/openscenario.hpp"
#include "vsd/pipeline/run.hpp"

namespace vsd::interop {

/// Imports options.scenarioFile (an .xosc), checks its road with netconvert (SumoError
/// "netconvert rejects FILE: ..." if SUMO cannot read it; a warning if netconvert's lanes
/// are more than 5 cm from vsd-sumo's reading) and runs it as one concrete scenario with
/// the sample index and seed the file records (so its road sits where the original run
/// put it): options' sampling (samples, seed, first sample) is replaced. The output folder
/// defaults to out/<file stem>.
pipeline::RunSummary runOpenScenario(pipeline::RunOptions options, const ImportOptions& import);

/// Largest distance (m) between the lane centres netconvert builds from `imported`'s
/// OpenDRIVE file and those vsd-sumo simulates. Throws SumoError if netconvert rejects it.
double netconvertDeviation(const ImportedScenario& imported);

}  // namespace vsd::interop
