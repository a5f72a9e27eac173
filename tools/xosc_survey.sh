#!/usr/bin/env bash
# Issue 24's measure on published OpenSCENARIO files: which ones vsd-sumo imports and runs,
# and the one line each refused file gets. Writes a report (tool version, sources, one line
# per file, totals) to OUT (default results/openscenario/survey.txt) when it is complete.
#
#   tools/xosc_survey.sh ASAM_DIR ESMINI_DIR [OUT]
#   VSD_SUMO=other/vsd-sumo tools/xosc_survey.sh ...      # another build (default: build/vsd-sumo)
#
# ASAM_DIR: a checkout of github.com/asam-oss/OSC-ALKS-scenarios; ESMINI_DIR: a checkout of
# github.com/esmini/esmini (its resources/xosc). Neither is part of this repository.
#   - ASAM's 15 concrete templates: `run --duration 60` (their StopTriggers are
#     not simulation times; 60 s covers every manoeuvre of the set).
#   - ASAM's variation files: `scenario check --duration 60` imports every parameter set
#     (skipped by the template's constraints / refused / would fail / would run, and how many of
#     those that run start with road users other than the Ego overlapping), then `run --samples 200
#     --duration 60` simulates 200 sets drawn from the grid (seed 1).
#   - esmini's resources/xosc: `scenario check --data-root resources --controller-map
#     tools/esmini_controllers.yaml` (its scenarios name roads in ../xodr; its human-driver
#     controllers map onto built-ins; `--ego FIRST_ENTITY` only where no entity has a
#     controller or is named Ego; `--duration 30` only where the StopTrigger is no
#     simulation time), then `run` of each file that would run (with the same options):
#     ran, or the first refusal. A file the scenario language refuses with a hint at `--network`
#     (its roads or SUMO traffic) is checked and run again with `--network` (its Init on SUMO's
#     network of its roads). Each file is also placed in or outside the issue's goal
#     ("roads netconvert reads", actions and conditions in its list): tools/xosc_scope.py,
#     then netconvert on the road it names.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
vsd="${VSD_SUMO:-$root/build/vsd-sumo}"
usage="usage: tools/xosc_survey.sh ASAM_DIR ESMINI_DIR [OUT]"
asam="${1:?$usage}"
esmini="${2:?$usage}"
out="${3:-$root/results/openscenario/survey.txt}"
[ -d "$asam/logical_scenarios" ] || { echo "xosc_survey.sh: $asam: expected a checkout of OSC-ALKS-scenarios (no logical_scenarios/)" >&2; exit 1; }
[ -d "$esmini/resources/xosc" ] || { echo "xosc_survey.sh: $esmini: expected a checkout of esmini (no resources/xosc/)" >&2; exit 1; }
export SUMO_HOME="${SUMO_HOME:-/usr/share/sumo}"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
# The report goes to a temporary file and replaces OUT only once it is complete.
exec 3>&1 > "$work/survey.txt"

echo "# tools/xosc_survey.sh - vsd-sumo $("$vsd" --version), $(date -u +%Y-%m-%dT%H:%MZ)"
# The binary's version ends in -dirty when it was built from uncommitted changes.
echo "# built from a clean tree: $(case "$("$vsd" --version)" in *dirty*) echo no ;; *) echo yes ;; esac)"
echo "# ASAM OSC-ALKS-scenarios $(git -C "$asam" rev-parse --short HEAD 2>/dev/null || echo '(not a git checkout)'), esmini $(git -C "$esmini" rev-parse --short HEAD 2>/dev/null || echo '(not a git checkout)')"

# The line of a run's output that counts its scenarios, or its error line.
run_line() {
  local log="$1" status="$2"
  if [ "$status" -eq 0 ]; then grep -m1 -E 'concrete scenarios? \(seed|samples from [0-9]+ Egos' "$log" || tail -1 "$log"
  else grep -m1 '^vsd-sumo: ' "$log" || tail -1 "$log"; fi
}

