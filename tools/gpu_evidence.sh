#!/usr/bin/env bash
# GPU evidence for the foundation issue, run on the lent GPU machine after ../shared/device staging:
#   phase train:  train gente_biped_flat at 4096 envs for $TRAIN_SECONDS (resumes if RESUME=1)
#   phase report: benchmark, play (tracking plot + exports), scalars CSV -> $OUT
set -uo pipefail
phase=${1:?usage: gpu_evidence.sh train|report}
export GENTE_LOG_ROOT=${GENTE_LOG_ROOT:-/tmp/gente_logs}
task=${TASK:-gente_biped_flat}
case "$phase" in
  train)
    extra=(); [ "${RESUME:-0}" = 1 ] && extra=(--resume)
    timeout -s INT "${TRAIN_SECONDS:-480}" python3 legged_gente/scripts/train.py --task="$task" --headless \
      --num_envs "${NUM_ENVS:-4096}" --max_iterations "${MAX_ITERS:-100000}" "${extra[@]}" 2>&1 \
      | grep -E "Learning iteration|Mean reward|Mean episode length|rew_tracking_lin_vel|Total timesteps|Iteration time|Steps per second|Logging|Interrupted|Error|error|Traceback" ;;
  report)
    python3 -m legged_gente.scripts.benchmark --task "$task" --num_envs ${BENCH_ENVS:-1024 4096 8192} 2>&1 | tail -12
    python3 legged_gente/scripts/play.py --task="$task" --headless --steps 500 2>&1 | tail -3
    run=$(ls -d "$GENTE_LOG_ROOT/$task"/20* | tail -1)
    python3 -m legged_gente.utils.tb_export "$run" "$OUT/${task}_scalars.csv"
    cp "$GENTE_LOG_ROOT/$task/exported/velocity_tracking.png" "$OUT/${task}_velocity_tracking.png"
    ls -t "$run"/model_*.pt | head -1 | xargs -I{} cp {} "$OUT/${task}_last.pt" ;;
esac
