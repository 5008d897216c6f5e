#!/usr/bin/env bash
# GPU evidence, run on the lent GPU machine after ../shared/device staging. The evaluation needs jsonschema,
# which the device lacks: stage it with ../shared/device/prepare jsonschema==4.26.0 jsonschema-specifications
# referencing rpds-py attrs (or carry their cp312 wheels in .whl and pip install --target /tmp/site).
#   phase train:   train $TASK at $NUM_ENVS envs for $TRAIN_SECONDS (RESUME=1 continues the latest run; $TRAIN_ARGS
#                  are more train.py flags, e.g. "--set terrain.solved_top_level=stay"); the
#                  latest checkpoint and the run's scalars CSV go to $OUT after every chunk
#   phase report:  benchmark (+ sync check, CSV), play (tracking plot + exports), scalars CSV -> $OUT
#   phase eval:    gente-evaluate the latest $TASK run on benchmarks/gente100 -> $OUT/eval; with FIG_ITEMS="id id id"
#                  also figure (d), success over training on those items -> $OUT
set -uo pipefail
phase=${1:?usage: gpu_evidence.sh train|report|eval}
export GENTE_LOG_ROOT=${GENTE_LOG_ROOT:-/tmp/gente_logs}
task=${TASK:-gente_biped_flat}
latest_run() { ls -d "$GENTE_LOG_ROOT/$task"/20* | tail -1; }
case "$phase" in
  train)
    read -ra extra <<< "${TRAIN_ARGS:-}"; [ "${RESUME:-0}" = 1 ] && extra+=(--resume)
    timeout -s INT "${TRAIN_SECONDS:-480}" python3 legged_gente/scripts/train.py --task="$task" --headless \
      --num_envs "${NUM_ENVS:-4096}" --max_iterations "${MAX_ITERS:-100000}" "${extra[@]}" 2>&1 \
      | grep -E "Learning iteration|Mean episode length|terrain_level|Steps per second|Interrupted|Error|Traceback" | tail -8
    # a cold machine loses /tmp: bring the latest checkpoint and the run's scalars back after every chunk
    run=$(latest_run); ls -t "$run"/model_*.pt | head -1 | xargs -I{} cp {} "$OUT/${task}_last.pt"
    python3 -m legged_gente.utils.tb_export "$run" "$OUT/${task}_scalars_$(basename "$run").csv" ;;
  report)
    python3 -m legged_gente.scripts.benchmark --task "$task" --num_envs ${BENCH_ENVS:-1024 4096 8192} --check_sync \
      --csv "$OUT/${task}_benchmark.csv" 2>&1 | tail -12
    python3 legged_gente/scripts/play.py --task="$task" --headless --steps 500 2>&1 | tail -3
    python3 -m legged_gente.utils.tb_export "$(latest_run)" "$OUT/${task}_scalars.csv"
    cp "$(ls -td "$GENTE_LOG_ROOT/$task"/20*/exported | head -1)/velocity_tracking.png" "$OUT/${task}_velocity_tracking.png"
    ls -t "$(latest_run)"/model_*.pt | head -1 | xargs -I{} cp {} "$OUT/${task}_last.pt" ;;
  eval)
    python3 -m legged_gente.scripts.evaluate --task "$task" --checkpoint "$(latest_run)" --benchmark benchmarks/gente100 \
      --robots_per_terrain "${ROBOTS:-16}" --out "$OUT/eval" --device cuda --no_progress 2>&1 | grep -v "^Module" | tail -12
    # figure (d): success over training on $FIG_ITEMS, from the checkpoints of all runs (resumed runs included)
    if [ -n "${FIG_ITEMS:-}" ]; then
      mkdir -p /tmp/all_checkpoints && cp "$GENTE_LOG_ROOT/$task"/20*/model_*.pt /tmp/all_checkpoints/
      python3 -m legged_gente.evaluation.figures training --task "$task" --run /tmp/all_checkpoints --items $FIG_ITEMS \
        --device cuda --out "$OUT/${task}_success_over_training.png" 2>&1 | grep -v "^Module" | tail -3
    fi ;;
  *) echo "unknown phase $phase: use train, report or eval" >&2; exit 2 ;;
esac
