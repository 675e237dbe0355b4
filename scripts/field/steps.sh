# Whole steps for reports/field/ (sourced by scripts/field/report.sh, whose variables and `step` it uses): every method
# as the narrow phase of ccdbench's `full` (`full+plugin:`), every step verified against the exact truth.
#  - cloth-funnel's public step (41,089 elementary tests), every method, δ = 0 (the data's own question);
#  - rod-twist's public step (2.49 million tests), every method whose cloth-funnel step took at most
#    max_us_per_test a test: the others would take longer than the report's budget on this one step;
#  - the built-in scenes in which pairs collide at this size (spinning-ball, drape, fold; 8 x 8 cloth, 5 steps), every
#    method at δ = 0. Not at the scenes' own δ (5% of an edge): on the first scene alone Tight-Inclusion took about 2
#    minutes and ipc-toolkit's TightInclusionCCD 4 on this machine (the stage was stopped there), past the budget;
#    the methods' δ > 0 answers are judged on the queries instead (report.sh's delta table).
# shellcheck shell=bash
max_us_per_test=40
steps_timeout=$timeout_timed
funnel=$data/scalable-ccd-sample/cloth-funnel/frames
rod=$data/scalable-ccd-sample/rod-twist/frames
strategies() {  # strategies SPECS: full and full+cubic64, then full+METHOD for each plugin of SPECS
  local list=(full full+cubic64) spec
  IFS=, read -r -a all <<<"$1"
  for spec in "${all[@]}"; do [[ $spec == plugin:* ]] && list+=("full+$spec"); done
  local IFS=,
  echo "${list[*]}"
}
step "steps cloth-funnel" "$ccdbench" --threads 1 run --frames "$funnel/227.ply" "$funnel/228.ply" --thickness 0 --toi \
  --strategy "$(strategies "$(specs $steps_timeout)")" --json "$out/steps-cloth-funnel.json" --out "$report/runs" --fresh
fast=$($python - "$out/steps-cloth-funnel.json" $max_us_per_test <<'EOF'
import json, sys
limit = float(sys.argv[2])
print(",".join(s["spec"][len("full+"):] for s in json.load(open(sys.argv[1]))
               if s["spec"].startswith("full+plugin:") and s["ms_per_step"] * 1000.0 / max(s["elementary_tests"], 1) <= limit))
EOF
)
step "steps rod-twist" "$ccdbench" --threads 1 run --frames "$rod/3036.ply" "$rod/3037.ply" --thickness 0 --toi --strategy "$(strategies "$fast")" \
  --json "$out/steps-rod-twist.json" --out "$report/runs" --fresh
for scene in spinning-ball drape fold; do
  step "scene $scene" "$ccdbench" generate "$scene" --resolution 8 --frames 6 --out "$report/scenes/$scene"
done
scenes=("$report/scenes/spinning-ball" "$report/scenes/drape" "$report/scenes/fold")
step "steps scenes" "$ccdbench" --threads 1 run --scene "${scenes[@]}" --thickness 0 --toi --strategy "$(strategies "$(specs $steps_timeout)")" \
  --json "$out/steps-scenes.json" --out "$report/runs" --fresh
