#!/usr/bin/env bash
# The accelerator records, from one prepared run on a GPU machine: the batched
# workloads on the GPU, then the same host's CPU (smaller batches), each to
# benchmarks/records/ (about five minutes on an H100 host; see gpu.py).
#
#   bash benchmarks/gpu.sh            # with jax[cuda], equinox, diffrax, optimistix
set -euo pipefail
cd "$(dirname "$0")/.."
stamp=$(date +%Y%m%d)
python benchmarks/gpu.py --json "benchmarks/records/gpu_${stamp}_gpu.json"
JAX_PLATFORMS=cpu python benchmarks/gpu.py --json "benchmarks/records/gpu_${stamp}_host_cpu.json"