echo
echo "## ASAM concrete templates: vsd-sumo run FILE --duration 60"
ran=0; total=0
for file in "$asam"/logical_scenarios/concrete_scenarios/*_template.xosc; do
  total=$((total + 1)); status=0
  "$vsd" run "$file" --duration 60 --out "$work/t$total" >"$work/log" 2>&1 || status=$?
  [ "$status" -eq 0 ] && ran=$((ran + 1))
  echo "  $(basename "$file"): exit $status; $(run_line "$work/log" "$status")"
done
echo "  templates run: $ran of $total"

echo
echo "## ASAM variations: scenario check --duration 60 (every set), run --samples 200 --duration 60"
ran=0; total=0
for file in "$asam"/logical_scenarios/*_variation*.xosc; do
  total=$((total + 1)); status=0
  "$vsd" scenario check --duration 60 "$file" >"$work/check" 2>&1 || status=$?
  # The counts alone: the first skipped / failing set's message is in the check's own output.
  sets="$(grep -m1 -E '[0-9]+ parameter sets: ' "$work/check" \
    | grep -oE '[0-9]+ (parameter sets|skipped by the template.s constraints|refused|would fail|would run)' \
    | paste -sd ';' - | sed 's/;/, /g' || true)"
  [ -z "$sets" ] && sets="$(grep -m1 '^REFUSED' "$work/check" | sed "s|$asam/||g" || true)"
  # Sets that run although road users other than the Ego start overlapping (the files' own values).
  overlapping="$(grep -m1 -oE '[0-9]+ of the sets that would run start with road users other than the Ego overlapping' \
    "$work/check" || true)"
  [ -n "$overlapping" ] && sets="$sets ($overlapping)"
  echo "  $(basename "$file"): check exit $status; $sets"
  if [ "$status" -eq 0 ]; then
    run_status=0
    "$vsd" run "$file" --samples 200 --seed 1 --duration 60 --out "$work/v$total" >"$work/log" 2>&1 || run_status=$?
    [ "$run_status" -eq 0 ] && ran=$((ran + 1))
    echo "    run of 200 sets: exit $run_status; $(run_line "$work/log" "$run_status")"
    [ "$run_status" -eq 0 ] && echo "      $(grep -m1 '^parameter sets:' "$work/log" || true)"
  fi
done
echo "  variation files run: $ran of $total"

echo
echo "## esmini resources/xosc: scenario check --data-root resources --controller-map" \
  "tools/esmini_controllers.yaml (--ego FIRST_ENTITY, --duration 30 where it asks for them), run if it would"
echo "   scope: in the issue's goal = netconvert reads its road and its actions and conditions are in the issue's list"
ran=0; total=0; in_scope=0; ran_in_scope=0
declare -A netconvert_reads
# `scenario check` of $file with ${options[@]} into $work/check, its exit in $status; adds --ego
# FIRST_ENTITY where no entity has a controller or is named Ego (all scripted: its first entity is
# the Ego, driven by the default controller, as a user would say with --ego) and --duration 30
# where the StopTrigger is no simulation time.
check_esmini() {
  status=0
  "$vsd" scenario check "${options[@]}" "$file" >"$work/check" 2>&1 || status=$?
  if grep -q 'which is the Ego?' "$work/check"; then
    first="$(python3 -c 'import sys, xml.etree.ElementTree as t
print(t.parse(sys.argv[1]).find(".//{*}ScenarioObject").get("name"))' "$file" 2>/dev/null || true)"
    if [ -n "$first" ]; then
      options+=(--ego "$first"); status=0
      "$vsd" scenario check "${options[@]}" "$file" >"$work/check" 2>&1 || status=$?
    fi
  fi
  if grep -q 'pass --duration' "$work/check"; then
    options+=(--duration 30); status=0
    "$vsd" scenario check "${options[@]}" "$file" >"$work/check" 2>&1 || status=$?
  fi
}
for file in "$esmini"/resources/xosc/*.xosc; do
  total=$((total + 1)); status=0
  scope="$(python3 "$root/tools/xosc_scope.py" "$file")"
  if [[ "$scope" == "in scope "* ]]; then
    road="$(cd "$(dirname "$file")" && realpath -m "${scope#in scope }")"
    if [ -z "${netconvert_reads[$road]+set}" ]; then
      if netconvert --opendrive-files "$road" -o "$work/road.net.xml" >"$work/netconvert.log" 2>&1; then
        netconvert_reads[$road]=yes
      else
        netconvert_reads[$road]="netconvert refuses $(basename "$road"): $(grep -m1 '^Error' \
          "$work/netconvert.log" || echo 'no such file')"
      fi
    fi
    [ "${netconvert_reads[$road]}" = yes ] && scope="in scope" || scope="outside: ${netconvert_reads[$road]}"
  fi
  # The file's own end where its StopTrigger is a simulation time; 30 s where it asks for one.
  options=(--data-root "$esmini/resources" --controller-map "$root/tools/esmini_controllers.yaml")
  check_esmini
  # A file whose roads (or SUMO traffic) the scenario language cannot carry: its Init on SUMO's
  # network of them, as the refusal suggests.
  if [ "$status" -ne 0 ] && grep -m1 -E '^REFUSED|^vsd-sumo: ' "$work/check" | grep -q -- '--network'; then
    options=(--data-root "$esmini/resources" --controller-map "$root/tools/esmini_controllers.yaml" --network)
    check_esmini
  fi
  if [ "$status" -eq 0 ]; then
    how=ran; run_out="$work/e$total"
    # A network scenario writes a dataset file (the scenes around the Ego), as `export` does.
    case " ${options[*]} " in *" --network "*) how="ran with --network"; run_out="$work/e$total.h5" ;; esac
    "$vsd" run "$file" "${options[@]}" --out "$run_out" >"$work/log" 2>&1 || status=$?
    if [ "$status" -eq 0 ]; then line="$how: $(run_line "$work/log" 0)"; ran=$((ran + 1))
    else line="run failed (exit $status): $(run_line "$work/log" "$status" | cut -c1-200)"; fi
  else
    line="$(grep -m1 -E '^REFUSED|^vsd-sumo: ' "$work/check" | sed "s|$esmini/||g" | cut -c1-220)"
    # Refused by the scenario language at its roads, then by the network scenario at this.
    case " ${options[*]} " in *" --network "*) line="with --network: $line" ;; esac
  fi
  if [ "$scope" = "in scope" ]; then
    in_scope=$((in_scope + 1)); [ "$status" -eq 0 ] && ran_in_scope=$((ran_in_scope + 1))
  fi
  echo "  $(basename "$file") [$scope]: $line"
done
echo "  esmini files that ran: $ran of $total"
echo "  in the issue's goal: $ran_in_scope of $in_scope ran ($((100 * ran_in_scope / in_scope)) %; the goal is 90 %)"
mkdir -p "$(dirname "$out")"
mv "$work/survey.txt" "$out"
echo "xosc_survey.sh: wrote $out" >&3
