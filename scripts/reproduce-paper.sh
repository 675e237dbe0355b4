#!/usr/bin/env bash
# Regenerates reports/apccd-paper/PROFILE/ on this machine: the map of where skipping pays (map/, scripts/apccd-map.sh),
# the paper's claims tested (CLAIMS.md), the attribution table, the crossover and memory plots and the wind sweep
# (README.md), and apccd's stages before and after issue 37's changes (profile/, scripts/apccd-profile.sh), from
# ccdbench runs whose commands are written beside every table. Every cell runs here, in this one invocation, so its
# ratios compare like with like.
#
# Each step of the quick profile is timed 3 times (its median counts): one pass of a 10-step cell on a shared machine
# is too noisy for the sweeps' ratios. The full profile's cells hold 96-99 steps (the crossover's from 8: it keeps 3).
# Usage: scripts/reproduce-paper.sh [quick|full|smoke]
#   quick  10 steps per scene, fewer sweep points: under 10 minutes on 16 cores from a cold truth cache
#   full   99 steps per scene and every sweep point (about an hour on 2 cores from a cold cache, 46 minutes with the
#          scenes and truth cached; finished cells are reused, so on a machine with a call limit it is run again until
#          done, each call resuming the last)
#   smoke  tiny resolutions, seconds on 2 cores: checks the pipeline end to end, its numbers mean nothing
# Environment: CCDBENCH_BIN (a built ccdbench; default: build it with scripts/build.sh release), BEFORE_BIN (the
# build before issue 37's changes for profile/; default: scripts/apccd-profile.sh builds it), OUT (default
# reports/apccd-paper/PROFILE), CCDBENCH_CACHE_DIR (scenes and truth; default build/cache), CELLS (finished cells
# reused by a rerun after an interruption; default build/paper-cells/PROFILE), THREADS (default: all cores).
set -euo pipefail
cd "$(dirname "$0")/.."
profile=${1:-quick}
case "$profile" in
  quick)
    steps=10 repeats=3 crossover_repeats=3 res_scale=1 memory_res="48 64 80 100" memory_frames=11
    spf_list="1 2 4 8 16" crossover_frames=5 winds="0 4 8 16 32" ;;
  full)
    steps=99 repeats=1 crossover_repeats=3 res_scale=1 memory_res="48 64 80 100 128" memory_frames=21
    spf_list="1 2 4 8 16 32" crossover_frames=9 winds="0 2 4 8 12 16 24 32" ;;
  smoke)
    steps=3 repeats=1 crossover_repeats=1 res_scale=8 memory_res="8 12" memory_frames=3
    spf_list="1 4" crossover_frames=3 winds="0 8" ;;
  *) echo "reproduce-paper.sh: unknown profile '$profile' (quick, full or smoke)" >&2; exit 2 ;;
esac
if [[ -z "${CCDBENCH_BIN:-}" ]]; then
  scripts/build.sh release
  CCDBENCH_BIN=build/release/bin/ccdbench
fi
out=${OUT:-reports/apccd-paper/$profile}
cells=${CELLS:-build/paper-cells/$profile}
export CCDBENCH_CACHE_DIR=${CCDBENCH_CACHE_DIR:-$PWD/build/cache}
threads=()
[[ -n "${THREADS:-}" ]] && threads=(--threads "$THREADS")
# Results are written next to the final folder and moved into place at the end: an interrupted run leaves the old
# report whole, and its finished cells in $cells for the rerun.
work="$out.partial"
rm -rf "$work"
mkdir -p "$work/raw" "$work/scenes" "$cells"
started=$(date +%s)
frames=$((steps + 1))
# Paper scale: resolution 100 (twist 80, pile 64, as `ccdbench run --suite paper`); smoke divides it.
res() { echo $(( $1 / res_scale )); }

