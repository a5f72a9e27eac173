#!/usr/bin/python3
"""Replay a `vsd-sumo run --fcd` batch in SUMO, faithfully.

SUMO 1.15 has no built-in FCD replay, so this script loads the batch's network,
adds every vehicle found in the FCD file and moves it along its recorded
positions with TraCI, step by step. Speeds are replayed too: every vehicle
departs with its recorded speed, runs with speed mode 0 and gets its recorded
speed with setSpeed each step, so devices that read speeds (SUMO's SSM device)
see the recorded ones — with moveToXY alone SUMO would derive each speed from
the previous step's displacement (0 at insertion).

    tools/replay_fcd.py out/acc_lk --batch 0            # opens sumo-gui
    tools/replay_fcd.py out/acc_lk --batch 0 --check    # headless: verify positions and speeds
    tools/replay_fcd.py out/acc_lk --check --sumo-option="--device.ssm.probability 1" \\
        --sumo-option="--device.ssm.file ssm.xml"       # extra SUMO options, e.g. the SSM device

Needs Debian's python3 with the `traci` package from sumo-tools.
"""
import argparse
import os
import re
import shlex
import sys
import xml.etree.ElementTree as ElementTree

os.environ.setdefault("SUMO_HOME", "/usr/share/sumo")
sys.path.append(os.path.join(os.environ["SUMO_HOME"], "tools"))
import traci  # noqa: E402

# `vsd-sumo run` names its vehicle types after their dimensions (sim/batch_simulation.cpp).
TYPE_PATTERN = re.compile(r"^vsd_([-+0-9.eE]+)x([-+0-9.eE]+)$")
# FCD output rounds positions and speeds to 0.01.
TOLERANCE = 0.011


def read_fcd(path):
    """{time: [(vehicle id, type, lane id, x, y, angle, speed)]}, times in file order."""
    steps = {}
    for _, element in ElementTree.iterparse(path, events=("end",)):
        if element.tag != "timestep":
            continue
        time = float(element.get("time"))
        steps[time] = [(v.get("id"), v.get("type", ""), v.get("lane", ""), float(v.get("x")), float(v.get("y")),
                        float(v.get("angle")), float(v.get("speed"))) for v in element.findall("vehicle")]
        element.clear()
    return steps


def ensure_type(type_id, known_types):
    """Recreates a vsd-sumo vehicle type (length x width, no minimum gap) the first time it is seen."""
    if not type_id or type_id in known_types:
        return type_id if type_id in known_types else "DEFAULT_VEHTYPE"
    match = TYPE_PATTERN.match(type_id)
    if not match:
        return "DEFAULT_VEHTYPE"
    traci.vehicletype.copy("DEFAULT_VEHTYPE", type_id)
    traci.vehicletype.setLength(type_id, float(match.group(1)))
    traci.vehicletype.setWidth(type_id, float(match.group(2)))
    traci.vehicletype.setMinGap(type_id, 0.0)
    traci.vehicletype.setMaxSpeed(type_id, 100.0)
    known_types.add(type_id)
    return type_id


def parse_arguments():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("out", help="output folder of `vsd-sumo run --fcd`")
    parser.add_argument("--batch", type=int, default=0, help="batch number (default 0)")
    parser.add_argument("--check", action="store_true",
                        help="run headless and verify positions and speeds, exit 1 on a mismatch")
    parser.add_argument("--delay", type=int, default=100, help="sumo-gui delay per step in ms")
    parser.add_argument("--sumo-option", action="append", default=[], metavar="OPTIONS",
                        help="extra SUMO command-line options (split like a shell would; repeatable)")
    return parser.parse_args()


def sumo_command(args, config, step_length, begin):
    binary = "sumo" if args.check else "sumo-gui"
    command = [binary, "-c", config, "--step-length", str(step_length), "--begin", str(begin),
               "--no-step-log", "true", "--collision.action", "none", "--xml-validation", "never"]
    if not args.check:
        command += ["--delay", str(args.delay), "--start"]
    for options in args.sumo_option:
        command += shlex.split(options)
    return command


def replay(steps, times, check):
    """Drives every vehicle through its recorded states; returns (vehicles, worst position, worst speed difference)."""
    known, known_types = set(), set()
    worst_position = worst_speed = 0.0
    for time in times:
        for vehicle, type_id, lane, x, y, angle, speed in steps[time]:
            edge = lane.rsplit("_", 1)[0] if lane else ""
            if vehicle not in known:
                if not edge:
                    continue
                traci.route.add("replay_" + vehicle, [edge])
                traci.vehicle.add(vehicle, "replay_" + vehicle, typeID=ensure_type(type_id, known_types),
                                  departSpeed=str(speed))
                traci.vehicle.setSpeedMode(vehicle, 0)
                traci.vehicle.setLaneChangeMode(vehicle, 0)
                known.add(vehicle)
            traci.vehicle.moveToXY(vehicle, edge, -1, x, y, angle, keepRoute=2)
            traci.vehicle.setSpeed(vehicle, speed)
        traci.simulationStep()
        if check:
            present = set(traci.vehicle.getIDList())
            for vehicle, _, _, x, y, _, speed in steps[time]:
                if vehicle in present:
                    px, py = traci.vehicle.getPosition(vehicle)
                    worst_position = max(worst_position, abs(px - x), abs(py - y))
                    worst_speed = max(worst_speed, abs(traci.vehicle.getSpeed(vehicle) - speed))
    return known, worst_position, worst_speed


def main():
    args = parse_arguments()
    stem = "batch_%05d" % args.batch
    config = os.path.join(args.out, "nets", stem + ".sumocfg")
    fcd = os.path.join(args.out, "fcd", stem + ".fcd.xml")
    for path in (config, fcd):
        if not os.path.exists(path):
            sys.exit("replay_fcd.py: %s does not exist (run `vsd-sumo run ... --fcd` first)" % path)

    steps = read_fcd(fcd)
    times = sorted(time for time, vehicles in steps.items() if vehicles)
    if not times:
        sys.exit("replay_fcd.py: %s holds no time steps" % fcd)
    step_length = round(times[1] - times[0], 6) if len(times) > 1 else 0.2
    begin = max(0.0, round(times[0] - step_length, 6))
    traci.start(sumo_command(args, config, step_length, begin), numRetries=5)
    try:
        known, worst_position, worst_speed = replay(steps, times, args.check)
    finally:
        traci.close()
    if args.check:
        print("replayed %d vehicles over %d steps; largest position difference %.4f m, speed difference %.4f m/s"
              % (len(known), len(times), worst_position, worst_speed))
        return 0 if worst_position <= TOLERANCE and worst_speed <= TOLERANCE else 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
