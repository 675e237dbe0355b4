#!/usr/bin/env bash
# The map of where apccd's skipping pays (issue 37): apccd against full over the motion per CCD step
# (steps_per_frame), the resolution, every paper scene, both narrow phases (cubic64, conservative; with cubic64 also
# apccd's box-only front end, heuristic=boxes) and the backends asked for, every cell verified against the exact truth, with apccd's session lengths and the reasons its
# sessions end. Writes reports/apccd-paper/PROFILE/map/ (raw runs, the commands, map.md and map.png through
# reports/apccd-paper/map.py). Each scene is a contact-rich stretch of its simulation: frames FIRST..FRAMES-1 are
# written (the earlier ones simulated only), the same simulated time at every steps_per_frame.
# Usage: scripts/apccd-map.sh [quick|full|smoke]
#   smoke  two tiny resolutions, two motions: checks the pipeline, its numbers mean nothing
#   quick  resolutions 16, 32, 48 (twist and pile at 0.8 and 0.64 of them, as the paper suite), steps_per_frame
#          1 2 4 8 16, 3 simulated frames from frame 20: minutes on 2 cores
#   full   resolutions 32, 64, 100, the same motions, 9 simulated frames from frame 20
# Environment: CCDBENCH_BIN (default: build it), VERIFY (exact, the default, or none: for a GPU machine's OpenCL map,
# verified afterwards by parity with the CPU map, whose folder PARITY names to map.py), SHOWN_AS (the folder the report is read from, for the command it
# prints; default OUT), BACKENDS ("cpu", "cpu opencl" or "opencl"; default cpu), OUT
# (default reports/apccd-paper/PROFILE/map), CELLS (finished cells a rerun reuses, e.g. after the device's call
# limit; default build/paper-cells/PROFILE/map), CCDBENCH_CACHE_DIR (scenes and truth), THREADS, REPEATS (3).
set -euo pipefail
cd "$(dirname "$0")/.."
profile=${1:-quick}
case "$profile" in
  smoke) resolutions="8 12" spf_list="1 4" first=20 frames=22 ;;
  quick) resolutions="16 32 48" spf_list="1 2 4 8 16" first=20 frames=24 ;;
  full) resolutions="32 64 100" spf_list="1 2 4 8 16" first=20 frames=30 ;;
  *) echo "apccd-map.sh: unknown profile '$profile' (smoke, quick or full)" >&2; exit 2 ;;
esac
if [[ -z "${CCDBENCH_BIN:-}" ]]; then
  scripts/build.sh release
  CCDBENCH_BIN=build/release/bin/ccdbench
fi
out=${OUT:-reports/apccd-paper/$profile/map}
cells=${CELLS:-build/paper-cells/$profile/map}
shown=${SHOWN_AS:-$out}
repeats=${REPEATS:-3}
verify=${VERIFY:-exact}
export CCDBENCH_CACHE_DIR=${CCDBENCH_CACHE_DIR:-$PWD/build/cache}
threads=()
[[ -n "${THREADS:-}" ]] && threads=(--threads "$THREADS")
mkdir -p "$out/raw" "$out/scenes" "$cells"
started=$(date +%s)

strategies=""
for backend in ${BACKENDS:-cpu}; do
  suffix=""
  [[ "$backend" == opencl ]] && suffix=":backend=opencl"
  # apccd:skip=off (every step a session start: the same front end, no skipping) splits apccd's gain over full
  # into its front end's and its skipping's; apccd+cubic64:heuristic=boxes is apccd with the front end that pays in
  # front of cubic64 (the box filter alone: it then tests full's pairs less those its object frames prove apart).
  strategies+="${strategies:+,}full+cubic64$suffix,apccd+cubic64$suffix,apccd+cubic64:heuristic=boxes$suffix,apccd+cubic64:skip=off$suffix"
  strategies+=",full$suffix,apccd$suffix,apccd:skip=off$suffix"
done

# One scene file per (scene, resolution, motion), with its generator block.
scenes=()
for r in $resolutions; do
  for name in spinning-ball drape flag twist funnel pile; do
    case "$name" in twist) res=$(( r * 4 / 5 )) ;; pile) res=$(( r * 16 / 25 )) ;; *) res=$r ;; esac
    for spf in $spf_list; do
      stem="$name-r$res-spf$spf"
      echo "{\"generator\": {\"name\": \"$name\", \"resolution\": $res, \"frames\": $frames, \"first_frame\": $first, \"steps_per_frame\": $spf}}" \
        > "$out/scenes/$stem.json"
      scenes+=("$out/scenes/$stem.json")
    done
  done
done

# One run per backend set: every cell verified (--verify exact), resumed from $cells after an interruption.
command=("$CCDBENCH_BIN" "${threads[@]}" run --scene "${scenes[@]}" --strategy "$strategies" --verify "$verify" --repeat "$repeats"
         --out "$cells" --json "$out/raw/map.json")
echo "== map: ${#scenes[@]} scenes, strategies $strategies, verify $verify"
{
  echo "# The map's run (scripts/apccd-map.sh $profile), as typed from the repository root:"
  echo "build/release/bin/ccdbench ${threads[*]:+${threads[*]} }run --scene $shown/scenes/*.json --strategy $strategies --verify $verify --repeat $repeats --out $cells --json $shown/raw/map.json"
} > "$out/raw/command.txt"
"${command[@]}" > "$out/raw/map.txt"
printf 'profile\t%s\nelapsed_s\t%s\nthreads\t%s\nbackends\t%s\n' "$profile" "$(( $(date +%s) - started ))" "${THREADS:-all}" "${BACKENDS:-cpu}" \
  > "$out/raw/run.tsv"
# Every step's answers digest (raw/answers.tsv.gz), for map.py --parity.
python=/usr/bin/python3
[[ -x "$python" ]] || python=python3
"$python" reports/apccd-paper/answers.py "$cells" "$out"
parity=()
[[ -n "${PARITY:-}" ]] && parity=(--parity "$PARITY")
if /usr/bin/python3 -c "import matplotlib" 2>/dev/null; then
  /usr/bin/python3 reports/apccd-paper/map.py "$out" "${parity[@]}"
else
  echo "apccd-map.sh: no /usr/bin/python3 with matplotlib here; render with: /usr/bin/python3 reports/apccd-paper/map.py $out ${parity[*]}" >&2
fi
echo "map: $out/map.md ($(( $(date +%s) - started )) s)"
