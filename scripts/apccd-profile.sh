#!/usr/bin/env bash
# The profile of apccd's stages before and after issue 37's changes (reports/apccd-paper/PROFILE/profile/): two
# ccdbench builds side by side on one machine in one invocation, in rounds (before, after, before, after, ...) so that
# a drift of the machine touches both alike. Each round runs full and apccd with both narrow phases (and, with the
# after build, apccd+cubic64:heuristic=boxes, which the before build lacks) over the paper scenes from frame 20 at 4
# and 16 CCD steps per frame, --verify none: the map verifies these strategies; here the answers of every step are
# compared between the builds by their digests instead (they must agree: the changes are for speed only; the script
# fails where one differs). Not resumable: a run starts again from its first round.
# reports/apccd-paper/profile.py then writes profile.md: per cell, the median over the rounds of each build's mean
# ms per step and of each stage.
# Usage: scripts/apccd-profile.sh [quick|full|smoke]
#   smoke  resolution 12, one round: checks the pipeline, its numbers mean nothing
#   quick  resolution 64 (twist 51, pile 41), 5 rounds
#   full   resolution 100 (twist 80, pile 64, as the paper suite), 5 rounds
# Environment: BEFORE (the revision before, default 7664fb0: built once in a worktree under build/before-REV unless
# BEFORE_BIN names a ccdbench build of it), CCDBENCH_BIN (the build after; default: build it), OUT (default
# reports/apccd-paper/PROFILE/profile), SHOWN_AS (the folder the report is read from, for the commands it prints;
# default OUT), CCDBENCH_CACHE_DIR, THREADS, ROUNDS, BACKENDS ("cpu", "opencl" or both).
set -euo pipefail
cd "$(dirname "$0")/.."
profile=${1:-quick}
case "$profile" in
  smoke) resolution=12 rounds=1 ;;
  quick) resolution=64 rounds=5 ;;
  full) resolution=100 rounds=5 ;;
  *) echo "apccd-profile.sh: unknown profile '$profile' (smoke, quick or full)" >&2; exit 2 ;;
esac
rounds=${ROUNDS:-$rounds}
before=${BEFORE:-7664fb0}
if [[ -z "${CCDBENCH_BIN:-}" ]]; then
  scripts/build.sh release
  CCDBENCH_BIN=build/release/bin/ccdbench
fi
if [[ -z "${BEFORE_BIN:-}" ]]; then
  source=build/before-$before
  if [[ ! -x "$source/build/release/bin/ccdbench" ]]; then
    rm -rf "$source"
    git worktree prune
    git worktree add --detach "$source" "$before" > /dev/null
    (cd "$source" && cmake --preset release > /dev/null && cmake --build --preset release --target ccdbench -j "$(nproc)" > /dev/null)
  fi
  BEFORE_BIN=$source/build/release/bin/ccdbench
fi
out=${OUT:-reports/apccd-paper/$profile/profile}
shown=${SHOWN_AS:-$out}
export CCDBENCH_CACHE_DIR=${CCDBENCH_CACHE_DIR:-$PWD/build/cache}
threads=()
[[ -n "${THREADS:-}" ]] && threads=(--threads "$THREADS")
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# A run starts from an empty folder: profile.py reads every round it finds there.
rm -rf "$out/raw" "$out/scenes"
mkdir -p "$out/raw" "$out/scenes"
started=$(date +%s)

scenes=()
for name in spinning-ball drape flag twist funnel pile; do
  case "$name" in twist) res=$(( resolution * 4 / 5 )) ;; pile) res=$(( resolution * 16 / 25 )) ;; *) res=$resolution ;; esac
  for spf in 4 16; do
    stem="$name-r$res-spf$spf"
    echo "{\"generator\": {\"name\": \"$name\", \"resolution\": $res, \"frames\": 23, \"first_frame\": 20, \"steps_per_frame\": $spf}}" \
      > "$out/scenes/$stem.json"
    scenes+=("$out/scenes/$stem.json")
  done
done

strategies_of() {  # strategies_of VARIANT: what the build runs (the before build lacks heuristic=boxes)
  local list="" backend suffix
  for backend in ${BACKENDS:-cpu}; do
    suffix=""
    [[ "$backend" == opencl ]] && suffix=":backend=opencl"
    list+="${list:+,}full+cubic64$suffix,apccd+cubic64$suffix,full$suffix,apccd$suffix"
    [[ "$1" == after ]] && list+=",apccd+cubic64:heuristic=boxes$suffix"
  done
  echo "$list"
}
{
  echo "# The profile's runs (scripts/apccd-profile.sh $profile), as typed from the repository root: $rounds rounds of"
  echo "# both builds in turn; BEFORE is a build of $before, AFTER this revision's."
  for variant in before after; do
    echo "ccdbench-${variant^^} ${threads[*]:+${threads[*]} }run --scene $shown/scenes/*.json --strategy $(strategies_of "$variant") --verify none --repeat 1 --out CELLS --json $shown/raw/$variant-ROUND.json --fresh"
  done
} > "$out/raw/command.txt"
for round in $(seq 1 "$rounds"); do
  for variant in before after; do
    bin=$CCDBENCH_BIN
    [[ "$variant" == before ]] && bin=$BEFORE_BIN
    echo "== round $round of $rounds, $variant ($(( $(date +%s) - started )) s so far)"
    "$bin" "${threads[@]}" run --scene "${scenes[@]}" --strategy "$(strategies_of "$variant")" --verify none --repeat 1 \
      --out "$work/$variant-$round" --json "$out/raw/$variant-$round.json" --fresh > /dev/null
  done
done
# Every step's answers digest, before against after (the first round; the same strategies' resolved names).
/usr/bin/python3 - "$work/before-1/results.jsonl" "$work/after-1/results.jsonl" > "$out/raw/answers.tsv" <<'EOF'
import json, sys
def digests(path):
    out = {}
    for line in open(path):
        record = json.loads(line)
        if record.get("record") == "step":
            out[(record["scene"], record["strategy"], record["step"])] = record["answers"]
    return out
before, after = digests(sys.argv[1]), digests(sys.argv[2])
common = sorted(set(before) & set(after))
print("compared_steps\tdiffering_steps")
print(f"{len(common)}\t{sum(1 for k in common if before[k] != after[k])}")
EOF
# The changes are for speed only: a step whose answers differ between the builds is a defect, and so is a run that
# compared none.
read -r compared differing < <(tail -n 1 "$out/raw/answers.tsv")
if [[ "$compared" == 0 || "$differing" != 0 ]]; then
  echo "apccd-profile.sh: $differing of $compared steps answer differently before and after" >&2
  exit 1
fi
printf 'profile\t%s\nelapsed_s\t%s\nthreads\t%s\nrounds\t%s\nbefore\t%s\nbackends\t%s\n' "$profile" "$(( $(date +%s) - started ))" \
  "${THREADS:-all}" "$rounds" "$before" "${BACKENDS:-cpu}" > "$out/raw/run.tsv"
if /usr/bin/python3 -c "import json" 2>/dev/null; then
  /usr/bin/python3 reports/apccd-paper/profile.py "$out"
else
  echo "apccd-profile.sh: no /usr/bin/python3 here; render with: /usr/bin/python3 reports/apccd-paper/profile.py $out" >&2
fi
echo "profile: $out/profile.md ($(( $(date +%s) - started )) s)"
