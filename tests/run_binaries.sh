#!/usr/bin/env bash
# `make test`'s Rust tests: what `cargo test --release` runs, with its test binaries run
# SGBEM_TEST_JOBS at a time (default: the number of cores) instead of one after another.
# Each binary already runs its tests two at a time, but a binary's longest test leaves the
# other core idle (full_rows' collapse searches take over a minute each); running binaries
# side by side keeps both cores busy. The heaviest binaries start first. Each binary's
# output goes to out/test-logs/NAME.log; a failing binary's log is printed whole.
# Each binary writes its scratch runs (tests/support's tmpdir, about 2 GB for the whole suite)
# under a TMPDIR of its own, removed when the binary passes and kept, with its path printed,
# when it fails: repeated runs do not fill the disk.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo=${CARGO:-cargo}
jobs=${SGBEM_TEST_JOBS:-$(nproc)}

"$cargo" test --release --no-run
mapfile -t bins < <("$cargo" test --release --no-run --message-format=json 2>/dev/null |
  grep -E '"profile":\{[^}]*"test":true' | grep -o '"executable":"[^"]*"' | cut -d'"' -f4)
[ "${#bins[@]}" -gt 0 ] || { echo "run_binaries: no test binaries found" >&2; exit 1; }

# Heaviest first (seconds per binary in a clean-clone CI, two at a time, 2026-11-27: full_rows
# 413 before its stone wall (169 s) was left out, sparse 271, friction 119,
# geometry_contact, outputs, workflow 75-79, hostile 65, then 30 and less).
heavy=(full_rows sparse friction geometry_contact workflow outputs hostile solvers arch_limit cli)
ordered=()
for h in "${heavy[@]}"; do
  for b in "${bins[@]}"; do [[ $(basename "$b") == "$h"-* ]] && ordered+=("$b"); done
done
for b in "${bins[@]}"; do
  n=$(basename "$b"); n=${n%-*}
  [[ " ${heavy[*]} " == *" $n "* ]] || ordered+=("$b")
done

logs=out/test-logs
rm -rf "$logs"
mkdir -p "$logs"
scratch=$(mktemp -d "${TMPDIR:-/tmp}/sgbem-tests.XXXXXX")
export logs scratch
one() {
  local n t
  n=$(basename "$1")
  t="$scratch/$n"
  mkdir -p "$t"
  if TMPDIR="$t" "$1" >"$logs/$n.log" 2>&1; then
    rm -rf "$t"
    echo "ok     $n: $(grep -h '^test result' "$logs/$n.log" | tail -1)"
  else
    echo "FAILED $n (its scratch runs are kept in $t)"
    touch "$logs/$n.failed"
  fi
}
export -f one
start=$(date +%s)
printf '%s\n' "${ordered[@]}" | xargs -P "$jobs" -I{} bash -c 'one "$@"' _ {}
failed=$(find "$logs" -name '*.failed' | sort)
if [ -n "$failed" ]; then
  for f in $failed; do
    echo "==== ${f%.failed}.log"
    cat "${f%.failed}.log"
  done
  echo "run_binaries: failed: $(for f in $failed; do basename "${f%.failed}"; done | tr '\n' ' ')" >&2
  exit 1
fi
rmdir "$scratch"
echo "run_binaries: ${#ordered[@]} test binaries passed in $(( $(date +%s) - start )) s"
"$cargo" test --release --doc
