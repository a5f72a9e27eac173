# Sourced by tools/instruction_count.sh and tools/instruction_profile.sh (POSIX sh).
# callgrind_run WORK BIN SCENARIO SAMPLES: runs `BIN run SCENARIO --samples SAMPLES --seed 3` under
# callgrind, every process included, dumps in WORK/cg.*. A forked child inherits callgrind's
# counters (valgrind's manual, "Forking Programs"), so each process dumps and zeroes its counters
# before every fork: every instruction is counted once. Stops the script if the run fails or if
# several processes ran and none dumped at a fork (their counts would repeat inherited ones).
callgrind_run() {
  command -v valgrind >/dev/null ||
    { echo "$(basename "$0"): needs valgrind (apt-get install valgrind)" >&2; exit 1; }
  rm -rf "$1/out" "$1"/cg.*
  valgrind --tool=callgrind --trace-children=yes --dump-before='*fork' --callgrind-out-file="$1/cg.%p" \
    "$2" --quiet run "$3" --samples "$4" --seed 3 --out "$1/out" >/dev/null 2>"$1/log" ||
    { echo "$(basename "$0"): $2 failed:" >&2; tail -3 "$1/log" >&2; exit 1; }
  processes=$(ls "$1" | sed -n 's/^cg\.\([0-9]*\).*/\1/p' | sort -u | wc -l)
  if [ "$processes" -gt 1 ] && ! ls "$1" | grep -q '^cg\.[0-9]*\.[0-9]*$'; then
    echo "$(basename "$0"): $processes processes but no dump at a fork: counts would repeat inherited ones" >&2
    exit 1
  fi
}

# callgrind_total WORK: the instructions of every dump in WORK/cg.* (cg.PID and cg.PID.N): each
# dump's "totals:" line, else its "summary:" line.
callgrind_total() {
  awk '$1 == "totals:" {t[FILENAME] = $2} $1 == "summary:" {s[FILENAME] = $2}
    END {for (f in s) if (!(f in t)) t[f] = s[f]; for (f in t) sum += t[f]; printf "%.0f", sum}' "$1"/cg.*
}
