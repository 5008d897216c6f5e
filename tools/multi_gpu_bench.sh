#!/usr/bin/env bash
# 2-GPU / 1-GPU PPO throughput and learning, on one host with >= 2 GPUs, from the project root:
#   T=300 NUM_ENVS=4096 TASK=gente_biped_flat tools/multi_gpu_bench.sh
# Trains for T seconds on cuda:0 alone, then T seconds under torchrun on 2 GPUs with the same num_envs per
# rank and the same seed; prints each run's mean "Steps per second" (rsl-rl counts all ranks' steps:
# num_steps_per_env * num_envs * world_size / rank 0's iteration time), skipping the first SKIP iterations
# (kernel loading, CUDA-graph capture), their ratio, and the mean reward / episode length of each run at its
# last iteration and at the last iteration both reached (each 2-GPU iteration learns from twice the samples).
set -uo pipefail
T=${T:-300}
NUM_ENVS=${NUM_ENVS:-4096}
TASK=${TASK:-gente_biped_flat}
SKIP=${SKIP:-3}
OUT_DIR=${OUT_DIR:-/tmp/gente_multi_gpu}
# NVLink multicast off: on the lent hosts it can put the shared GPUs out of service (docs/multi_gpu.md)
export NCCL_NVLS_ENABLE=0 TORCH_SYMM_MEM_DISABLE_MULTICAST=1 PYTHONUNBUFFERED=1

gpus=$(python3 -c "import torch; print(torch.cuda.device_count())")
[ "$gpus" -ge 2 ] || { echo "multi_gpu_bench.sh needs 2 GPUs, found $gpus" >&2; exit 1; }
mkdir -p "$OUT_DIR"

# SIGINT after T s: train.py saves a checkpoint and exits; -k: SIGKILL 60 s later if a rank still hangs
train() {
  local name=$1; shift
  echo "== $name: $* (T=${T}s, num_envs=$NUM_ENVS per rank)"
  GENTE_LOG_ROOT="$OUT_DIR/$name" timeout -k 60 -s INT "$T" "$@" --task="$TASK" --headless \
    --num_envs "$NUM_ENVS" --max_iterations 1000000 --seed 1 > "$OUT_DIR/$name.log" 2>&1
  grep -E "^\[distributed\]|Traceback|Error" "$OUT_DIR/$name.log" | head -5
}
# warm-up: compile/load the Warp kernels once, so neither timed run pays for it
GENTE_LOG_ROOT="$OUT_DIR/warmup" python3 legged_gente/scripts/train.py --task="$TASK" --headless --num_envs 64 \
  --max_iterations 1 --device cuda:0 > "$OUT_DIR/warmup.log" 2>&1 || { tail -20 "$OUT_DIR/warmup.log"; exit 1; }
train 1gpu python3 legged_gente/scripts/train.py --device cuda:0
train 2gpu python3 -m torch.distributed.run --standalone --nproc_per_node=2 legged_gente/scripts/train.py

python3 - "$OUT_DIR/1gpu.log" "$OUT_DIR/2gpu.log" "$SKIP" <<'EOF'
import re, statistics, sys

def parse(path):
    """Per iteration: steps/s, mean reward, mean episode length (rsl-rl's console log of rank 0)."""
    rows, row = {}, None
    for line in open(path, errors="replace"):
        if m := re.search(r"Learning iteration (\d+)/", line):
            row = rows.setdefault(int(m.group(1)), {})
        elif row is not None and (m := re.match(r"\s*(Steps per second|Mean reward|Mean episode length):\s*(\S+)", line)):
            row[m.group(1)] = float(m.group(2))
    return rows

one, two = parse(sys.argv[1]), parse(sys.argv[2])
skip = int(sys.argv[3])
for name, rows in (("1gpu", one), ("2gpu", two)):
    if len(rows) <= skip:
        sys.exit(f"{name}: only {len(rows)} iterations logged (need > SKIP={skip}); raise T or see its log")
sps = {name: statistics.mean(r["Steps per second"] for i, r in rows.items() if i >= min(rows) + skip)
       for name, rows in (("1gpu", one), ("2gpu", two))}

def learning(rows, it):
    r = rows[it]
    return f"iteration {it}: mean reward {r.get('Mean reward', float('nan')):.2f}, " \
           f"mean episode length {r.get('Mean episode length', float('nan')):.1f}"

common = min(max(one), max(two))
for name, rows in (("1gpu", one), ("2gpu", two)):
    print(f"{name}: {len(rows)} iterations, mean steps/s {sps[name]:.0f} (iterations after the first {skip})")
    print(f"      last   {learning(rows, max(rows))}")
    print(f"      common {learning(rows, common)}")
print(f"throughput ratio 2gpu/1gpu: {sps['2gpu'] / sps['1gpu']:.3f}")
EOF
