#!/usr/bin/env bash
# Runs the README's "Audit your CCD" walkthrough exactly as the README writes it (its two code blocks, extracted
# from README.md, then the "CI regression" block, in a shell that stops at the first failing command), from the repository's root, with HOME a fresh
# folder (the walkthrough installs into ~/ccdbench and copies the template to ~/my-ccd). scripts/test.sh runs it
# after the Release tests; it needs the public data (scripts/data-dir.sh finds it) and says so when it is absent.
# Usage: scripts/readme-walkthrough.sh   (after scripts/build.sh release)
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/data-dir.sh
if [ -z "${CCDBENCH_DATA_DIR:-}" ]; then
  echo "readme-walkthrough: skipped: it needs the public data (docs/DATA.md): run scripts/fetch-data.sh, or set CCDBENCH_DATA_DIR"
  exit 0
fi
# The walkthrough's blocks: the first two ```sh blocks after its heading.
script=$(awk '/^### Walkthrough, from a fresh clone/ {on = 1} on && /^```sh/ {inside = 1; ++blocks; next} inside && /^```/ {inside = 0; if (blocks == 2) exit; next} inside {print}' README.md)
[ "$(grep -c 'ccdbench ' <<<"$script")" -ge 6 ] || { echo "readme-walkthrough: the README's walkthrough was not found" >&2; exit 1; }
home=$(mktemp -d)
trap 'rm -rf "$home"' EXIT
log=$home/walkthrough.log
echo "readme-walkthrough: running the README's walkthrough (HOME=$home):"
sed 's/^/  | /' <<<"$script"
if ! HOME=$home bash -euo pipefail -c "$script" >"$log" 2>&1; then
  tail -n 40 "$log"
  echo "readme-walkthrough: FAILED (the log above ends where it stopped)" >&2
  exit 1
fi
grep -E '^(fold|\(all\)|check:)|^plugin:.*\(all\)' "$log" | cut -c1-200 || true
echo "readme-walkthrough: every command of the walkthrough succeeded"

# "CI regression": its block, from the repository's root (it works in a folder of its own), and the lines the README
# shows of its output.
ci=$(awk '/^## CI regression/ {on = 1} on && /^```sh/ {inside = 1; next} inside && /^```/ {exit} inside {print}' README.md)
[ "$(grep -c 'ccdbench ' <<<"$ci")" -ge 5 ] || { echo "readme-walkthrough: the README's CI regression block was not found" >&2; exit 1; }
echo "readme-walkthrough: running the README's CI regression block:"
sed 's/^/  | /' <<<"$ci"
if ! HOME=$home bash -euo pipefail -c "$ci" >"$log" 2>&1; then
  tail -n 40 "$log"
  echo "readme-walkthrough: the CI regression block FAILED (the log above ends where it stopped)" >&2
  exit 1
fi
grep -E '^(entry|ok|FAIL|check|compare|cell|fold8 /)|^  (missed|plugin code|answers|newly|written)' "$log" | cut -c1-220
for expected in 'check: wrote 1 entry' 'check: every result within its baseline' 'check exit status 1' 'newly missed at step' 'compare exit status 1'; do
  grep -q "$expected" "$log" || { echo "readme-walkthrough: the CI regression block did not print '$expected'" >&2; exit 1; }
done
echo "readme-walkthrough: the CI regression block printed what the README shows"
