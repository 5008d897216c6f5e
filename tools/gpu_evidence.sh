#!/usr/bin/env bash
# GPU evidence, run on the lent GPU machine after ../shared/device staging. The evaluation needs jsonschema,
# which the device lacks: stage it with ../shared/device/prepare jsonschema==4.26.0 jsonschema-specifications
# referencing rpds-py attrs (or carry their cp312 wheels in .whl and pip install --target /tmp/site).
#   phase train:   train $TASK at $NUM_ENVS envs for $TRAIN_SECONDS (RESUME=1 continues the latest run)
#   phase report:  benchmark (+ sync check, CSV), play (tracking plot + exports), scalars CSV -> $OUT
#   phase eval:    gente-evaluate the latest $TASK run on benchmarks/gente100 -> $OUT/eval
set -uo pipefail
phase=${1:?usage: gpu_evidence.sh train|report|eval}
export GENTE_LOG_ROOT=${GENTE_LOG_ROOT:-/tmp/gente_logs}
task=${TASK:-gente_biped_flat}
latest_run() { ls -d "$GENTE_LOG_ROOT/$task"/20* | tail -1; }
case "$phase" in
  train)
    extra=(); [ "${RESUME:-0}" = 1 ] && extra=(--resume)
    timeout -s INT "${TRAIN_SECONDS:-480}" python3 legged_gente/scripts/train.py --task="$task" --headless \
      --num_envs "${NUM_ENVS:-4096}" --max_iterations "${MAX_ITERS:-100000}" "${extra[@]}" 2>&1 \
      | grep -E "Learning iteration|Mean reward|Mean episode length|rew_tracking_lin_vel|terrain_level|Iteration time|Steps per second|Logging|Interrupted|Error|error|Traceback" ;;
  report)
    python3 -m legged_gente.scripts.benchmark --task "$task" --num_envs ${BENCH_ENVS:-1024 4096 8192} --check_sync \
      --csv "$OUT/${task}_benchmark.csv" 2>&1 | tail -12
    python3 legged_gente/scripts/play.py --task="$task" --headless --steps 500 2>&1 | tail -3
    python3 -m legged_gente.utils.tb_export "$(latest_run)" "$OUT/${task}_scalars.csv"
    cp "$GENTE_LOG_ROOT/$task/exported/velocity_tracking.png" "$OUT/${task}_velocity_tracking.png"
    ls -t "$(latest_run)"/model_*.pt | head -1 | xargs -I{} cp {} "$OUT/${task}_last.pt" ;;
  eval)
    python3 -m legged_gente.scripts.evaluate --task "$task" --checkpoint "$(latest_run)" --benchmark benchmarks/gente100 \
      --robots_per_terrain "${ROBOTS:-16}" --out "$OUT/eval" --device cuda --no_progress 2>&1 | grep -v "^Module" | tail -12 ;;
  *) echo "unknown phase $phase: use train, report or eval" >&2; exit 2 ;;
esac
