#!/usr/bin/env bash
# The GPU results of docs/performance.md, from the project root on a host with a GPU (the package and its
# dependencies installed); everything it keeps goes to $OUT_DIR (default gpu_evidence/):
#   phase train:   train $TASK at $NUM_ENVS envs for $TRAIN_SECONDS of training (RESUME=1 continues the latest run;
#                  $TRAIN_ARGS are more train.py flags, e.g. "--set terrain.solved_top_level=stay", or
#                  "--resume --load_run <path of a run folder brought from elsewhere>"); the
#                  latest checkpoint and the run's scalars CSV go to $OUT_DIR after every chunk
#   phase report:  benchmark (+ sync check, CSV), play (tracking plot + exports), scalars CSV -> $OUT_DIR
#   phase bench:   benchmark (+ sync check, CSV) at $BENCH_ENVS (default 8192) and the force kernels' profile
#                  (tools/profile_force_kernels.py) -> $OUT_DIR; needs no run
#   phase eval:    gente-evaluate the latest $TASK run on gente100 -> $OUT_DIR/eval; with FIG_ITEMS="id id id"
#                  also figure (d), success over training on those items -> $OUT_DIR
set -uo pipefail
phase=${1:?usage: gpu_evidence.sh train|report|bench|eval}
export GENTE_LOG_ROOT=${GENTE_LOG_ROOT:-/tmp/gente_logs}
OUT_DIR=${OUT_DIR:-gpu_evidence}
mkdir -p "$OUT_DIR"
task=${TASK:-gente_biped_flat}
latest_run() { ls -d "$GENTE_LOG_ROOT/$task"/20* | tail -1; }
case "$phase" in
  train)
    read -ra extra <<< "${TRAIN_ARGS:-}"; [ "${RESUME:-0}" = 1 ] && extra+=(--resume)
    # train.py stops itself after $TRAIN_SECONDS of training (--max_minutes, counted once the env is built) and
    # saves; the outer timeout only guards against a hang (env build and kernel compilation come on top)
    seconds=${TRAIN_SECONDS:-480}
    timeout -k 30 -s INT $((seconds + 300)) python3 legged_gente/scripts/train.py --task="$task" --headless \
      --num_envs "${NUM_ENVS:-4096}" --max_iterations "${MAX_ITERS:-100000}" \
      --max_minutes "$(python3 -c "print($seconds / 60)")" "${extra[@]}" 2>&1 \
      | grep -E "Learning iteration|Mean episode length|terrain_level|Steps per second|Interrupted|Time limit|Error|Traceback" | tail -8
    # keep the latest checkpoint and the run's scalars after every chunk (the log root may be temporary)
    run=$(latest_run); ls -t "$run"/model_*.pt | head -1 | xargs -I{} cp {} "$OUT_DIR/${task}_last.pt"
    cp "$run/config.json" "$OUT_DIR/${task}_config.json"  # tools/ship_policy.py reads it beside the checkpoint
    python3 -m legged_gente.utils.tb_export "$run" "$OUT_DIR/${task}_scalars_$(basename "$run").csv" ;;
  report)
    python3 -m legged_gente.scripts.benchmark --task "$task" --num_envs ${BENCH_ENVS:-1024 4096 8192} --check_sync \
      --csv "$OUT_DIR/${task}_benchmark.csv" 2>&1 | tail -12
    python3 legged_gente/scripts/play.py --task="$task" --headless --steps 500 2>&1 | tail -3
    python3 -m legged_gente.utils.tb_export "$(latest_run)" "$OUT_DIR/${task}_scalars.csv"
    cp "$(ls -td "$GENTE_LOG_ROOT/$task"/20*/exported | head -1)/velocity_tracking.png" "$OUT_DIR/${task}_velocity_tracking.png"
    ls -t "$(latest_run)"/model_*.pt | head -1 | xargs -I{} cp {} "$OUT_DIR/${task}_last.pt" ;;
  bench)
    envs=${BENCH_ENVS:-8192}
    python3 -m legged_gente.scripts.benchmark --task "$task" --num_envs $envs --check_sync \
      --csv "$OUT_DIR/${task}_benchmark.csv" 2>&1 | grep -v "^Module" | tee "$OUT_DIR/${task}_benchmark.log" | tail -12
    python3 tools/profile_force_kernels.py --task "$task" --num_envs "${envs%% *}" 2>&1 | grep -v "^Module" \
      > "$OUT_DIR/${task}_force_kernels_profile.log"; tail -3 "$OUT_DIR/${task}_force_kernels_profile.log" ;;
  eval)
    python3 -m legged_gente.scripts.evaluate --task "$task" --checkpoint "$(latest_run)" --benchmark gente100 \
      --robots_per_terrain "${ROBOTS:-16}" --out "$OUT_DIR/eval" --device cuda --no_progress 2>&1 | grep -v "^Module" | tail -12
    # figure (d): success over training on $FIG_ITEMS, from the run's folder and those of its --resume chunks
    if [ -n "${FIG_ITEMS:-}" ]; then
      python3 -m legged_gente.evaluation.figures training --task "$task" --run "$GENTE_LOG_ROOT/$task"/20* \
        --items $FIG_ITEMS --device cuda --out "$OUT_DIR/${task}_success_over_training.png" 2>&1 | grep -v "^Module" | tail -3
    fi ;;
  *) echo "unknown phase $phase: use train, report, bench or eval" >&2; exit 2 ;;
esac
