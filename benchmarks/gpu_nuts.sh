#!/usr/bin/env bash
# NUTS on the shipped campaigns on a GPU machine: the models the shipped
# calibrations chose (refitted by `posterior_nuts.py --choose` on any machine,
# written to benchmarks/records/posterior_nuts_models.json) sampled by `--chosen`, the
# four chains of a campaign vectorised on the GPU, PROCS campaigns at a time;
# the same host's CPU times one gradient of the first for comparison.
#
#   bash benchmarks/gpu_nuts.sh [PROCS] [SECONDS]
#
# Writes $OUT/posterior_nuts_gpu.json (rows as `posterior_nuts.py` records
# them; a campaign unfinished at SECONDS has none) and $OUT/log.txt.
set -u
PROCS=${1:-4}
LIMIT=${2:-500}
OUT=${OUT:-/tmp/gpu_nuts}
mkdir -p "$OUT"
if [ -d .whl ]; then   # packages the machine lacks, carried as wheels
  python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade \
    --target /tmp/site .whl/*.whl || exit 1
  export PYTHONPATH=/tmp/site
fi
export PYTHONPATH=$PWD/src${PYTHONPATH:+:$PYTHONPATH} PYTHONUNBUFFERED=1
export XLA_PYTHON_CLIENT_PREALLOCATE=false   # several processes share the GPU
MODELS=benchmarks/records/posterior_nuts_models.json
python3 -c "
import jax, diffrax, equinox, optimistix, lineax, optax, blackjax, numpy
print({m.__name__: m.__version__ for m in (jax, diffrax, equinox, optimistix, lineax, optax,
       blackjax, numpy)}, jax.devices())" 2>&1 | tee "$OUT/log_versions.txt"
nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader
# the angle-dependent and pressure-law campaigns first (the ones whose k and
# exponent a user carries to a design), dealt round-robin to the processes
CAMPAIGNS=(campaign_two_lobe_k campaign_pressure_exponent campaign_three_lobe_k
           campaign_run_in_and_lobes campaign_lobed_bore campaign_run_in_and_creep
           campaign_low_wear_skin campaign_coating_worn_through campaign_humidity_k
           campaign_clean campaign_long_crank campaign_run_in_weak_creep
           campaign_slow_run_in campaign_unseen_run_in)
for ((i = 0; i < PROCS; i++)); do
  mine=()
  for ((j = i; j < ${#CAMPAIGNS[@]}; j += PROCS)); do mine+=("${CAMPAIGNS[j]}"); done
  timeout "$LIMIT" python3 benchmarks/posterior_nuts.py "${mine[@]}" --chosen "$MODELS" \
    --json "$OUT/rows_$i.json" >"$OUT/log_$i.txt" 2>&1 &
done
JAX_PLATFORMS=cpu timeout "$LIMIT" python3 benchmarks/posterior_nuts.py "${CAMPAIGNS[0]}" \
  --chosen "$MODELS" --gradient-only --json "$OUT/rows_cpu.json" >"$OUT/log_cpu.txt" 2>&1 &
wait
python3 - "$OUT" <<'PY'
import json, pathlib, sys
out = pathlib.Path(sys.argv[1])
rows = [r for f in sorted(out.glob("rows_*.json")) for r in json.loads(f.read_text())["rows"]]
(out / "posterior_nuts_gpu.json").write_text(json.dumps({"rows": rows}, indent=2) + "\n")
PY
for f in "$OUT"/log_*.txt; do echo "== $f"; cat "$f"; done >"$OUT/log.txt"
rm -f "$OUT"/rows_*.json "$OUT"/log_*.txt
grep -hE "R-hat|gradient|Error|error" "$OUT/log.txt" | tail -n 40
