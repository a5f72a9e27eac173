#pragma once
// Fault-injection hooks: named points in the code (every write, fsync and rename
// of an output, the phases of a worker process) at which a test can make the
// process misbehave on purpose — to prove that an interruption at *that* moment
// leaves no corrupt or complete-looking output behind.
//
// Inactive (one branch on a cached flag) unless the environment sets:
//
//   VSD_FAULT=<action>@<point>[#<n>]
//       At the n-th time (default 1st) this process reaches a point whose name
//       matches <point>, perform <action>. <point> is a full point name, or a
//       prefix followed by '*' ("folder.rename:*" matches every rename of a
//       folder commit). Counting is per process; a forked worker inherits the
//       parent's counts at the time of the fork.
//       <action>:
//         kill   SIGKILL itself (power loss, OOM killer: no handler runs)
//         term   SIGTERM to itself, then go on (the handler's flag is set)
//         int    SIGINT to itself, then go on
//         abort  abort() (what a failed assertion in libsumo does)
//         segv   SIGSEGV with the default action (a crash)
//         exit0  exit(0) (a plugin that ends the process "successfully")
//         hang   sleep forever (a hang; only a watchdog or SIGKILL ends it)
//         term-parent, int-parent   SIGTERM / SIGINT to the parent process (from a
//                worker: the user's signal arriving while the worker is at <point>)
//   VSD_FAULT_TRACE=<file>
//       Append one line "<pid> <point>" to <file> for every point reached
//       (to enumerate the points of a command, then inject at each).
//
// Points (stable names; <file> is the path relative to the output folder or the
// final file name):
//   folder.stage:<file>     a staged file of an output folder is complete and closed
//   folder.fsync:<file>     before it is flushed to disk
//   folder.manifest         before the staged manifest is written
//   folder.decide           before the staged set becomes the folder's new contents
//   folder.unlink-manifest  before the old manifest is removed
//   folder.remove:<file>    before a file of the old set that the new set lacks is removed
//   folder.rename:<file>    before a staged file is renamed into the folder
//   folder.publish          before the new manifest is renamed into the folder
//   folder.cleanup          before the emptied staging folder is removed
//   atomic.fsync:<file>     AtomicOutput: before the finished file is flushed to disk
//   atomic.rename:<file>    AtomicOutput: before it gets its final name
//   pool.fork               the parent is about to fork a worker process
//   run.write               the parent has written one batch of results (temporary files)
//   export.write            the export worker has written 1000 samples (temporary file)
//   worker.start            a worker process started (in the worker)
//   netconvert.wait         a worker starts waiting for netconvert
//   sumo.load               before libsumo loads a simulation (in the worker)
//   sumo.step               before every libsumo step (in the worker)
//   sumo.step-with:<sample> before every step of a simulation holding that concrete scenario
//   controller.step:<sample> before the Ego controller of that concrete scenario steps
//   controller.step:<ego id> same for a closed-loop Ego of a map export

#include <string>

namespace vsd {

/// Reaches the named fault-injection point (see above). Cheap when inactive.
void faultPoint(const char* point);
void faultPoint(const std::string& point);
/// True if VSD_FAULT or VSD_FAULT_TRACE is set (to skip building point names).
bool faultInjectionActive();
/// Reads VSD_FAULT and VSD_FAULT_TRACE again and resets the counts (for tests
/// that set them in a forked child).
void reloadFaultInjection();

}  // namespace vsd
