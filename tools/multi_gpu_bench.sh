#!/usr/bin/env bash
# N-GPU / 1-GPU PPO throughput and learning, on one host with >= N GPUs (GPUS, default 2), from the project root:
#   T=300 NUM_ENVS=4096 TASK=gente_biped_flat tools/multi_gpu_bench.sh
#   GPUS=4 T=110 NUM_ENVS=8192 TASK=gente_biped tools/multi_gpu_bench.sh
# Trains for T seconds on cuda:0 alone, then T seconds under torchrun on N GPUs with the same num_envs per
# rank and the same seed; prints each run's mean "Steps per second" (rsl-rl counts all ranks' steps:
# num_steps_per_env * num_envs * world_size / rank 0's iteration time), skipping the first SKIP iterations
# (kernel loading, CUDA-graph capture), their ratio, and the mean reward / episode length of each run at its
# last iteration and at the last iteration both reached (each N-GPU iteration learns from N times the samples);
# every iteration of both runs goes to $OUT_DIR/multi_gpu.csv, their reward curves to multi_gpu.png
# (tools/multi_gpu_report.py).
set -uo pipefail
T=${T:-300}
NUM_ENVS=${NUM_ENVS:-4096}
TASK=${TASK:-gente_biped_flat}
SKIP=${SKIP:-3}
GPUS=${GPUS:-2}
OUT_DIR=${OUT_DIR:-/tmp/gente_multi_gpu}
# NVLink multicast off, as the runner keeps it by default (docs/multi_gpu.md)
export NCCL_NVLS_ENABLE=0 TORCH_SYMM_MEM_DISABLE_MULTICAST=1 PYTHONUNBUFFERED=1

gpus=$(python3 -c "import torch; print(torch.cuda.device_count())")
[ "$gpus" -ge "$GPUS" ] && [ "$GPUS" -ge 2 ] || { echo "multi_gpu_bench.sh: GPUS=$GPUS needs 2 or more GPUs and at most the $gpus found" >&2; exit 1; }
mkdir -p "$OUT_DIR"

# SIGINT after T s: train.py saves a checkpoint and exits; -k: SIGKILL 60 s later if a rank still hangs
train() {
  local name=$1; shift
  echo "== $name: $* (T=${T}s, num_envs=$NUM_ENVS per rank)"
  GENTE_LOG_ROOT="$OUT_DIR/$name" timeout -k 60 -s INT "$T" "$@" --task="$TASK" --headless \
    --num_envs "$NUM_ENVS" --max_iterations 1000000 --seed 1 > "$OUT_DIR/$name.log" 2>&1
  # torchrun's own traceback for the SIGINT sent above ("SignalException: Process N got signal: 2") is expected
  grep -E "^\[distributed\]|Error|^Interrupted: saved" "$OUT_DIR/$name.log" | grep -v "SignalException: Process [0-9]* got signal: 2" | head -5
}
# warm-up: compile the Warp kernels and the torch.compile'd step logic (specialised to NUM_ENVS) once, into their
# on-disk caches, so that neither timed run pays for it (with a 64-env warm-up, at commit 99ae644 and T=45, the
# 1-GPU run's first iteration took 20.9 s and the 2-GPU run logged no iteration at all)
GENTE_LOG_ROOT="$OUT_DIR/warmup" python3 legged_gente/scripts/train.py --task="$TASK" --headless --num_envs "$NUM_ENVS" \
  --max_iterations 1 --device cuda:0 > "$OUT_DIR/warmup.log" 2>&1 || { tail -20 "$OUT_DIR/warmup.log"; exit 1; }
train 1gpu python3 legged_gente/scripts/train.py --device cuda:0
train "${GPUS}gpu" python3 -m torch.distributed.run --standalone --nproc_per_node="$GPUS" legged_gente/scripts/train.py

python3 tools/multi_gpu_report.py "$OUT_DIR/1gpu.log" "$OUT_DIR/${GPUS}gpu.log" --gpus "$GPUS" --skip "$SKIP" --csv "$OUT_DIR/multi_gpu.csv" \
  --plot "$OUT_DIR/multi_gpu.png"