scene() {  # scene NAME FILE-STEM KEY=VALUE...: a scene file with a generator block
  local name=$1 stem=$2
  shift 2
  local keys="\"name\": \"$name\""
  for kv in "$@"; do keys+=", \"${kv%%=*}\": ${kv#*=}"; done
  echo "{\"generator\": {$keys}}" > "$work/scenes/$stem.json"
  echo "$work/scenes/$stem.json"
}

run() {  # run EXPERIMENT VERIFY REPEATS STRATEGIES SCENE-FILES...
  local experiment=$1 verify=$2 repeat=$3 strategies=$4
  shift 4
  local command=("$CCDBENCH_BIN" "${threads[@]}" run --scene "$@" --strategy "$strategies" --verify "$verify" --repeat "$repeat"
                 --out "$cells/$experiment" --json "$work/raw/$experiment.json")
  echo "== $experiment ($(( $(date +%s) - started )) s so far): ${#@} scenes, strategies $strategies, verify $verify"
  # The command as a reader would type it from the repository root: the release build's ccdbench (whichever build
  # ran it; its revision is in every record), the scenes by their file names in the report.
  printf '%s\tbuild/release/bin/ccdbench %s\n' "$experiment" "${command[*]:1}" | sed "s#$work/#$out/#g" >> "$work/raw/commands.tsv"
  "${command[@]}" > "$work/raw/$experiment.txt"
  echo "== $experiment done at $(( $(date +%s) - started )) s"
}

# 0. The map (issue 37): apccd against full over motion per step, resolution, every paper scene and both narrow
#    phases, with session lengths and why sessions end (scripts/apccd-map.sh; BACKENDS adds opencl). Its OpenCL half
#    on a GPU machine is scripts/device-apccd-map.sh, into PROFILE/map-device/ (kept when this script runs again).
OUT="$work/map" SHOWN_AS="$out/map" CELLS="$cells/map" CCDBENCH_BIN="$CCDBENCH_BIN" scripts/apccd-map.sh "$profile"

# 1. Attribution (claims 2, 4, 6): the paper suite at each scene's δ, every step verified. full:filter=on runs the
#    same distance heuristic as apccd, so apccd's gain splits into the heuristic's and skipping's; skip=off is the
#    heuristic alone; object_pairs=session and history=persistent are the paper's pipeline where ours departs.
paper_scenes=(
  "$(scene spinning-ball spinning-ball resolution=$(res 100) frames=$frames)"
  "$(scene drape drape resolution=$(res 100) frames=$frames)"
  "$(scene flag flag resolution=$(res 100) frames=$frames)"
  "$(scene twist twist resolution=$(res 80) frames=$frames)"
  "$(scene funnel funnel resolution=$(res 100) frames=$frames)"
  "$(scene pile pile resolution=$(res 64) frames=$frames)")
run attribution exact "$repeats" "full,full:filter=on,apccd,apccd:skip=off,apccd:object_pairs=session,apccd:history=persistent" "${paper_scenes[@]}"

