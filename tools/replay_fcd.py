#!/usr/bin/python3
"""Replay a `vsd-sumo run --fcd` batch in sumo-gui.

SUMO 1.15 has no built-in FCD replay, so this script loads the batch's network,
adds every vehicle found in the FCD file and moves it along its recorded
positions with TraCI's moveToXY, step by step.

    tools/replay_fcd.py out/acc_lk --batch 0            # opens sumo-gui
    tools/replay_fcd.py out/acc_lk --batch 0 --check    # headless: verify the replay matches the FCD

Needs Debian's python3 with the `traci` package from sumo-tools.
"""
import argparse
import os
import sys
import xml.etree.ElementTree as ElementTree

os.environ.setdefault("SUMO_HOME", "/usr/share/sumo")
sys.path.append(os.path.join(os.environ["SUMO_HOME"], "tools"))
import traci  # noqa: E402


def read_fcd(path):
    """{time: [(vehicle id, lane id, x, y, angle)]}, times in file order."""
    steps = {}
    for _, element in ElementTree.iterparse(path, events=("end",)):
        if element.tag != "timestep":
            continue
        time = float(element.get("time"))
        steps[time] = [(v.get("id"), v.get("lane", ""), float(v.get("x")), float(v.get("y")), float(v.get("angle")))
                       for v in element.findall("vehicle")]
        element.clear()
    return steps


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("out", help="output folder of `vsd-sumo run --fcd`")
    parser.add_argument("--batch", type=int, default=0, help="batch number (default 0)")
    parser.add_argument("--check", action="store_true", help="run headless and verify positions, exit 1 on mismatch")
    parser.add_argument("--delay", type=int, default=100, help="sumo-gui delay per step in ms")
    args = parser.parse_args()

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
    binary = "sumo" if args.check else "sumo-gui"
    command = [binary, "-c", config, "--step-length", str(step_length), "--begin", str(begin),
               "--no-step-log", "true", "--collision.action", "none", "--xml-validation", "never"]
    if not args.check:
        command += ["--delay", str(args.delay), "--start"]
    traci.start(command, numRetries=5)
    known = set()
    worst = 0.0
    try:
        for time in times:
            for vehicle, lane, x, y, angle in steps[time]:
                edge = lane.rsplit("_", 1)[0] if lane else ""
                if vehicle not in known:
                    if not edge:
                        continue
                    traci.route.add("replay_" + vehicle, [edge])
                    traci.vehicle.add(vehicle, "replay_" + vehicle)
                    known.add(vehicle)
                traci.vehicle.moveToXY(vehicle, edge, -1, x, y, angle, keepRoute=2)
            traci.simulationStep()
            if args.check:
                present = set(traci.vehicle.getIDList())
                for vehicle, _, x, y, _ in steps[time]:
                    if vehicle in present:
                        px, py = traci.vehicle.getPosition(vehicle)
                        worst = max(worst, abs(px - x), abs(py - y))
    finally:
        traci.close()
    if args.check:
        print("replayed %d vehicles over %d steps; largest position difference %.4f m" % (len(known), len(times), worst))
        return 0 if worst <= 0.011 else 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
