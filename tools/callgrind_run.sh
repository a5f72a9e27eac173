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
  hwy_without_rdtscp "$1/hwy" "$2"
  LD_LIBRARY_PATH="$1/hwy${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}" valgrind --tool=callgrind --trace-children=yes --dump-before='*fork' --callgrind-out-file="$1/cg.%p" \
    "$2" --quiet run "$3" --samples "$4" --seed 3 --out "$1/out" >/dev/null 2>"$1/log" ||
    { echo "$(basename "$0"): $2 failed:" >&2; tail -3 "$1/log" >&2; exit 1; }
  processes=$(ls "$1" | sed -n 's/^cg\.\([0-9]*\).*/\1/p' | sort -u | wc -l)
  if [ "$processes" -gt 1 ] && ! ls "$1" | grep -q '^cg\.[0-9]*\.[0-9]*$'; then
    echo "$(basename "$0"): $processes processes but no dump at a fork: counts would repeat inherited ones" >&2
    exit 1
  fi
}

# hwy_without_rdtscp DIR BIN: Debian 12's valgrind (3.19) does not know RDTSCP on AMD
# processors, and libhwy (which SUMO's library pulls in through libjxl) executes it while it is
# loaded. On such a host DIR gets a copy of the libhwy.so.1 BIN loads with every RDTSCP replaced
# by RDTSC + NOP (it only reads a timer; the counts of vsd-sumo's own work do not change);
# elsewhere, or if BIN loads no libhwy, DIR stays empty.
hwy_without_rdtscp() {
  mkdir -p "$1"
  grep -q AuthenticAMD /proc/cpuinfo || return 0
  library=$(ldd "$2" | awk '$1 == "libhwy.so.1" {print $3}')
  [ -n "$library" ] || return 0
  command -v objdump >/dev/null ||
    { echo "$(basename "$0"): needs objdump to run valgrind on this AMD host (apt-get install binutils)" >&2; exit 1; }
  cp "$(readlink -f "$library")" "$1/libhwy.so.1"
  objdump -d "$1/libhwy.so.1" | awk '/\trdtscp/ {sub(":", "", $1); print $1}' | /usr/bin/python3 -c "
import sys
path = sys.argv[1]
data = bytearray(open(path, 'rb').read())
for line in sys.stdin:
    at = int(line, 16)
    if data[at:at + 3] != b'\\x0f\\x01\\xf9':
        sys.exit('hwy_without_rdtscp: no RDTSCP at %#x in %s' % (at, path))
    data[at:at + 3] = b'\\x0f\\x31\\x90'
open(path, 'wb').write(data)" "$1/libhwy.so.1"
}

# callgrind_total WORK: the instructions of every dump in WORK/cg.* (cg.PID and cg.PID.N): each
# dump's "totals:" line, else its "summary:" line.
callgrind_total() {
  awk '$1 == "totals:" {t[FILENAME] = $2} $1 == "summary:" {s[FILENAME] = $2}
    END {for (f in s) if (!(f in t)) t[f] = s[f]; for (f in t) sum += t[f]; printf "%.0f", sum}' "$1"/cg.*
}
