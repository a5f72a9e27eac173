#!/usr/bin/env bash
# Issue 29's measure for map exports: export real SUMO maps and check that no valid instant
# moves impossibly (tools/motion_check.py: |a| <= 15 m/s^2, no jump beyond speed x step
# + 0.5 m). Prints a report with the tool version, the maps, the exports' own summaries,
# their time and peak memory, and the motion check of each.
#
#   tools/redteam_maps.sh PASUBIO_DIR SUMO_SCENARIOS_DIR > results/robustness/maps.txt
#
# PASUBIO_DIR: SUMO's Bologna pasubio scenario (Debian's sumo-tools installs it under
# /usr/share/sumo/tools/sumolib/scenario/scenarios/RealWorld/pasubio); SUMO_SCENARIOS_DIR: a
# checkout of github.com/DLR-TS/sumo-scenarios (TAVF-Hamburg, Wildau). Neither is part of
# this repository. Each export: 20 random Egos, seed 1, at most 2,000 samples.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
vsd="$root/build/vsd-sumo"
pasubio="${1:?usage: tools/redteam_maps.sh PASUBIO_DIR SUMO_SCENARIOS_DIR}"
dlr="${2:?usage: tools/redteam_maps.sh PASUBIO_DIR SUMO_SCENARIOS_DIR}"
export SUMO_HOME="${SUMO_HOME:-/usr/share/sumo}"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

echo "# tools/redteam_maps.sh - vsd-sumo $("$vsd" --version), $(date -u +%Y-%m-%dT%H:%MZ)"
echo "# git tree clean: $(cd "$root" && git diff --quiet HEAD && echo yes || echo no)"
echo "# every export: --egos random:20 --seed 1 --max-samples 2000; check: tools/motion_check.py"

check_map() {
  local name="$1"; shift
  echo
  echo "## $name: vsd-sumo export $*"
  local status=0
  /usr/bin/time -f "time %e s, peak memory %M KiB" -o "$work/$name.time" \
    "$vsd" -q export "$@" --egos random:20 --seed 1 --max-samples 2000 --out "$work/$name.h5" \
    >"$work/$name.log" 2>&1 || status=$?
  sed 's|^|  |' "$work/$name.log" | grep -v '^  $' || true
  echo "  exit $status; $(cat "$work/$name.time" | tail -1)"
  if [ "$status" -eq 0 ]; then
    /usr/bin/python3 "$root/tools/motion_check.py" "$work/$name.h5" | sed 's|^|  |;s|'"$work"'/||' || true
  fi
}

check_map pasubio --net "$pasubio/pasubio_buslanes.net.xml" \
  --routes "$pasubio/pasubio_vtypes.add.xml" "$pasubio/pasubio.rou.xml"
check_map tavf_hamburg --net "$dlr/TAVF-Hamburg/network.net.xml.gz" \
  --routes "$dlr/TAVF-Hamburg/vType.xml" "$dlr/TAVF-Hamburg/PKW_automatic.rou.xml.gz" \
  "$dlr/TAVF-Hamburg/LKW_automatic.rou.xml"
check_map wildau "$dlr/Wildau/output_configuration.sumocfg"
