#!/bin/bash
# The shipped biped fine-tuned with mosaic columns in its curriculum, in chunks, and evaluated (GPU machine).
#   bash run_ft.sh train <minutes>          start from the shipped policy (--pretrained)
#   bash run_ft.sh resume <minutes> <dir>   continue the run carried in <dir>
#   bash run_ft.sh eval <dir> <benchmark>...  evaluate <dir>'s last checkpoint
OUT_DIR=${OUT_DIR:-out}
mkdir -p "$OUT_DIR"
export PYTHONUNBUFFERED=1
MOSAIC="natural_ground|random_uniform|pyramid_slope|pyramid_slope:direction=down|pyramid_stairs|pyramid_stairs:direction=down|discrete_obstacles|rocks|waves"
TYPES="['flat', 'random_uniform', 'natural_ground', 'pyramid_slope', 'pyramid_slope:direction=down', 'pyramid_stairs', 'pyramid_stairs:direction=down', 'discrete_obstacles', 'rocks', 'waves', 'river+water', 'basin+water:flow=current,speed=0.5', 'hills+soil:preset=dry_sand', 'soil:preset=mud', 'low_friction', '$MOSAIC']"
PROPS="[0.125, 0.0833, 0.0417, 0.0625, 0.0625, 0.0417, 0.0417, 0.0417, 0.0417, 0.0417, 0.0625, 0.0417, 0.0625, 0.0417, 0.0417, 0.1667]"
SETS=(--set runner.critic_warmup_iterations=500 --set terrain.max_init_terrain_level=8 --set "terrain.terrain_types=$TYPES" --set "terrain.terrain_proportions=$PROPS" --set terrain.num_cols=24
      --set terrain.solved_top_level=stay --set terrain.max_difficulty=1.65 --set terrain.num_rows=16
      --set rewards.scales.tracking_lin_vel=5 --set rewards.scales.tracking_ang_vel=4)
nvidia-smi --query-gpu=name --format=csv,noheader 2>/dev/null
summary() {  # the last iterations' headline numbers; the whole log gzipped
  grep -E "Learning iteration|Mean reward|terrain_level|diverged_resets|Time limit|Error|error" "$OUT_DIR/train.log" | tail -12
  gzip -f "$OUT_DIR/train.log"
}
pack() {  # the run folder's last checkpoint, config and event files to $OUT_DIR/run.tar.gz
  local run=$1 last
  last=$(ls -v "$run"/model_*.pt | tail -1)
  tar czf "$OUT_DIR/run.tar.gz" -C "$(dirname "$run")" "$(basename "$run")/$(basename "$last")" \
      $(cd "$(dirname "$run")" && ls -d "$(basename "$run")"/*.json "$(basename "$run")"/events* 2>/dev/null)
  echo "packed $last"
}
case $1 in
  train)
    python -m legged_gente.scripts.train --task gente_biped --headless --num_envs ${NUM_ENVS:-4096} ${EXTRA:-} --max_iterations 100000 \
      --pretrained --max_minutes "$2" --log_root /tmp/ft_logs "${SETS[@]}" > "$OUT_DIR/train.log" 2>&1
    echo "rc $?"; summary
    pack "$(ls -d /tmp/ft_logs/gente_biped/*/ | tail -1)" ;;
  resume)
    python -m legged_gente.scripts.train --task gente_biped --headless --num_envs ${NUM_ENVS:-4096} ${EXTRA:-} --max_iterations 100000 \
      --resume --load_run "$PWD/$3" --max_minutes "$2" --log_root /tmp/ft_logs \
      "${SETS[@]}" > "$OUT_DIR/train.log" 2>&1
    echo "rc $?"; summary
    pack "$(ls -d /tmp/ft_logs/gente_biped/*/ | tail -1)" ;;
  eval)
    run=$2; shift 2
    ckpt=$(ls -v "$run"/model_*.pt | tail -1)
    for b in "$@"; do
      python -m legged_gente.scripts.evaluate --task gente_biped --checkpoint "$ckpt" --benchmark "$b" \
        --robots_per_terrain 64 --seed 0 --out "/tmp/ev_$b" --no_progress > "$OUT_DIR/ev_$b.log" 2>&1
      echo "rc $? $b"; tail -12 "$OUT_DIR/ev_$b.log"; cp "/tmp/ev_$b/report.csv" "$OUT_DIR/$b.csv"
    done ;;
esac
