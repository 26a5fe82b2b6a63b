#!/usr/bin/env bash
# `tessera farm` on a real Slurm: starts a one-node Slurm of its own (tools/local_slurm.sh), submits
# a 4-task array rendering the Cornell box with bdpt plus the merge job, waits for the merge, checks
# that the merged image has the bits of one single-process render of the same seed and spp, and
# stops exactly the daemons it started. Exit 77 (skipped, with the reason) when Slurm cannot run
# here; with CI set that is a failure. Usage: test_farm_slurm.sh TESSERA_BINARY SOURCE_DIR
set -uo pipefail
tessera="$1"
src="$2"
skip() {
  if [ -n "${CI:-}" ]; then echo "FAIL (CI must run this test): $*" >&2; exit 1; fi
  echo "SKIPPED: $*" >&2
  exit 77
}
if ! command -v slurmctld >/dev/null 2>&1 && [ ! -x /usr/sbin/slurmctld ] && [ -z "${CI:-}" ]; then
  skip "slurm-wlm is not installed (bash tools/bootstrap.sh --install slurm)"
fi
work="$(mktemp -d /tmp/tessera-farm-slurm.XXXXXX)"
cleanup() { bash "$src/tools/local_slurm.sh" stop "$work/slurm"; rm -rf "$work"; }
trap cleanup EXIT
bash "$src/tools/local_slurm.sh" start "$work/slurm"
rc=$?
[ $rc -eq 3 ] && skip "Slurm cannot be started here (see above)"
[ $rc -ne 0 ] && { echo "FAIL: tools/local_slurm.sh start exited $rc" >&2; exit 1; }
export SLURM_CONF="$work/slurm/slurm.conf" PATH="$PATH:/usr/sbin"

scene="$src/scenes/cornell-box/cornell-box.gltf"
opts=(--resolution 48x36 --seed 9 --integrator bdpt --max-depth 5)
farm() { "$tessera" farm "$scene" --parts 4 --spp 12 --out "$work/farm" --cpus-per-task 1 --json -- "${opts[@]}"; }
field() { python3 -c 'import json,sys; print(json.loads(sys.argv[1])[sys.argv[2]])' "$1" "$2"; }
wait_gone() {  # job id: wait until it has left the queue (at most 120 s)
  local i
  for i in $(seq 240); do
    [ -z "$(squeue -h -j "$1" 2>/dev/null)" ] && return 0
    sleep 0.5
  done
  echo "FAIL: job $1 still queued after 120 s" >&2; squeue >&2; exit 1
}

# First run: task 1 (samples 3:6) fails (its output path is a directory), so the merge job is
# cancelled and no image appears.
mkdir -p "$work/farm/part_3-6.partial"
json="$(farm)" || { echo "FAIL: tessera farm" >&2; exit 1; }
echo "$json"
[ -n "$(field "$json" array_job)" ] || { echo "FAIL: no array job submitted" >&2; exit 1; }
wait_gone "$(field "$json" array_job)"
wait_gone "$(field "$json" merge_job)"
merged="$work/farm/cornell-box.exr"
[ -f "$merged" ] && { echo "FAIL: the merge ran although task 1 failed" >&2; exit 1; }
[ "$(ls "$work"/farm/part_*.partial -d | wc -l)" = 4 ] || { echo "FAIL: expected 3 partials and the blocker" >&2; exit 1; }

# Re-run after the failure: only 3:6 is submitted; the merge then writes the image.
rmdir "$work/farm/part_3-6.partial"
json="$(farm)" || { echo "FAIL: tessera farm (re-run)" >&2; exit 1; }
echo "$json"
[ "$(field "$json" submitted)" = "['3:6']" ] || { echo "FAIL: the re-run should submit only 3:6" >&2; exit 1; }
wait_gone "$(field "$json" merge_job)"
if [ ! -f "$merged" ]; then
  echo "FAIL: no merged image after the merge job; logs:" >&2
  tail -n 20 "$work"/farm/logs/* "$work/slurm/log/slurmctld.log" >&2
  exit 1
fi

"$tessera" render "$scene" --quiet --no-png --spp 12 "${opts[@]}" -o "$work/single.exr" || { echo "FAIL: single render" >&2; exit 1; }
# Bit identity: no pixel differs at all (max |a - b| = 0 over every channel), none is NaN/Inf, and
# the image is not black.
cmp="$("$tessera" compare "$merged" "$work/single.exr" --json)" || { echo "FAIL: tessera compare" >&2; exit 1; }
echo "$cmp"
python3 - "$cmp" <<'PY' || { echo "FAIL: the merged image differs from the single-process render" >&2; exit 1; }
import json, sys
c = json.loads(sys.argv[1])
ok = c["max_abs_error"]["value"] == 0 and c["non_finite_test"] == 0 and c["non_finite_ref"] == 0 and sum(c["mean_ref"]) > 0
sys.exit(0 if ok else 1)
PY
echo "PASS: 4-task Slurm array + merge job = single render, bit for bit"
