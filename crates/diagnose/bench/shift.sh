#!/usr/bin/env bash
# Benchmark (issue 13): diagnose an 8-hour shift bag of crates/twin/examples/cells/xfyz_shift.yaml
# without camera frames, against a model that lacks the X reversal error; prints the time from bag to
# diagnosis and the ratios against building the records and against the declared fit alone (peers in
# the same run). Usage: crates/diagnose/bench/shift.sh [DURATION] (default 8h); WORK=dir to keep files.
set -euo pipefail
cd "$(dirname "$0")/../../.."
duration="${1:-8h}"
work="${WORK:-$(mktemp -d)}"
cargo build --release -p metrocell-cli --bin metrocell -p metrocell-diagnose --example shift_bench >&2
# the cell without its camera (no frames in the bag), and the model: the same cell without the backlash term
python3 - "$work" <<'PY'
import re, sys
work = sys.argv[1]
text = open("crates/twin/examples/cells/xfyz_shift.yaml").read()
start = text.index("  camera:")
end = text.index("environment:")
truth = text[:start] + text[end:]
model = re.sub(r"  - id: backlash\n    options: \{axis: x\}\n    params: \{reversal: 8 um\}\n", "", truth)
assert model != truth
open(f"{work}/truth.yaml", "w").write(truth)
open(f"{work}/model.yaml", "w").write(model)
PY
if [ ! -d "$work/shift_bag" ]; then
  /usr/bin/time -f "sim: %e s wall, %M KB max RSS" target/release/metrocell sim --cell "$work/truth.yaml" --duration "$duration" -o "$work/shift_bag" --quiet
fi
/usr/bin/time -f "shift_bench: %e s wall, %M KB max RSS" target/release/examples/shift_bench "$work/model.yaml" "$work/shift_bag"
/usr/bin/time -f "metrocell diagnose: %e s wall, %M KB max RSS" target/release/metrocell diagnose --model "$work/model.yaml" "$work/shift_bag" --json "$work/result.json" > "$work/summary.txt"
head -3 "$work/summary.txt"
echo "files in $work"