# 2. Crossover: the same simulated motion cut into more, smaller CCD steps (steps_per_frame), on two scenes that
#    deform from their first frame (drape and the pile fall rigidly for their first frames: no relative motion).
#    Where does skipping frames start to pay (apccd against apccd:skip=off)?
crossover_scenes=()
for scene_res in flag:100 twist:80; do
  scene_name=${scene_res%%:*}
  for spf in $spf_list; do
    crossover_scenes+=("$(scene "$scene_name" "crossover-$scene_name-spf$spf" resolution=$(res "${scene_res#*:}") frames=$crossover_frames steps_per_frame=$spf)")
  done
done
run crossover exact "$crossover_repeats" "full:filter=on,apccd,apccd:skip=off" "${crossover_scenes[@]}"

# 3. Wind (claim 3): the flag under a sweep of its mean wind speed, at one CCD step per frame and at four.
wind_scenes=()
for wind in $winds; do
  for spf in 1 4; do
    # As many CCD steps at four per frame as at one (a quarter of the simulated time), at least one frame.
    wind_frames=$(( steps / spf > 0 ? steps / spf + 1 : 2 ))
    wind_scenes+=("$(scene flag "wind-$wind-spf$spf" resolution=$(res 100) frames=$wind_frames wind=$wind steps_per_frame=$spf)")
  done
done
run wind exact "$repeats" "full:filter=on,apccd,apccd:skip=off" "${wind_scenes[@]}"

# 4. Memory (claims 1, 5): the spinning ball at resolutions that bracket the paper's 142k pending pairs, history off
#    and persistent. Not verified: memory and pending pairs do not depend on the truth, and the same code is
#    verified in the attribution runs above.
memory_scenes=()
for r in $memory_res; do
  memory_scenes+=("$(scene spinning-ball "memory-r$r" resolution=$r frames=$memory_frames)")
done
run memory none "$repeats" "apccd,apccd:history=persistent" "${memory_scenes[@]}"

# 5. The seed's claims not yet judged (issue 37; rules in claims.py, written before measuring), where skipping can
#    pay (the map: sessions reach nf_max at 8 CCD steps per frame): the paper scenes at 8 steps per frame, from
#    frame 20 (contact), every step verified. history=persistent with cubic64 (a narrow phase that misses: what
#    history catches), dangling_max=0 (every dangling vertex ends the session: a full re-traversal instead of the
#    partial one), global-only and local-only inflation, and a fixed nf against the adaptive one.
seed_frames=$(( steps / 8 + 1 > 2 ? steps / 8 + 1 : 2 ))
seed_scenes=(
  "$(scene spinning-ball seed-spinning-ball resolution=$(res 100) frames=$((20 + seed_frames)) first_frame=20 steps_per_frame=8)"
  "$(scene drape seed-drape resolution=$(res 100) frames=$((20 + seed_frames)) first_frame=20 steps_per_frame=8)"
  "$(scene flag seed-flag resolution=$(res 100) frames=$((20 + seed_frames)) first_frame=20 steps_per_frame=8)"
  "$(scene twist seed-twist resolution=$(res 80) frames=$((20 + seed_frames)) first_frame=20 steps_per_frame=8)"
  "$(scene funnel seed-funnel resolution=$(res 100) frames=$((20 + seed_frames)) first_frame=20 steps_per_frame=8)"
  "$(scene pile seed-pile resolution=$(res 64) frames=$((20 + seed_frames)) first_frame=20 steps_per_frame=8)")
run seed exact "$repeats" "apccd,apccd:dangling_max=0,apccd:local=0:global=1.25,apccd:local=1:global=0,apccd:nf_min=4:nf_max=4,apccd+cubic64,apccd+cubic64:history=persistent" "${seed_scenes[@]}"

# 6. apccd's stages before and after issue 37's changes, the two builds side by side (scripts/apccd-profile.sh).
OUT="$work/profile" SHOWN_AS="$out/profile" CCDBENCH_BIN="$CCDBENCH_BIN" scripts/apccd-profile.sh "$profile"

elapsed=$(( $(date +%s) - started ))
printf 'profile\t%s\nelapsed_s\t%s\nthreads\t%s\n' "$profile" "$elapsed" "${THREADS:-all}" > "$work/raw/run.tsv"
if /usr/bin/python3 -c "import matplotlib" 2>/dev/null; then
  /usr/bin/python3 reports/apccd-paper/claims.py "$work" "$out"
else
  # A machine without Debian's python3-matplotlib (the GPU machine) keeps the runs; render them elsewhere.
  echo "reproduce-paper.sh: no /usr/bin/python3 with matplotlib here; render with:" \
       "/usr/bin/python3 reports/apccd-paper/claims.py $out" >&2
fi
# The GPU machine's map (scripts/device-apccd-map.sh) is not made here: it stays.
if [[ -d "$out/map-device" && ! -e "$work/map-device" ]]; then mv "$out/map-device" "$work/map-device"; fi
rm -rf "$out"
mv "$work" "$out"
echo "report: $out/CLAIMS.md and $out/README.md ($elapsed s of runs)"
