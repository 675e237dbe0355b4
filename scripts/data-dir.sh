# Sourced by the scripts that use the public data with exact ground truth (docs/DESIGN.md §7): exports
# CCDBENCH_DATA_DIR, when it is not set already, as the first of these folders that holds the data:
#   data/external (where scripts/fetch-data.sh puts it), ../shared/data (a copy beside the checkout).
# Leaves it unset when neither does: the data tests then skip, each saying how to get the data.
if [ -z "${CCDBENCH_DATA_DIR:-}" ]; then
  for ccdbench_data_candidate in "$PWD/data/external" "$(cd .. && pwd)/shared/data"; do
    if [ -d "$ccdbench_data_candidate/sample-queries" ] && [ -d "$ccdbench_data_candidate/scalable-ccd-sample" ]; then
      export CCDBENCH_DATA_DIR=$ccdbench_data_candidate
      break
    fi
  done
  unset ccdbench_data_candidate
fi
